#include "tools/stepctl/drive_command.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <stdexcept>
#include <thread>

#include "node/profiles/cia402/objects.hpp"
#include "od/sdo_abort.hpp"
#include "od/value_codec.hpp"
#include "tools/stepctl/drive_words.hpp"

namespace stepnode::tools {
namespace {

using namespace cia402::obj;
using drive::State;
using Clock = std::chrono::steady_clock;

// How long a switching transition may take (python-canopen's 0.4 s per state change).
constexpr double kStepSeconds = 0.4;

std::string hex4(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%04X", v);
  return buf;
}
std::string hex8(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08X", v);
  return buf;
}

std::string join(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : ", ") + w;
  return out.empty() ? "none" : out;
}

// One axis' CiA 402 objects over SDO.
class Axis {
 public:
  Axis(MasterBus& bus, const ObjectCatalog& catalog, const DriveArgs& args)
      : bus_(bus),
        catalog_(catalog),
        node_(static_cast<uint8_t>(args.node)),
        axis_(static_cast<unsigned>(args.axis)),
        quiet_(args.quiet) {}

  std::string who() const {
    return "node " + std::to_string(node_) + " axis " + std::to_string(axis_);
  }
  bool quiet() const { return quiet_; }
  uint16_t at(uint16_t base) const { return index(axis_ - 1, base); }

  od::SdoResult try_read(uint16_t base, uint8_t sub = 0) {
    return bus_.upload(node_, at(base), sub);
  }
  od::Bytes read(uint16_t base, uint8_t sub = 0) {
    od::SdoResult r = bus_.upload(node_, at(base), sub);
    if (!r.ok()) fail(base, sub, r);
    return r.data;
  }
  od::SdoResult try_write(uint16_t base, uint8_t sub, od::Bytes data) {
    return bus_.download(node_, at(base), sub, std::move(data));
  }
  void write(uint16_t base, uint8_t sub, od::Bytes data) {
    od::SdoResult r = bus_.download(node_, at(base), sub, std::move(data));
    if (!r.ok()) fail(base, sub, r);
  }
  [[noreturn]] void fail(uint16_t base, uint8_t sub, const od::SdoResult& r) {
    const uint16_t i = at(base);
    char addr[16];
    std::snprintf(addr, sizeof addr, "0x%04X:%02X", i, sub);
    std::string what = who() + ": " + addr;
    if (auto info = catalog_.find(i, sub)) what += " " + info->name;
    what += std::string(": ") + (r.aborted_by_server ? "abort " : "failed ") +
            hex8(static_cast<uint32_t>(r.abort)) + " " + std::string(od::abort_text(r.abort));
    if (r.abort == od::SdoAbort::NoObject)
      what += " (no CiA 402 axis " + std::to_string(axis_) +
              " on this node? profiles = [\"cia402\"] in its config)";
    throw std::runtime_error(what);
  }

  uint16_t statusword() { return od::decode<uint16_t>(read(kStatusword)); }
  uint16_t controlword() { return od::decode<uint16_t>(read(kControlword)); }
  void controlword(uint16_t cw) {
    write(kControlword, 0, od::encode<uint16_t>(cw));
    last_cw_ = cw;
  }
  uint16_t last_controlword() const { return last_cw_; }
  void set_last_controlword(uint16_t cw) { last_cw_ = cw; }
  int8_t mode_display() { return od::decode<int8_t>(read(kModesOfOperationDisplay)); }
  uint16_t error_code() { return od::decode<uint16_t>(read(kErrorCode)); }
  int32_t position() { return od::decode<int32_t>(read(kPositionActual)); }
  int32_t velocity() { return od::decode<int32_t>(read(kVelocityActual)); }
  void write_u32(uint16_t base, uint8_t sub, int64_t v) {
    write(base, sub, od::encode<uint32_t>(static_cast<uint32_t>(v)));
  }
  void write_i32(uint16_t base, int64_t v) {
    write(base, 0, od::encode<int32_t>(static_cast<int32_t>(v)));
  }

  // "Fault, 603Fh 0x8612 reference limit" (the error code only in the fault states).
  std::string state_text(uint16_t sw) {
    const State s = drive::decode_state(sw);
    std::string text = drive::name(s);
    if (s == State::Unknown) text += " (6041h " + hex4(sw) + ")";
    if (drive::fault(s)) {
      const uint16_t code = error_code();
      text += ", 603Fh " + hex4(code) + " " + drive::error_code_text(code);
    }
    return text;
  }

 private:
  MasterBus& bus_;
  const ObjectCatalog& catalog_;
  uint8_t node_;
  unsigned axis_;
  bool quiet_;
  uint16_t last_cw_ = 0;
};

void sleep_ms(int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); }

Clock::time_point after(double seconds) {
  return Clock::now() +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

std::string seconds_text(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g s", s);
  return buf;
}

// ---- device control ---------------------------------------------------------------------

using Planner = std::function<std::optional<drive::Step>(State, uint16_t)>;

// Carries out the planner's steps from the state the drive is in until it has none; each
// step's states checked in 6041h within kStepSeconds (a ramp: within wait_s). Returns the
// last statusword.
uint16_t run_steps(Axis& a, const Planner& plan, int wait_s) {
  a.set_last_controlword(a.controlword());
  uint16_t sw = a.statusword();
  for (int taken = 0;; ++taken) {
    const State state = drive::decode_state(sw);
    if (state == State::Unknown)
      throw std::runtime_error(a.who() + ": statusword 6041h " + hex4(sw) +
                               " shows no CiA 402 state");
    const std::optional<drive::Step> step = plan(state, a.last_controlword());
    if (!step) return sw;
    if (taken == 8)
      throw std::runtime_error(a.who() + ": still in " + a.state_text(sw) + " after 8 steps");
    std::string words;
    for (uint16_t cw : step->controlwords) words += (words.empty() ? "" : ", ") + hex4(cw);
    std::string doing = step->controlwords.empty() ? "waiting " + step->command
                                                   : step->command + " (6040h = " + words + ")";
    std::string targets;
    for (State s : step->leads_to)
      targets += std::string(targets.empty() ? "" : " or ") + drive::name(s);
    if (!a.quiet())
      std::printf("  %s: %s -> %s\n", drive::name(state), doing.c_str(), targets.c_str());
    for (uint16_t cw : step->controlwords) a.controlword(cw);
    const double limit = step->ramp ? static_cast<double>(wait_s) : kStepSeconds;
    const auto deadline = after(limit);
    for (;;) {
      sw = a.statusword();
      const State now = drive::decode_state(sw);
      if (std::find(step->leads_to.begin(), step->leads_to.end(), now) != step->leads_to.end())
        break;
      if (drive::fault(now) && !drive::fault(state))  // a fault on the way: no use waiting
        throw std::runtime_error(a.who() + ": went to " + a.state_text(sw) + " on " + doing);
      if (Clock::now() > deadline) {
        std::string what = a.who();
        what.append(": stuck in ").append(a.state_text(sw)).append(": ").append(doing);
        what.append(" did not lead to ")
            .append(targets)
            .append(" within ")
            .append(seconds_text(limit));
        throw std::runtime_error(what);
      }
      sleep_ms(10);
    }
  }
}

int cmd_status(Axis& a) {
  const uint16_t sw = a.statusword();
  const int8_t mode = a.mode_display();
  const uint16_t code = a.error_code();
  const int32_t pos = a.position(), vel = a.velocity();
  const State state = drive::decode_state(sw);
  std::printf("%s: %s, mode %s (6061h = %d)\n", a.who().c_str(), drive::name(state),
              drive::mode_name(mode).c_str(), mode);
  std::printf("  statusword 6041h %s: %s\n", hex4(sw).c_str(),
              join(drive::status_bits(sw, mode)).c_str());
  if (mode == cia402::mode::kHoming)
    std::printf("  homing: %s\n", drive::homing_status(sw).c_str());
  std::printf("  error code 603Fh %s: %s\n", hex4(code).c_str(),
              drive::error_code_text(code).c_str());
  std::printf("  position actual 6064h %d, velocity actual 606Ch %d\n", pos, vel);
  return drive::fault(state) || state == State::Unknown ? 1 : 0;
}

int cmd_device_control(Axis& a, const DriveArgs& args) {
  const std::string& v = args.verb;
  const State before = drive::decode_state(a.statusword());
  Planner plan = v == "enable"       ? Planner(drive::enable_step)
                 : v == "disable"    ? Planner(drive::disable_step)
                 : v == "quick-stop" ? Planner(drive::quick_stop_step)
                                     : Planner(drive::fault_reset_step);
  const uint16_t sw = run_steps(a, plan, args.wait_s);
  const State state = drive::decode_state(sw);
  std::string note;
  if (v == "quick-stop" && state == before) {
    note = drive::fault(state)               ? " (the fault reaction has stopped the drive)"
           : state == State::QuickStopActive ? " (already)"
                                             : " (nothing to stop)";
  } else if (v == "fault-reset" && state == before) {
    note = " (no fault to reset)";
  } else if (v == "disable" && state == before && state != State::ReadyToSwitchOn) {
    note = " (already disabled)";
  } else if (v == "enable" && state == State::OperationEnabled &&
             a.mode_display() == cia402::mode::kProfileVelocity) {
    // Profile velocity follows 60FFh whenever operation is enabled: say so when it moves.
    const int32_t target = od::decode<int32_t>(a.read(kTargetVelocity));
    if (target != 0) note = " (profile velocity: following 60FFh = " + std::to_string(target) + ")";
  }
  std::printf("%s: %s%s\n", a.who().c_str(), a.state_text(sw).c_str(), note.c_str());
  return 0;
}

// ---- the modes ----------------------------------------------------------------------------

// The drive must be in Operation enabled for a mode to move it.
void require_enabled(Axis& a, const DriveArgs& args) {
  const uint16_t sw = a.statusword();
  if (drive::decode_state(sw) == State::OperationEnabled) return;
  throw std::runtime_error(a.who() + " is in " + a.state_text(sw) +
                           ", not Operation enabled: run `stepctl drive " + "enable --node " +
                           std::to_string(args.node) + " --axis " + std::to_string(args.axis) +
                           "` first");
}

// 6060h = mode, then 6061h shows it (within kStepSeconds). Returns false when the drive
// refused the value with a range/value abort (the mode is not supported). When 6061h does
// not follow, 6060h is put back to the mode shown, so no mode change stays pending.
bool set_mode(Axis& a, int8_t mode) {
  const int8_t shown_before = a.mode_display();
  if (shown_before == mode && od::decode<int8_t>(a.read(kModesOfOperation)) == mode) return true;
  const od::SdoResult r = a.try_write(kModesOfOperation, 0, od::encode<int8_t>(mode));
  if (r.abort == od::SdoAbort::InvalidValue || r.abort == od::SdoAbort::ValueTooHigh ||
      r.abort == od::SdoAbort::ValueTooLow)
    return false;
  if (!r.ok()) a.fail(kModesOfOperation, 0, r);
  const auto deadline = after(kStepSeconds);
  int8_t shown = a.mode_display();
  while (shown != mode) {
    if (Clock::now() > deadline) {
      a.try_write(kModesOfOperation, 0, od::encode<int8_t>(shown));
      throw std::runtime_error(a.who() + ": 6061h still shows " + drive::mode_name(shown) +
                               " after 6060h = " + std::to_string(mode) + " (" +
                               drive::mode_name(mode) +
                               "): the drive changes its mode when its motion has ended");
    }
    sleep_ms(10);
    shown = a.mode_display();
  }
  return true;
}

// Until bit 12 of 6041h is `on` (within kStepSeconds); false when it was not.
bool wait_bit12(Axis& a, bool on, uint16_t& sw, double seconds = kStepSeconds) {
  const auto deadline = after(seconds);
  for (;;) {
    sw = a.statusword();
    if (((sw & drive::sw::kBit12) != 0) == on) return true;
    if (drive::decode_state(sw) != State::OperationEnabled) return false;
    if (Clock::now() > deadline) return false;
    sleep_ms(5);
  }
}

// Live position and velocity until `done(statusword)`; the drive leaving Operation enabled
// or --wait running out is a failure. `bar`: from, to positions for a progress bar.
uint16_t follow(Axis& a, const DriveArgs& args, int8_t mode,
                const std::function<bool(uint16_t)>& done, const char* what,
                std::optional<std::pair<int64_t, int64_t>> bar = std::nullopt) {
  const auto deadline = after(args.wait_s);
  for (;;) {
    const uint16_t sw = a.statusword();
    const int32_t pos = a.position(), vel = a.velocity();
    const int8_t shown = a.mode_display();
    if (!a.quiet()) {
      std::string b;
      if (bar && bar->first != bar->second) {
        const double part = std::clamp(
            static_cast<double>(pos - bar->first) / static_cast<double>(bar->second - bar->first),
            0.0, 1.0);
        const int filled = static_cast<int>(std::lround(part * 30));
        b = "[" + std::string(filled, '#') + std::string(30 - filled, '-') + "] " +
            std::to_string(static_cast<int>(part * 100)) + "% ";
      }
      std::printf("\r  %sposition %10d   velocity %8d   ", b.c_str(), pos, vel);
      std::fflush(stdout);
    }
    const State state = drive::decode_state(sw);
    if (state != State::OperationEnabled) {
      if (!a.quiet()) std::printf("\n");
      throw std::runtime_error(a.who() + ": left Operation enabled " + what + ": " +
                               a.state_text(sw) + ", position " + std::to_string(pos));
    }
    if (shown != mode) {  // another master changed the mode: the bits mean other things now
      if (!a.quiet()) std::printf("\n");
      throw std::runtime_error(a.who() + ": 6061h changed to " + drive::mode_name(shown) + " " +
                               what + ", position " + std::to_string(pos));
    }
    if (done(sw)) {
      if (!a.quiet()) std::printf("\n");
      return sw;
    }
    if (Clock::now() > deadline) {
      if (!a.quiet()) std::printf("\n");
      throw std::runtime_error(a.who() + ": not done " + what + " after " +
                               std::to_string(args.wait_s) + " s (position " + std::to_string(pos) +
                               ", velocity " + std::to_string(vel) +
                               "); `stepctl drive quick-stop` stops it");
    }
    sleep_ms(50);
  }
}

// Makes the rising edge of bit 4 possible: bit 4 (and halt) at 0 in Operation enabled.
void clear_bit4(Axis& a) {
  const uint16_t cw = a.controlword();
  if (cw & (drive::cw::kNewSetPoint | drive::cw::kHalt)) a.controlword(drive::cw::kEnableOperation);
}

int cmd_pp(Axis& a, const DriveArgs& args) {
  require_enabled(a, args);
  if (!set_mode(a, cia402::mode::kProfilePosition))
    throw std::runtime_error(a.who() + ": the drive refused 6060h = 1 (profile position)");
  if (args.velocity) a.write_u32(kProfileVelocity, 0, *args.velocity);
  if (args.acceleration) a.write_u32(kProfileAcceleration, 0, *args.acceleration);
  if (args.deceleration) a.write_u32(kProfileDeceleration, 0, *args.deceleration);
  a.write_i32(kTargetPosition, args.target);
  clear_bit4(a);
  // The drive takes a new set-point only while 6041h bit 12 is 0: it stays 1 while its
  // buffer is full, and an edge of bit 4 then is ignored (an earlier set-point waits for the
  // move before it). Raised then, the old 1 looked like the acknowledgement of a set-point
  // the drive never took (found in review).
  uint16_t sw = 0;
  if (!wait_bit12(a, false, sw, args.wait_s))
    throw std::runtime_error(a.who() +
                             ": the drive takes no new set-point (6041h bit 12 stayed 1 for " +
                             std::to_string(args.wait_s) + " s: its set-point buffer is full; " +
                             a.state_text(sw) + ", 6041h " + hex4(sw) + ")");
  const int64_t start = a.position();
  // The set-point handshake: bit 4 up, bit 12 answers; bit 4 down, bit 12 follows (it stays
  // up while the drive's buffer is full: the set-point waits for the move before it).
  const uint16_t cw = drive::set_point_controlword(args.immediate, args.relative);
  a.controlword(cw);
  if (!wait_bit12(a, true, sw))
    throw std::runtime_error(
        a.who() + ": the set-point was not acknowledged (6041h bit 12 stayed 0 for " +
        seconds_text(kStepSeconds) + "; " + a.state_text(sw) + ", 6041h " + hex4(sw) + ")");
  a.controlword(static_cast<uint16_t>(cw & ~drive::cw::kNewSetPoint));
  const bool buffered = !wait_bit12(a, false, sw);
  if (buffered && drive::decode_state(sw) == State::OperationEnabled && !a.quiet())
    std::printf("  set-point buffered: the drive carries it out after the move it is on\n");
  if (args.no_wait) {
    std::printf("%s: set-point %lld%s acknowledged\n", a.who().c_str(),
                static_cast<long long>(args.target), args.relative ? " (relative)" : "");
    return 0;
  }
  const int64_t to = args.relative ? start + args.target : args.target;
  sw = follow(
      a, args, cia402::mode::kProfilePosition,
      [](uint16_t s) { return (s & drive::sw::kTargetReached) != 0; }, "on the way to the target",
      std::make_pair(start, to));
  const std::string limit = (sw & drive::sw::kInternalLimitActive)
                                ? " (internal limit active: the target was outside 607Dh)"
                                : "";
  std::printf("%s: target reached, position %d%s\n", a.who().c_str(), a.position(), limit.c_str());
  return 0;
}

int cmd_pv(Axis& a, const DriveArgs& args) {
  require_enabled(a, args);
  // Beyond 607Fh the drive limits the velocity, and bit 10 would not come.
  if (const od::SdoResult m = a.try_read(kMaxProfileVelocity); m.ok()) {
    const int64_t max = od::decode<uint32_t>(m.data);
    if (args.target > max || args.target < -max)
      throw std::invalid_argument(a.who() + ": velocity " + std::to_string(args.target) +
                                  " is beyond 607Fh max profile velocity " + std::to_string(max));
  }
  if (args.acceleration) a.write_u32(kProfileAcceleration, 0, *args.acceleration);
  if (args.deceleration) a.write_u32(kProfileDeceleration, 0, *args.deceleration);
  // The target first: the drive follows 60FFh from the moment 6061h shows pv.
  a.write_i32(kTargetVelocity, args.target);
  if (!set_mode(a, cia402::mode::kProfileVelocity))
    throw std::runtime_error(a.who() + ": the drive refused 6060h = 3 (profile velocity)");
  if (a.controlword() & drive::cw::kHalt) a.controlword(drive::cw::kEnableOperation);
  if (args.no_wait) {
    std::printf("%s: target velocity %lld set\n", a.who().c_str(),
                static_cast<long long>(args.target));
    return 0;
  }
  const bool zero = args.target == 0;
  follow(
      a, args, cia402::mode::kProfileVelocity,
      [zero](uint16_t s) {
        return (s & drive::sw::kTargetReached) && (!zero || (s & drive::sw::kBit12));
      },
      zero ? "while stopping" : "while reaching the velocity");
  std::printf("%s: %s, velocity %d\n", a.who().c_str(), zero ? "speed zero" : "velocity reached",
              a.velocity());
  return 0;
}

[[noreturn]] void no_homing(const Axis& a, const std::string& why) {
  throw std::invalid_argument("homing (6060h = 6) is not supported by this node yet (" + a.who() +
                              ": " + why + ")");
}

int cmd_home(Axis& a, const DriveArgs& args) {
  require_enabled(a, args);
  // 6502h bit 5: homing mode. A drive without 6502h is asked through 6060h.
  const od::SdoResult modes = a.try_read(kSupportedDriveModes);
  if (modes.ok()) {
    const uint32_t supported = od::decode<uint32_t>(modes.data);
    if (!(supported & (1u << 5))) no_homing(a, "6502h " + hex8(supported) + " has no bit 5");
  } else if (modes.abort != od::SdoAbort::NoObject) {
    a.fail(kSupportedDriveModes, 0, modes);
  }
  if (args.method) a.write(kHomingMethod, 0, od::encode<int8_t>(static_cast<int8_t>(*args.method)));
  if (args.switch_speed)
    a.write_u32(kHomingSpeeds, cia402::homing_speed_sub::kSwitchSearch, *args.switch_speed);
  if (args.zero_speed)
    a.write_u32(kHomingSpeeds, cia402::homing_speed_sub::kZeroSearch, *args.zero_speed);
  if (args.acceleration) a.write_u32(kHomingAcceleration, 0, *args.acceleration);
  if (args.home_offset) a.write_i32(kHomeOffset, *args.home_offset);
  const int8_t method = od::decode<int8_t>(a.read(kHomingMethod));
  if (method == 0)
    throw std::invalid_argument(a.who() +
                                ": 6098h homing method is 0 (none assigned): give --method N");
  if (!set_mode(a, cia402::mode::kHoming)) no_homing(a, "6060h = 6 refused");
  clear_bit4(a);
  a.controlword(drive::cw::kEnableOperation | drive::cw::kNewSetPoint);  // homing operation start
  if (args.no_wait) {
    std::printf("%s: homing started (method %d)\n", a.who().c_str(), method);
    return 0;
  }
  // Bits 13/12/10: 0/0/1 is "interrupted or not started": the start did not take.
  const auto not_started_by = after(kStepSeconds);
  uint16_t sw = follow(
      a, args, cia402::mode::kHoming,
      [&](uint16_t s) {
        const bool error = s & drive::sw::kBit13, attained = s & drive::sw::kBit12,
                   reached = s & drive::sw::kTargetReached;
        if (!error && !attained && reached && Clock::now() > not_started_by) return true;
        return (attained && reached) || (error && reached);
      },
      "while homing");
  a.controlword(drive::cw::kEnableOperation);  // bit 4 back to 0: the procedure has ended
  const std::string status = drive::homing_status(sw);
  if (!(sw & drive::sw::kBit12))
    throw std::runtime_error(a.who() + ": " + status + " (method " + std::to_string(method) +
                             ", position " + std::to_string(a.position()) + ")");
  std::printf("%s: %s, position %d\n", a.who().c_str(), status.c_str(), a.position());
  return 0;
}

}  // namespace

int run_drive_command(MasterBus& bus, const ObjectCatalog& catalog, const DriveArgs& args) {
  if (args.axis < 1 || args.axis > static_cast<int>(cia402::kMaxAxes))
    throw std::invalid_argument("--axis must be 1..8");
  Axis a(bus, catalog, args);
  if (args.verb == "status") return cmd_status(a);
  if (args.verb == "pp") return cmd_pp(a, args);
  if (args.verb == "pv") return cmd_pv(a, args);
  if (args.verb == "home") return cmd_home(a, args);
  if (args.verb == "enable" || args.verb == "disable" || args.verb == "quick-stop" ||
      args.verb == "fault-reset")
    return cmd_device_control(a, args);
  throw std::invalid_argument("unknown drive command '" + args.verb + "'");
}

}  // namespace stepnode::tools
