#include "tools/stepctl/drive_words.hpp"

#include "od/emcy_text.hpp"

namespace stepnode::tools::drive {

State decode_state(uint16_t s) {
  // 6041h state coding: (mask, value) per state.
  if ((s & 0x4F) == 0x00) return State::NotReadyToSwitchOn;   // x0xx 0000
  if ((s & 0x4F) == 0x40) return State::SwitchOnDisabled;     // x1xx 0000
  if ((s & 0x6F) == 0x21) return State::ReadyToSwitchOn;      // x01x 0001
  if ((s & 0x6F) == 0x23) return State::SwitchedOn;           // x01x 0011
  if ((s & 0x6F) == 0x27) return State::OperationEnabled;     // x01x 0111
  if ((s & 0x6F) == 0x07) return State::QuickStopActive;      // x00x 0111
  if ((s & 0x4F) == 0x0F) return State::FaultReactionActive;  // x0xx 1111
  if ((s & 0x4F) == 0x08) return State::Fault;                // x0xx 1000
  return State::Unknown;
}

const char* name(State state) {
  switch (state) {
    case State::NotReadyToSwitchOn: return "Not ready to switch on";
    case State::SwitchOnDisabled: return "Switch on disabled";
    case State::ReadyToSwitchOn: return "Ready to switch on";
    case State::SwitchedOn: return "Switched on";
    case State::OperationEnabled: return "Operation enabled";
    case State::QuickStopActive: return "Quick stop active";
    case State::FaultReactionActive: return "Fault reaction active";
    case State::Fault: return "Fault";
    case State::Unknown: break;
  }
  return "unknown state";
}

bool disabled(State state) {
  return state == State::NotReadyToSwitchOn || state == State::SwitchOnDisabled ||
         state == State::ReadyToSwitchOn || state == State::Fault;
}

bool fault(State state) { return state == State::FaultReactionActive || state == State::Fault; }

std::string mode_name(int8_t mode) {
  switch (mode) {
    case 0: return "no mode assigned";
    case 1: return "Profile position";
    case 2: return "Velocity";
    case 3: return "Profile velocity";
    case 4: return "Profile torque";
    case 6: return "Homing";
    case 7: return "Interpolated position";
    case 8: return "Cyclic synchronous position";
    case 9: return "Cyclic synchronous velocity";
    case 10: return "Cyclic synchronous torque";
    default: break;
  }
  if (mode < 0) return "manufacturer-specific mode " + std::to_string(mode);
  return "reserved mode " + std::to_string(mode);
}

std::vector<std::string> status_bits(uint16_t s, int8_t mode) {
  // Bits 10, 12 and 13 by mode (CiA 402-2, each mode's statusword bits).
  const char* bit10 = "target reached";
  const char* bit12 = "bit 12 (mode-specific)";
  const char* bit13 = "bit 13 (mode-specific)";
  switch (mode) {
    case 1: bit12 = "set-point acknowledge", bit13 = "following error"; break;
    case 3: bit10 = "velocity reached", bit12 = "speed zero", bit13 = "max slippage error"; break;
    case 6: bit12 = "homing attained", bit13 = "homing error"; break;
    case 7: bit12 = "ip mode active"; break;
    case 8: bit12 = "drive follows the command value", bit13 = "following error"; break;
    case 9:
    case 10: bit12 = "drive follows the command value"; break;
    default: break;
  }
  const std::pair<uint16_t, const char*> bits[] = {
      {1u << 3, "fault"},
      {sw::kVoltageEnabled, "voltage enabled"},
      {sw::kWarning, "warning"},
      {1u << 8, "manufacturer-specific bit 8"},
      {sw::kRemote, "remote"},
      {sw::kTargetReached, bit10},
      {sw::kInternalLimitActive, "internal limit active"},
      {sw::kBit12, bit12},
      {sw::kBit13, bit13},
      {1u << 14, "manufacturer-specific bit 14"},
      {1u << 15, "manufacturer-specific bit 15"},
  };
  std::vector<std::string> out;
  for (const auto& [bit, text] : bits)
    if (s & bit) out.emplace_back(text);
  return out;
}

std::string homing_status(uint16_t s) {
  const bool error = s & sw::kBit13, attained = s & sw::kBit12, reached = s & sw::kTargetReached;
  if (error && attained) return "reserved (bits 13 and 12 both set)";
  if (error)
    return reached ? "homing error occurred, velocity is 0"
                   : "homing error occurred, velocity is not 0";
  if (attained)
    return reached ? "homing procedure is completed successfully"
                   : "homing is attained, but target is not reached";
  return reached ? "homing procedure is interrupted or not started"
                 : "homing procedure is in progress";
}

std::string error_code_text(uint16_t code) {
  switch (code) {
    case 0x0000: return "no error";
    case 0x8611: return "following error";
    case 0x8612: return "reference limit";
    default: return od::emcy_code_text(code);
  }
}

namespace {

Step step(std::vector<uint16_t> controlwords, const char* command, std::vector<State> leads_to,
          bool ramp = false) {
  return Step{std::move(controlwords), command, std::move(leads_to), ramp};
}

// Fault reset: the rising edge of bit 7, so bit 7 goes to 0 first when it is 1.
Step reset(uint16_t controlword) {
  std::vector<uint16_t> words;
  if (controlword & cw::kFaultReset) words.push_back(cw::kDisableVoltage);
  words.push_back(cw::kFaultReset);
  return step(std::move(words), "Fault reset", {State::SwitchOnDisabled});
}

Step wait_for(State state, const char* what, bool ramp) { return step({}, what, {state}, ramp); }

}  // namespace

std::optional<Step> enable_step(State state, uint16_t controlword) {
  switch (state) {
    case State::NotReadyToSwitchOn:
      return wait_for(State::SwitchOnDisabled, "(the drive's initialisation)", false);
    case State::SwitchOnDisabled:
      return step({cw::kShutdown}, "Shutdown", {State::ReadyToSwitchOn});
    case State::ReadyToSwitchOn: return step({cw::kSwitchOn}, "Switch on", {State::SwitchedOn});
    case State::SwitchedOn:
      return step({cw::kEnableOperation}, "Enable operation", {State::OperationEnabled});
    case State::OperationEnabled: return std::nullopt;
    case State::QuickStopActive:
      return step({cw::kDisableVoltage}, "Disable voltage", {State::SwitchOnDisabled});
    case State::FaultReactionActive: return wait_for(State::Fault, "(the fault reaction)", true);
    case State::Fault: return reset(controlword);
    case State::Unknown: return std::nullopt;
  }
  return std::nullopt;
}

std::optional<Step> disable_step(State state, uint16_t) {
  switch (state) {
    case State::OperationEnabled:  // transition 5: 605Ch may ramp down first
      return step({cw::kSwitchOn}, "Disable operation", {State::SwitchedOn}, true);
    case State::SwitchedOn: return step({cw::kShutdown}, "Shutdown", {State::ReadyToSwitchOn});
    case State::QuickStopActive:
      return step({cw::kDisableVoltage}, "Disable voltage", {State::SwitchOnDisabled});
    case State::FaultReactionActive: return wait_for(State::Fault, "(the fault reaction)", true);
    default: return std::nullopt;
  }
}

std::optional<Step> quick_stop_step(State state, uint16_t) {
  switch (state) {
    case State::OperationEnabled:  // transition 11, then 12 after the ramp for 605Ah 0..4
      return step({cw::kQuickStop}, "Quick stop",
                  {State::QuickStopActive, State::SwitchOnDisabled});
    case State::SwitchedOn:       // transition 10
    case State::ReadyToSwitchOn:  // transition 7
      return step({cw::kQuickStop}, "Quick stop", {State::SwitchOnDisabled});
    default: return std::nullopt;
  }
}

std::optional<Step> fault_reset_step(State state, uint16_t controlword) {
  if (state == State::FaultReactionActive)
    return wait_for(State::Fault, "(the fault reaction)", true);
  if (state != State::Fault) return std::nullopt;
  return reset(controlword);
}

uint16_t set_point_controlword(bool immediately, bool relative) {
  return static_cast<uint16_t>(cw::kEnableOperation | cw::kNewSetPoint |
                               (immediately ? cw::kChangeSetImmediately : 0) |
                               (relative ? cw::kRelative : 0));
}

}  // namespace stepnode::tools::drive
