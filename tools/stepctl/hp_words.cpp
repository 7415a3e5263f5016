#include "tools/stepctl/hp_words.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

#include "node/profiles/hp44714a/objects.hpp"

namespace stepnode::tools {
namespace {

using namespace hp44714a::obj;

std::string upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return s;
}

std::vector<std::string> split_words(const std::string& s) {
  std::vector<std::string> out;
  std::string w;
  for (char c : s) {
    if (std::isspace(static_cast<unsigned char>(c)) || c == ',') {
      if (!w.empty()) out.push_back(upper(w));
      w.clear();
    } else {
      w += c;
    }
  }
  if (!w.empty()) out.push_back(upper(w));
  return out;
}

double number(const std::string& command, const std::string& w) {
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(w, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != w.size() || !std::isfinite(v))
    throw std::invalid_argument(command + ": '" + w + "' is not a number");
  return v;
}

// HI/LH = 1, LO/HL = 0 (PULSE, HARDLIM, STANDBY senses).
uint8_t sense(const std::string& command, const std::string& w) {
  if (w == "HI" || w == "LH") return 1;
  if (w == "LO" || w == "HL") return 0;
  throw std::invalid_argument(command + ": sense '" + w + "' must be HI, LO, LH or HL");
}

struct Planner {
  unsigned ch;
  std::vector<HpAccess> out;

  uint16_t at(uint16_t offset) const { return index(ch, offset); }
  void write(uint16_t offset, uint8_t sub, od::Bytes data) {
    out.push_back({HpAccess::Write, at(offset), sub, std::move(data), {}, {}});
  }
  void u8(uint16_t offset, uint8_t sub, uint8_t v) { write(offset, sub, od::encode<uint8_t>(v)); }
  void real(uint16_t offset, uint8_t sub, double v) { write(offset, sub, od::encode<double>(v)); }
  void read(uint16_t offset, uint8_t sub, od::DataType type, std::string label) {
    out.push_back({HpAccess::Read, at(offset), sub, {}, type, std::move(label)});
  }
  void wait_running() {
    out.push_back({HpAccess::WaitWhileRunning, at(kDone), 0, {}, od::DataType::Integer8, "DONE?"});
  }

  using Words = std::vector<std::string>;  // the command, then its parameters

  // Checks the number of parameters (the words after the command).
  static void need(const Words& w, size_t lo, size_t hi) {
    if (w.size() - 1 < lo || w.size() - 1 > hi)
      throw std::invalid_argument(w[0] + ": takes " + std::to_string(lo) +
                                  (lo == hi ? "" : ".." + std::to_string(hi)) +
                                  " parameters, got " + std::to_string(w.size() - 1));
  }

  void profile(const Words& w) {
    need(w, 5, 5);
    if (w[1] != "FREQ" && w[1] != "WIDTH")
      throw std::invalid_argument("PROFILE: mode must be FREQ or WIDTH");
    u8(kProfile, hp44714a::profile_sub::kMode, w[1] == "WIDTH" ? 1 : 0);
    for (uint8_t k = 0; k < 4; ++k)
      real(kProfile, static_cast<uint8_t>(hp44714a::profile_sub::kMin + k), number(w[0], w[2 + k]));
    u8(kProfile, hp44714a::profile_sub::kApply, 1);
  }

  void pscale(const Words& w) {
    need(w, 1, 1);
    double s = number(w[0], w[1]);
    if (s == 0) throw std::invalid_argument("PSCALE: the scale factor cannot be 0");
    real(kPscale, 0, s);
  }

  // MOVE distance [ABS|REL] [NOWAIT], SUSTAIN velocity [NOWAIT].
  void move_or_sustain(const Words& w) {
    const std::string& c = w[0];
    need(w, 1, 3);
    double v = number(c, w[1]);
    bool nowait = false, absolute = false;
    for (size_t k = 2; k < w.size(); ++k) {
      if (w[k] == "NOWAIT") nowait = true;
      else if (c == "MOVE" && (w[k] == "ABS" || w[k] == "REL")) absolute = w[k] == "ABS";
      else throw std::invalid_argument(c + ": unknown option '" + w[k] + "'");
    }
    u8(kMove, hp44714a::move_sub::kNowait, nowait ? 1 : 0);
    if (c == "MOVE")
      real(kMove, absolute ? hp44714a::move_sub::kAbsolute : hp44714a::move_sub::kRelative, v);
    else real(kSustain, 0, v);
    if (!nowait) wait_running();  // without NOWAIT the command completes first (3-12)
  }

  void trig(const Words& w) {
    need(w, 0, 1);
    static const std::map<std::string, uint8_t> modes = {
        {"HOLD", 0}, {"AUTO", 1}, {"INT", 1}, {"SGL", 2}, {"SYS", 3}, {"CHAN0", 4}, {"CHAN", 4}};
    std::string m = w.size() > 1 ? w[1] : "SGL";  // "TRIG" alone is TRIG SGL
    if (!modes.contains(m))
      throw std::invalid_argument("TRIG: mode must be HOLD, AUTO, INT, SGL, SYS or CHAN0");
    u8(kTrig, 0, modes.at(m));
  }

  void delay(const Words& w) {
    need(w, 1, 1);
    double s = number(w[0], w[1]);
    if (s < 0 || s > 65.535) throw std::invalid_argument("DELAY: 0.000 to 65.535 seconds");
    write(kDelay, 0, od::encode<uint16_t>(static_cast<uint16_t>(std::llround(s * 1000))));
  }

  void standby(const Words& w) {
    need(w, 0, 2);
    // No mode: ON; no sense: as previously set (3-6).
    static const std::map<std::string, uint8_t> modes = {{"OFF", 0}, {"ON", 1}, {"AUTO", 2}};
    uint8_t mode = 1;
    size_t k = 1;
    if (w.size() > k && modes.contains(w[k])) mode = modes.at(w[k++]);
    if (w.size() > k) u8(kOutput, hp44714a::output_sub::kStandbySense, sense(w[0], w[k++]));
    if (w.size() > k) throw std::invalid_argument("STANDBY: unknown word '" + w[k] + "'");
    u8(kOutput, hp44714a::output_sub::kStandbyMode, mode);
  }

  void pulse(const Words& w) {
    need(w, 2, 3);
    if (w[1] != "SD" && w[1] != "SS") throw std::invalid_argument("PULSE: mode must be SD or SS");
    uint8_t p = sense(w[0], w[2]);
    uint8_t n = w.size() > 3 ? sense(w[0], w[3]) : p;  // NDIR defaults to PSTP's sense
    u8(kOutput, hp44714a::output_sub::kPstpSense, p);
    u8(kOutput, hp44714a::output_sub::kNdirSense, n);
    u8(kOutput, hp44714a::output_sub::kPulseMode, w[1] == "SS" ? 1 : 0);
  }

  void hardlim(const Words& w) {
    need(w, 1, 2);
    uint8_t p = sense(w[0], w[1]);
    u8(kLimits, hp44714a::limits_sub::kPlimSense, p);
    u8(kLimits, hp44714a::limits_sub::kNlimSense, w.size() > 2 ? sense(w[0], w[2]) : p);
  }

  void halt(const Words& w) {
    need(w, 1, 1);
    if (w[1] == "SGL") u8(kLimits, hp44714a::limits_sub::kHaltSgl, 1);
    else if (w[1] == "OFF") u8(kLimits, hp44714a::limits_sub::kHaltMode, 2);
    else u8(kLimits, hp44714a::limits_sub::kHaltMode, sense(w[0], w[1]));
  }

  void pos(const Words& w) {
    need(w, 1, 1);
    real(kPosition, 0, number(w[0], w[1]));
  }

  // POS?, DONE?, ERR? (ERROR?), QPOS?: a read, its answer printed.
  void query(const Words& w) {
    need(w, 0, 0);
    const std::string& c = w[0];
    if (c == "POS?") read(kPosition, 0, od::DataType::Real64, "POS?");
    else if (c == "DONE?") read(kDone, 0, od::DataType::Integer8, "DONE?");
    else if (c == "QPOS?")
      read(kQuadrature, hp44714a::quad_sub::kQpos, od::DataType::Real64, "QPOS?");
    else read(kError, 0, od::DataType::Unsigned8, "ERROR?");
  }

  void qscale(const Words& w) {
    need(w, 1, 1);
    real(kQuadrature, hp44714a::quad_sub::kQscale, number(w[0], w[1]));
  }

  void qindex(const Words& w) {
    need(w, 0, 1);
    static const std::map<std::string, uint8_t> modes = {{"OFF", 0}, {"ONCE", 1}, {"SGL", 2}};
    std::string m = w.size() > 1 ? w[1] : "SGL";
    if (!modes.contains(m)) throw std::invalid_argument("QINDEX: mode must be OFF, ONCE or SGL");
    u8(kQuadrature, hp44714a::quad_sub::kQindex, modes.at(m));
  }

  // TEST [slot]: the pass/fail self test (Command Summary 4-3), then its answer. The slot is
  // the node (--node): a number given is checked and not sent.
  void test(const Words& w) {
    need(w, 0, 1);
    if (w.size() > 1) number(w[0], w[1]);
    u8(kTest, hp44714a::test_sub::kRun, 1);
    read(kTest, hp44714a::test_sub::kResult, od::DataType::Unsigned8, "TEST");
  }

  // ENABLE INTR, DISABLE INTR.
  void interrupts(const Words& w) {
    const std::string& c = w[0];
    if (w.size() != 2 || w[1] != "INTR") throw std::invalid_argument(c + ": only " + c + " INTR");
    u8(kInterrupt, hp44714a::intr_sub::kEnable, c == "ENABLE" ? 1 : 0);
  }

  void command(const Words& w) {
    const std::string& c = w[0];
    if (std::find(w.begin(), w.end(), "USE") != w.end())
      throw std::invalid_argument(c + ": USE ch is given with --axis (channel 0 = axis 1)");
    using Handler = void (Planner::*)(const Words&);
    static const std::map<std::string, Handler> handlers = {
        {"PROFILE", &Planner::profile},
        {"PSCALE", &Planner::pscale},
        {"MOVE", &Planner::move_or_sustain},
        {"SUSTAIN", &Planner::move_or_sustain},
        {"TRIG", &Planner::trig},
        {"DELAY", &Planner::delay},
        {"STANDBY", &Planner::standby},
        {"PULSE", &Planner::pulse},
        {"HARDLIM", &Planner::hardlim},
        {"HALT", &Planner::halt},
        {"POS", &Planner::pos},
        {"POS?", &Planner::query},
        {"DONE?", &Planner::query},
        {"ERR?", &Planner::query},
        {"ERROR?", &Planner::query},
        {"QSCALE", &Planner::qscale},
        {"QINDEX", &Planner::qindex},
        {"QPOS?", &Planner::query},
        {"ENABLE", &Planner::interrupts},
        {"DISABLE", &Planner::interrupts},
        {"TEST", &Planner::test},
    };
    const auto h = handlers.find(c);
    if (h == handlers.end()) throw std::invalid_argument("'" + c + "' is not an HP 44714A command");
    (this->*h->second)(w);
  }
};

}  // namespace

std::vector<HpAccess> plan_hp_words(const std::string& text, unsigned channel) {
  Planner p{channel, {}};
  std::stringstream ss(text);
  std::string one;
  while (std::getline(ss, one, ';')) {
    auto w = split_words(one);
    if (!w.empty()) p.command(w);
  }
  if (p.out.empty()) throw std::invalid_argument("no HP command given");
  return p.out;
}

std::string hp_error_text(unsigned n) {
  switch (n) {
    case 0: return "no error";
    case 89: return "ACCESSORY BUSY";
    case 90: return "NO ACTION DEFINED";
    case 91: return "MUST STOP TO CHANGE DIRECTION";
    case 92: return "NOT VALID IN WIDTH MODE";
    case 93: return "TERMINAL CARD TEST JUMPER SET";
    case 94: return "CANNOT MOVE WHILE STANDBY ON";
    default: return "unknown error";
  }
}

std::string hp_conflict_text(unsigned row) {
  switch (row) {
    case 0: return "no conflict";
    case 1: return "slope = 0; min-to-max range unattainable";
    case 2: return "min = 0; slope = 0; no pulses can be generated";
    case 3: return "min = max = slope = 0; no pulses can be generated";
    case 4: return "pulse width larger than the period of max (FREQ) / period < max width (WIDTH)";
    case 5: return "min > max";
    case 6: return "outside the module's specifications (appendix A)";
    case 7: return "mode change while a MOVE or SUSTAIN waits for its trigger";
    default: return "unknown conflict";
  }
}

std::string hp_done_text(int code) {
  switch (code) {
    case -3: return "waiting for trigger";
    case -2: return "running";
    case -1: return "SUSTAIN running / ready for next command";
    case 0: return "move completed successfully";
    case 1: return "move aborted because of halt";
    case 2: return "move aborted because of hard limit";
    default: return "unknown";
  }
}

}  // namespace stepnode::tools
