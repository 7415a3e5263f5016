#include "node/profiles/cia402/drive_state.hpp"

namespace stepnode::cia402 {

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
  }
  return "?";
}

const char* name(Command command) {
  switch (command) {
    case Command::None: return "none";
    case Command::Shutdown: return "Shutdown";
    case Command::SwitchOn: return "Switch on";
    case Command::SwitchOnAndEnable: return "Switch on + enable operation";
    case Command::EnableOperation: return "Enable operation";
    case Command::DisableOperation: return "Disable operation";
    case Command::DisableVoltage: return "Disable voltage";
    case Command::QuickStop: return "Quick stop";
    case Command::FaultReset: return "Fault reset";
  }
  return "?";
}

const char* name(Stop stop) {
  switch (stop) {
    case Stop::None: return "none";
    case Stop::DisableDrive: return "disable drive function";
    case Stop::SlowDownRamp: return "slow-down ramp";
    case Stop::QuickStopRamp: return "quick stop ramp";
    case Stop::Immediate: return "current limit (pulses stop, motor powered)";
  }
  return "?";
}

Command decode(uint16_t controlword, uint16_t previous_controlword) {
  // 6040h command coding: bit 7 and bits 3..0. Every command but the fault reset has bit 7 at
  // 0; the reset is its 0 -> 1 edge, bits 3..0 whatever they are.
  const bool reset_now = (controlword & cw::kFaultReset) != 0;
  const bool reset_before = (previous_controlword & cw::kFaultReset) != 0;
  if (reset_now) return reset_before ? Command::None : Command::FaultReset;
  if ((controlword & 0x0002) == 0x0000) return Command::DisableVoltage;  // 0xxx xx0x
  if ((controlword & 0x0006) == 0x0002) return Command::QuickStop;       // 0xxx x01x
  if ((controlword & 0x0007) == 0x0006) return Command::Shutdown;        // 0xxx x110
  if ((controlword & 0x000F) == 0x0007) return Command::SwitchOn;        // 0xxx 0111
  return Command::SwitchOnAndEnable;                                     // 0xxx 1111
}

Command decode(uint16_t controlword, uint16_t previous_controlword, State state) {
  Command command = decode(controlword, previous_controlword);
  if (command == Command::SwitchOn && state == State::OperationEnabled)
    return Command::DisableOperation;
  if (command == Command::SwitchOnAndEnable &&
      (state == State::SwitchedOn || state == State::OperationEnabled ||
       state == State::QuickStopActive))
    return Command::EnableOperation;
  return command;
}

bool powered(State state) {
  return state == State::SwitchedOn || state == State::OperationEnabled ||
         state == State::QuickStopActive || state == State::FaultReactionActive;
}

uint16_t state_bits(State state) {
  // 6041h state coding (bits 6, 5, 3..0), "x" taken as 0:
  uint16_t bits = 0;
  switch (state) {
    case State::NotReadyToSwitchOn: bits = 0x0000; break;   // x0xx 0000
    case State::SwitchOnDisabled: bits = 0x0040; break;     // x1xx 0000
    case State::ReadyToSwitchOn: bits = 0x0021; break;      // x01x 0001
    case State::SwitchedOn: bits = 0x0023; break;           // x01x 0011
    case State::OperationEnabled: bits = 0x0027; break;     // x01x 0111
    case State::QuickStopActive: bits = 0x0007; break;      // x00x 0111
    case State::FaultReactionActive: bits = 0x000F; break;  // x0xx 1111
    case State::Fault: bits = 0x0008; break;                // x0xx 1000
  }
  if (powered(state)) bits |= sw::kVoltageEnabled;
  return static_cast<uint16_t>(bits | sw::kRemote);
}

Stop quick_stop_stop(int16_t option_605a) {
  switch (option_605a) {
    case 0: return Stop::DisableDrive;
    case 1:
    case 5: return Stop::SlowDownRamp;
    case 2:
    case 6: return Stop::QuickStopRamp;
    case 3:
    case 4:
    case 7:
    case 8: return Stop::Immediate;
    default: return quick_stop_stop(option::kQuickStopDefault);
  }
}

bool quick_stop_stays_active(int16_t option_605a) { return option_605a >= 5 && option_605a <= 8; }

Stop shutdown_stop(int16_t option_605b) {
  switch (option_605b) {
    case 0: return Stop::DisableDrive;
    case 1: return Stop::SlowDownRamp;
    default: return shutdown_stop(option::kShutdownDefault);
  }
}

Stop disable_operation_stop(int16_t option_605c) {
  switch (option_605c) {
    case 0: return Stop::DisableDrive;
    case 1: return Stop::SlowDownRamp;
    default: return disable_operation_stop(option::kDisableOperationDefault);
  }
}

Stop halt_stop(int16_t option_605d) {
  switch (option_605d) {
    case 1: return Stop::SlowDownRamp;
    case 2: return Stop::QuickStopRamp;
    case 3:
    case 4: return Stop::Immediate;
    default: return halt_stop(option::kHaltDefault);
  }
}

Stop fault_reaction_stop(int16_t option_605e) {
  switch (option_605e) {
    case 0: return Stop::DisableDrive;
    case 1: return Stop::SlowDownRamp;
    case 2: return Stop::QuickStopRamp;
    case 3:
    case 4: return Stop::Immediate;
    default: return fault_reaction_stop(option::kFaultReactionDefault);
  }
}

void DriveStateMachine::take(int transition, State target) {
  state_ = target;
  last_transition_ = transition;
}

void DriveStateMachine::power_on() {
  pending_ = {};
  error_code_ = 0;
  take(0, State::NotReadyToSwitchOn);  // initialisation and self test: nothing to do here
  take(1, State::SwitchOnDisabled);    // communication enabled
}

Stop DriveStateMachine::on_controlword(uint16_t controlword) {
  const Command command = decode(controlword, previous_controlword_, state_);
  previous_controlword_ = controlword;
  return apply(command);
}

Stop DriveStateMachine::apply(Command command) {
  switch (state_) {
    case State::SwitchOnDisabled:
      if (command == Command::Shutdown) take(2, State::ReadyToSwitchOn);
      return Stop::None;
    case State::ReadyToSwitchOn:
      if (command == Command::SwitchOn) {
        take(3, State::SwitchedOn);
      } else if (command == Command::SwitchOnAndEnable) {
        take(3, State::SwitchedOn);
        take(4, State::OperationEnabled);
      } else if (command == Command::DisableVoltage || command == Command::QuickStop) {
        take(7, State::SwitchOnDisabled);
      }
      return Stop::None;
    case State::SwitchedOn:
      // Nothing moves here: switching the power section off needs no stop.
      if (command == Command::EnableOperation) take(4, State::OperationEnabled);
      else if (command == Command::Shutdown) take(6, State::ReadyToSwitchOn);
      else if (command == Command::DisableVoltage || command == Command::QuickStop)
        take(10, State::SwitchOnDisabled);
      return Stop::None;
    case State::OperationEnabled: return from_operation_enabled(command);
    case State::QuickStopActive: return from_quick_stop_active(command);
    case State::Fault:
      // Transition 15 "if no fault exists currently on the drive": with the cause still
      // there the reset is refused and the drive stays in Fault.
      if (command == Command::FaultReset && !fault_condition_) {
        error_code_ = 0;
        take(15, State::SwitchOnDisabled);
      }
      return Stop::None;
    case State::NotReadyToSwitchOn:
    case State::FaultReactionActive:
      return Stop::None;  // no command leaves these states (transitions 1 and 14 are automatic)
  }
  return Stop::None;
}

// Starts a transition whose action is `stop`: at once for DisableDrive, else after the ramp.
Stop DriveStateMachine::ramp_then(int transition, State target, Stop stop) {
  if (waiting() && pending_.transition == transition) return Stop::None;  // already on its way
  if (stop == Stop::DisableDrive) {
    pending_ = {};
    take(transition, target);
    return stop;
  }
  pending_ = {transition, target, stop};
  return stop;
}

Stop DriveStateMachine::from_operation_enabled(Command command) {
  switch (command) {
    case Command::EnableOperation:
      pending_ = {};  // a waiting transition 5 or 8 is called off
      return Stop::None;
    case Command::DisableOperation:  // transition 5, 605Ch
      return ramp_then(5, State::SwitchedOn, disable_operation_stop(options_.disable_operation));
    case Command::Shutdown:  // transition 8, 605Bh
      return ramp_then(8, State::ReadyToSwitchOn, shutdown_stop(options_.shutdown));
    case Command::DisableVoltage:  // transition 9: power off at once, the motor free to rotate
      pending_ = {};
      take(9, State::SwitchOnDisabled);
      return Stop::DisableDrive;
    case Command::QuickStop: return quick_stop();  // transition 11
    default: return Stop::None;
  }
}

Stop DriveStateMachine::quick_stop() {
  pending_ = {};
  take(11, State::QuickStopActive);
  const Stop stop = quick_stop_stop(options_.quick_stop);
  if (quick_stop_stays_active(options_.quick_stop)) {
    pending_ = {0, State::QuickStopActive, stop};  // 5..8: the ramp ends in Quick stop active
    return stop;
  }
  // 0..4: transition 12 once the quick stop is completed (at once for 0).
  return ramp_then(12, State::SwitchOnDisabled, stop);
}

Stop DriveStateMachine::from_quick_stop_active(Command command) {
  if (command == Command::DisableVoltage) {  // transition 12 by command: power off at once
    pending_ = {};
    take(12, State::SwitchOnDisabled);
    return Stop::DisableDrive;
  }
  // Transition 16 only with 605Ah 5..8, the options that stay in Quick stop active for it
  // (CiA 402-2 Table 26 recommends not to support it; then 5..8 would have to be refused).
  // It calls off what remains of the ramp.
  if (command == Command::EnableOperation && quick_stop_stays_active(options_.quick_stop)) {
    pending_ = {};
    take(16, State::OperationEnabled);
  }
  return Stop::None;
}

void DriveStateMachine::motion_stopped() {
  if (!waiting()) return;
  const Pending done = pending_;
  pending_ = {};
  if (done.transition != 0) take(done.transition, done.target);
}

Stop DriveStateMachine::fault(uint16_t error_code) {
  error_code_ = error_code;
  if (state_ == State::FaultReactionActive || state_ == State::Fault) return Stop::None;
  const bool may_move = state_ == State::OperationEnabled || state_ == State::QuickStopActive;
  pending_ = {};
  take(13, State::FaultReactionActive);
  if (!may_move) {
    take(14, State::Fault);  // nothing to stop: the fault reaction is complete
    return Stop::None;
  }
  return ramp_then(14, State::Fault, fault_reaction_stop(options_.fault_reaction));
}

Stop DriveStateMachine::abort_connection(int16_t option, uint16_t error_code) {
  switch (option) {
    case option::kAbortNoAction: return Stop::None;
    case option::kAbortDisableVoltage: return apply(Command::DisableVoltage);
    case option::kAbortQuickStop: return apply(Command::QuickStop);
    default: return fault(error_code);  // 1, and the values this drive does not define
  }
}

}  // namespace stepnode::cia402
