// The plain sample structs of bridge/samples.hpp as the IDL types fastddsgen generates
// from bridge/idl/stepnode.idl, and back (stepwatch and tests read them). Pure.
#pragma once
#include <stepnodePubSubTypes.h>

#include <string_view>

#include "bridge/samples.hpp"

namespace stepnode::bridge::dds {

// Status word bits (%I1..%I16 as bits 0..15, node/motion/axis_registers.hpp).
namespace status_bit {
constexpr uint16_t kEmergencyStop = 1u << 0;   // %I1
constexpr uint16_t kLowerLimit = 1u << 1;      // %I2
constexpr uint16_t kUpperLimit = 1u << 2;      // %I3
constexpr uint16_t kIllegalMove = 1u << 3;     // %I4
constexpr uint16_t kMotorStalled = 1u << 4;    // %I5
constexpr uint16_t kPowerUp = 1u << 7;         // %I8
constexpr uint16_t kErrors = 0x00FF;           // %I1..%I8
constexpr uint16_t kPositionValid = 1u << 8;   // %I9
constexpr uint16_t kResumable = 1u << 9;       // %I10
constexpr uint16_t kAxis2Selected = 1u << 10;  // %I11
constexpr uint16_t kAxis3Selected = 1u << 11;  // %I12
constexpr uint16_t kAtHome = 1u << 12;         // %I13
constexpr uint16_t kAccelerating = 1u << 13;   // %I14
constexpr uint16_t kDecelerating = 1u << 14;   // %I15
constexpr uint16_t kMoving = 1u << 15;         // %I16
}  // namespace status_bit

::stepnode::AxisStatus to_idl(const AxisStatusSample& s);
::stepnode::AxisPosition to_idl(const AxisPositionSample& s);
::stepnode::NodeHealth to_idl(const NodeHealthSample& s);
::stepnode::Emergency to_idl(const EmergencySample& s);
::stepnode::NodeState to_idl(NodeState state);

NodeState from_idl(::stepnode::NodeState state);
// "OPERATIONAL", "LOST", ... (stepwatch prints these).
std::string_view state_text(::stepnode::NodeState state);

}  // namespace stepnode::bridge::dds
