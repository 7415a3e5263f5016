#include "bridge/dds/convert.hpp"

namespace stepnode::bridge::dds {

::stepnode::NodeState to_idl(NodeState state) {
  switch (state) {
    case NodeState::Unknown: return ::stepnode::NODE_UNKNOWN;
    case NodeState::BootUp: return ::stepnode::NODE_BOOT_UP;
    case NodeState::Stopped: return ::stepnode::NODE_STOPPED;
    case NodeState::Operational: return ::stepnode::NODE_OPERATIONAL;
    case NodeState::PreOperational: return ::stepnode::NODE_PRE_OPERATIONAL;
    case NodeState::Lost: return ::stepnode::NODE_LOST;
  }
  return ::stepnode::NODE_UNKNOWN;
}

NodeState from_idl(::stepnode::NodeState state) {
  switch (state) {
    case ::stepnode::NODE_UNKNOWN: return NodeState::Unknown;
    case ::stepnode::NODE_BOOT_UP: return NodeState::BootUp;
    case ::stepnode::NODE_STOPPED: return NodeState::Stopped;
    case ::stepnode::NODE_OPERATIONAL: return NodeState::Operational;
    case ::stepnode::NODE_PRE_OPERATIONAL: return NodeState::PreOperational;
    case ::stepnode::NODE_LOST: return NodeState::Lost;
  }
  return NodeState::Unknown;
}

std::string_view state_text(::stepnode::NodeState state) {
  switch (state) {
    case ::stepnode::NODE_UNKNOWN: return "UNKNOWN";
    case ::stepnode::NODE_BOOT_UP: return "BOOT_UP";
    case ::stepnode::NODE_STOPPED: return "STOPPED";
    case ::stepnode::NODE_OPERATIONAL: return "OPERATIONAL";
    case ::stepnode::NODE_PRE_OPERATIONAL: return "PRE_OPERATIONAL";
    case ::stepnode::NODE_LOST: return "LOST";
  }
  return "UNKNOWN";
}

::stepnode::DriveState to_idl(DriveState state) {
  switch (state) {
    case DriveState::Unknown: return ::stepnode::DRIVE_UNKNOWN;
    case DriveState::NotReadyToSwitchOn: return ::stepnode::DRIVE_NOT_READY_TO_SWITCH_ON;
    case DriveState::SwitchOnDisabled: return ::stepnode::DRIVE_SWITCH_ON_DISABLED;
    case DriveState::ReadyToSwitchOn: return ::stepnode::DRIVE_READY_TO_SWITCH_ON;
    case DriveState::SwitchedOn: return ::stepnode::DRIVE_SWITCHED_ON;
    case DriveState::OperationEnabled: return ::stepnode::DRIVE_OPERATION_ENABLED;
    case DriveState::QuickStopActive: return ::stepnode::DRIVE_QUICK_STOP_ACTIVE;
    case DriveState::FaultReactionActive: return ::stepnode::DRIVE_FAULT_REACTION_ACTIVE;
    case DriveState::Fault: return ::stepnode::DRIVE_FAULT;
  }
  return ::stepnode::DRIVE_UNKNOWN;
}

std::string_view drive_state_text(::stepnode::DriveState state) {
  switch (state) {  // IEC 61800-7-201 / CiA 402-2 state names
    case ::stepnode::DRIVE_UNKNOWN: return "unknown";
    case ::stepnode::DRIVE_NOT_READY_TO_SWITCH_ON: return "Not ready to switch on";
    case ::stepnode::DRIVE_SWITCH_ON_DISABLED: return "Switch on disabled";
    case ::stepnode::DRIVE_READY_TO_SWITCH_ON: return "Ready to switch on";
    case ::stepnode::DRIVE_SWITCHED_ON: return "Switched on";
    case ::stepnode::DRIVE_OPERATION_ENABLED: return "Operation enabled";
    case ::stepnode::DRIVE_QUICK_STOP_ACTIVE: return "Quick stop active";
    case ::stepnode::DRIVE_FAULT_REACTION_ACTIVE: return "Fault reaction active";
    case ::stepnode::DRIVE_FAULT: return "Fault";
  }
  return "unknown";
}

::stepnode::DriveStatus to_idl(const DriveStatusSample& s) {
  ::stepnode::DriveStatus out;
  auto bit = [&](uint16_t mask) { return (s.statusword & mask) != 0; };
  out.node(s.node);
  out.axis(s.axis);
  out.statusword(s.statusword);
  out.state(to_idl(s.state()));
  out.mode_display(s.mode_display);
  out.position_actual(s.position_actual);
  out.velocity_actual(s.velocity_actual);
  out.following_error(s.following_error);
  out.error_code(s.error_code);
  out.ready_to_switch_on(bit(drive_bit::kReadyToSwitchOn));
  out.switched_on(bit(drive_bit::kSwitchedOn));
  out.operation_enabled(bit(drive_bit::kOperationEnabled));
  out.fault(bit(drive_bit::kFault));
  out.voltage_enabled(bit(drive_bit::kVoltageEnabled));
  out.quick_stop(bit(drive_bit::kQuickStop));
  out.switch_on_disabled(bit(drive_bit::kSwitchOnDisabled));
  out.warning(bit(drive_bit::kWarning));
  out.remote(bit(drive_bit::kRemote));
  out.target_reached(bit(drive_bit::kTargetReached));
  out.internal_limit_active(bit(drive_bit::kInternalLimitActive));
  out.bit12(bit(kDriveBit12));
  out.bit13(bit(kDriveBit13));
  out.can_time_ns(s.can_time_ns);
  out.publish_time_ns(s.publish_time_ns);
  return out;
}

::stepnode::AxisStatus to_idl(const AxisStatusSample& s) {
  ::stepnode::AxisStatus out;
  auto bit = [&](uint16_t mask) { return (s.status_bits & mask) != 0; };
  out.node(s.node);
  out.axis(s.axis);
  out.emergency_stop(bit(status_bit::kEmergencyStop));
  out.lower_limit(bit(status_bit::kLowerLimit));
  out.upper_limit(bit(status_bit::kUpperLimit));
  out.illegal_move(bit(status_bit::kIllegalMove));
  out.motor_stalled(bit(status_bit::kMotorStalled));
  out.power_up_error(bit(status_bit::kPowerUp));
  out.position_valid(bit(status_bit::kPositionValid));
  out.resumable(bit(status_bit::kResumable));
  out.axis2_selected(bit(status_bit::kAxis2Selected));
  out.axis3_selected(bit(status_bit::kAxis3Selected));
  out.at_home(bit(status_bit::kAtHome));
  out.accelerating(bit(status_bit::kAccelerating));
  out.decelerating(bit(status_bit::kDecelerating));
  out.moving(bit(status_bit::kMoving));
  out.status_bits(s.status_bits);
  out.error_bits(static_cast<uint8_t>(s.status_bits & status_bit::kErrors));
  out.done_code(s.done_code);
  out.hp_error(s.hp_error);
  out.can_time_ns(s.can_time_ns);
  return out;
}

::stepnode::AxisPosition to_idl(const AxisPositionSample& s) {
  ::stepnode::AxisPosition out;
  out.node(s.node);
  out.axis(s.axis);
  out.motor_position(s.motor_position);
  out.encoder_position(s.encoder_position);
  out.motor_user_units(s.motor_user_units);
  out.encoder_user_units(s.encoder_user_units);
  out.velocity(s.velocity);
  out.motion_phase(s.motion_phase);
  out.sync_counter(s.sync_counter);
  out.can_time_ns(s.can_time_ns);
  out.publish_time_ns(s.publish_time_ns);
  return out;
}

::stepnode::NodeHealth to_idl(const NodeHealthSample& s) {
  ::stepnode::NodeHealth out;
  out.node(s.node);
  out.state(to_idl(s.state));
  out.is_stepnode(s.is_stepnode);
  out.discovered(s.discovered);
  out.device_name(s.device_name);
  out.vendor_id(s.vendor_id);
  out.product_code(s.product_code);
  out.revision(s.revision);
  out.serial(s.serial);
  out.axes(s.axes);
  out.heartbeat_age_ms(s.heartbeat_age_ms);
  out.last_emcy_code(s.last_emcy_code);
  out.error_register(s.error_register);
  out.frames(s.frames);
  out.bad_frames(s.bad_frames);
  out.sdo_failures(s.sdo_failures);
  out.bus_frames(s.bus.frames);
  out.bus_bad_frames(s.bus.bad_frames);
  out.bus_undecoded(s.bus.undecoded);
  out.bus_error_frames(s.bus.error_frames);
  out.bus_error_passive(s.bus.error_passive);
  out.bus_off(s.bus.bus_off);
  out.bus_overruns(s.bus.overruns);
  return out;
}

::stepnode::Emergency to_idl(const EmergencySample& s) {
  ::stepnode::Emergency out;
  out.node(s.node);
  out.code(s.code);
  out.error_register(s.error_register);
  out.manufacturer(s.manufacturer);
  out.text(s.text);
  out.can_time_ns(s.can_time_ns);
  return out;
}

}  // namespace stepnode::bridge::dds
