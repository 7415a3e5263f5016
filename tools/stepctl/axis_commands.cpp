#include "tools/stepctl/axis_commands.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <thread>

#include "node/profiles/horner/objects.hpp"
#include "od/sdo_abort.hpp"

namespace stepnode::tools {
namespace {

using namespace horner::obj;

struct AxisAccess {
  MasterBus& bus;
  uint8_t node;
  unsigned axis;

  od::Bytes read(uint16_t offset, uint8_t sub = 0) {
    od::SdoResult r = bus.upload(node, index(axis, offset), sub);
    if (!r.ok()) fail(index(axis, offset), r);
    return r.data;
  }
  void write(uint16_t offset, od::Bytes data, uint8_t sub = 0) {
    od::SdoResult r = bus.download(node, index(axis, offset), sub, std::move(data));
    if (!r.ok()) fail(index(axis, offset), r);
  }
  [[noreturn]] void fail(uint16_t object, const od::SdoResult& r) const {
    char buf[160];
    std::snprintf(buf, sizeof buf, "node %u axis %u: 0x%04X: 0x%08X %s", node, axis + 1, object,
                  static_cast<uint32_t>(r.abort), std::string(od::abort_text(r.abort)).c_str());
    throw std::runtime_error(buf);
  }
  // Commands act on the OFF->ON edge: the bit goes on, then off again.
  void pulse(uint16_t bit) {
    write(kCommandBits, od::encode<uint16_t>(0));
    write(kCommandBits, od::encode<uint16_t>(bit));
    write(kCommandBits, od::encode<uint16_t>(0));
  }
  uint16_t status() { return od::decode<uint16_t>(read(kStatusBits)); }
};

const char* kPhase[] = {"stopped", "accelerating", "running", "decelerating", "base velocity"};

// Live line while the axis moves: a bar toward the target (moves), position, velocity, phase.
void progress(AxisAccess& a, bool quiet,
              std::optional<std::pair<int64_t, int64_t>> from_to = std::nullopt) {
  for (;;) {
    uint16_t s = a.status();
    int32_t pos = od::decode<int32_t>(a.read(kMotorPosition));
    int32_t vel = od::decode<int32_t>(a.read(kVelocity));
    uint8_t phase = a.read(kMotionPhase).at(0);
    if (!quiet) {
      std::string bar;
      if (from_to && from_to->first != from_to->second) {
        double done = static_cast<double>(pos - from_to->first) /
                      static_cast<double>(from_to->second - from_to->first);
        int filled = static_cast<int>(std::lround(std::clamp(done, 0.0, 1.0) * 30));
        bar = "[" + std::string(filled, '#') + std::string(30 - filled, '-') + "] " +
              std::to_string(static_cast<int>(std::clamp(done, 0.0, 1.0) * 100)) + "%";
      }
      std::printf("\r  %s position %10d   velocity %8d steps/s   %-14s", bar.c_str(), pos, vel,
                  phase < 5 ? kPhase[phase] : "?");
      std::fflush(stdout);
    }
    if (!(s & 0x8000)) break;  // %I16 moving
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (!quiet) std::printf("\n");
}

int report(AxisAccess& a) {
  uint16_t s = a.status();
  int32_t pos = od::decode<int32_t>(a.read(kMotorPosition));
  int32_t enc = od::decode<int32_t>(a.read(kEncoderPosition));
  std::printf("node %u axis %u: position %d, encoder %d, status 0x%04X: %s\n", a.node, a.axis + 1,
              pos, enc, s, status_words(s).c_str());
  return (s & 0x00FF) ? 1 : 0;  // an error bit is on
}

}  // namespace

std::string status_words(uint16_t s) {
  static const char* names[16] = {
      "EMERGENCY STOP", "LOWER LIMIT",  "UPPER LIMIT",     "ILLEGAL MOVE",
      "MOTOR STALLED",  "error 6",      "error 7",         "POWER-UP/WATCHDOG",
      "position valid", "resumable",    "axis 2 selected", "axis 3 selected",
      "at home",        "accelerating", "decelerating",    "moving"};
  std::string out;
  for (int i = 0; i < 16; ++i) {
    if (!(s & (1u << i))) continue;
    if (!out.empty()) out += ", ";
    out += names[i];
  }
  return out.empty() ? "no bits set (position not valid)" : out;
}

int run_axis_command(MasterBus& bus, int node, int axis, const std::vector<std::string>& w,
                     double jog_seconds, bool quiet) {
  if (axis < 1 || axis > 8) throw std::invalid_argument("--axis must be 1..8");
  AxisAccess a{bus, static_cast<uint8_t>(node), static_cast<unsigned>(axis - 1)};
  const std::string& verb = w.at(0);
  auto direction = [&](const char* what) {
    if (w.size() != 2 || (w[1] != "up" && w[1] != "down"))
      throw std::invalid_argument(std::string(what) + " needs 'up' or 'down'");
    return w[1] == "up";
  };
  if (verb == "status") return report(a);
  if (verb == "clear") {
    a.pulse(1u << 13);  // %Q14
    return report(a);
  }
  if (verb == "stop") {
    a.pulse(1u << 14);  // %Q15 decelerate and stop
    progress(a, quiet);
    return report(a);
  }
  if (verb == "estop") {
    a.pulse(1u << 15);  // %Q16 immediate stop
    return report(a);
  }
  if (verb == "home") {
    a.pulse(direction("home") ? 1u << 3 : 1u << 4);  // %Q4 / %Q5
    progress(a, quiet);
    return report(a);
  }
  if (verb == "jog") {
    // Jog is level-sensitive: on for the time asked, then off (the axis ramps down).
    uint16_t bit = direction("jog") ? 1u << 5 : 1u << 6;
    a.write(kCommandBits, od::encode<uint16_t>(0));
    a.write(kCommandBits, od::encode<uint16_t>(bit));
    auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(jog_seconds);
    while (std::chrono::steady_clock::now() < end) {
      int32_t pos = od::decode<int32_t>(a.read(kMotorPosition));
      if (!quiet) std::printf("\r  jogging: position %10d", pos), std::fflush(stdout);
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    a.write(kCommandBits, od::encode<uint16_t>(0));
    if (!quiet) std::printf("\n");
    progress(a, quiet);
    return report(a);
  }
  if (verb == "move") {
    if (w.size() != 3 || (w[1] != "abs" && w[1] != "rel"))
      throw std::invalid_argument("move needs 'abs' or 'rel' and a position, e.g. move abs 1000");
    long long target = 0;
    try {
      size_t used = 0;
      // Decimal, or hex after 0x ("010" is ten, not octal eight).
      const size_t sign = w[2][0] == '-' || w[2][0] == '+' ? 1 : 0;
      const bool hex = w[2].compare(sign, 2, "0x") == 0 || w[2].compare(sign, 2, "0X") == 0;
      target = std::stoll(w[2], &used, hex ? 16 : 10);
      if (used != w[2].size()) throw std::invalid_argument(w[2]);
    } catch (const std::exception&) {
      throw std::invalid_argument("move: '" + w[2] + "' is not a whole number of steps");
    }
    if (target < -8'388'608 || target > 8'388'607)
      throw std::invalid_argument("move: " + w[2] +
                                  " is outside -8388608..8388607 (the module's range)");
    int64_t start = od::decode<int32_t>(a.read(kMotorPosition));
    a.write(kDestination, od::encode<int32_t>(static_cast<int32_t>(target)));
    a.pulse(w[1] == "abs" ? 1u << 8 : 1u << 7);  // %Q9 / %Q8
    progress(a, quiet, std::make_pair(start, w[1] == "abs" ? target : start + target));
    return report(a);
  }
  throw std::invalid_argument("unknown axis command '" + verb +
                              "' (clear, home, move, jog, stop, estop, status)");
}

}  // namespace stepnode::tools
