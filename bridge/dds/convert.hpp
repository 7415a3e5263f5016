// The plain sample structs of bridge/samples.hpp as the IDL types fastddsgen generates
// from bridge/idl/stepnode.idl, and back (stepwatch and tests read them). Pure.
#pragma once
#include <stepnodePubSubTypes.h>

#include <string_view>

#include "bridge/samples.hpp"
#include "node/profiles/cia402/drive_state.hpp"
#include "node/profiles/horner/bits.hpp"

namespace stepnode::bridge::dds {

// Status word bits (%I1..%I16 as bits 0..15 of 0x2n01).
namespace status_bit = horner::status;
// CiA 402 statusword bits (6041h); bits 12 and 13 are mode-specific.
namespace drive_bit = cia402::sw;
constexpr uint16_t kDriveBit12 = 1u << 12, kDriveBit13 = 1u << 13;

::stepnode::AxisStatus to_idl(const AxisStatusSample& s);
::stepnode::AxisPosition to_idl(const AxisPositionSample& s);
::stepnode::NodeHealth to_idl(const NodeHealthSample& s);
::stepnode::Emergency to_idl(const EmergencySample& s);
::stepnode::DriveStatus to_idl(const DriveStatusSample& s);
::stepnode::NodeState to_idl(NodeState state);
::stepnode::DriveState to_idl(DriveState state);

NodeState from_idl(::stepnode::NodeState state);
// "OPERATIONAL", "LOST", ... (stepwatch prints these).
std::string_view state_text(::stepnode::NodeState state);
// The standard's names: "Operation enabled", "Switch on disabled", ...; "unknown".
std::string_view drive_state_text(::stepnode::DriveState state);

}  // namespace stepnode::bridge::dds
