// `stepctl drive`: the master's side of CiA 402 device control (CiA 402-2 / IEC 61800-7-201),
// pure: the statusword (6041h) in the standard's words, decoded with the masks of its state
// coding table; the mode (6061h) by name; and the controlword (6040h) steps that bring a
// drive from the state it is in to Operation enabled, to Ready to switch on, through a quick
// stop or a fault reset. drive_command.cpp carries the steps out over SDO.
//
// A master's view: it knows only what the bus shows, so it decodes with the standard's
// tables and not with the node's state machine (node/profiles/cia402/drive_state.*), and
// works as well with another vendor's CiA 402 drive.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace stepnode::tools::drive {

// The eight states of the PDS FSA, and Unknown for a statusword that matches no row of the
// state coding table.
enum class State : uint8_t {
  NotReadyToSwitchOn,
  SwitchOnDisabled,
  ReadyToSwitchOn,
  SwitchedOn,
  OperationEnabled,
  QuickStopActive,
  FaultReactionActive,
  Fault,
  Unknown,
};

// The state a statusword shows (bits 0-3, 5, 6 with the table's masks: 0x4F for Not ready
// to switch on, Switch on disabled, Fault reaction active and Fault, 0x6F for the others).
State decode_state(uint16_t statusword);
// "Switch on disabled", "Operation enabled", ... as the standard names them; "unknown state".
const char* name(State state);
// The states where the power section is off and nothing moves under the drive's control.
bool disabled(State state);
bool fault(State state);  // Fault reaction active or Fault

// 6060h/6061h: "Profile position", "Profile velocity", "Homing", ..., "no mode assigned" (0),
// "manufacturer-specific mode -3" (negative), "reserved mode 12".
std::string mode_name(int8_t mode);

// Controlword commands of the command coding table with the bits the table leaves open 0,
// and the mode-specific bits of profile position and homing mode.
namespace cw {
constexpr uint16_t kDisableVoltage = 0x0000;        // 0xxx xx0x
constexpr uint16_t kQuickStop = 0x000B;             // 0xxx x01x, with bits 0 and 3 as in operation
constexpr uint16_t kShutdown = 0x0006;              // 0xxx x110
constexpr uint16_t kSwitchOn = 0x0007;              // 0xxx 0111 (also Disable operation)
constexpr uint16_t kEnableOperation = 0x000F;       // 0xxx 1111
constexpr uint16_t kFaultReset = 0x0080;            // bit 7, its rising edge
constexpr uint16_t kNewSetPoint = 0x0010;           // pp bit 4; hm bit 4: homing operation start
constexpr uint16_t kChangeSetImmediately = 0x0020;  // pp bit 5
constexpr uint16_t kRelative = 0x0040;              // pp bit 6
constexpr uint16_t kHalt = 0x0100;                  // bit 8
}  // namespace cw

// Statusword bits beyond the state coding.
namespace sw {
constexpr uint16_t kVoltageEnabled = 1u << 4;
constexpr uint16_t kWarning = 1u << 7;
constexpr uint16_t kRemote = 1u << 9;
constexpr uint16_t kTargetReached = 1u << 10;  // pv: velocity reached
constexpr uint16_t kInternalLimitActive = 1u << 11;
constexpr uint16_t kBit12 =
    1u << 12;  // pp set-point acknowledge, pv speed zero, hm homing attained
constexpr uint16_t kBit13 = 1u << 13;  // pp following error, pv max slippage error, hm homing error
}  // namespace sw

// The statusword bits that are set, in words, the mode-specific ones (10, 12, 13) named for
// `mode` (6061h): e.g. {"voltage enabled", "remote", "target reached", "set-point
// acknowledge"}. The state bits (0-3, 5, 6) are left to name(decode_state()).
std::vector<std::string> status_bits(uint16_t statusword, int8_t mode);
// The homing status of bits 13, 12, 10 (CiA 402-2 homing mode statusword table):
// "homing procedure is in progress", "... completed successfully", "homing error occurred,
// velocity is 0", ...
std::string homing_status(uint16_t statusword);
// 603Fh in words: "no error" (0), "reference limit" (8612h), else CiA 301's (od/emcy_text).
std::string error_code_text(uint16_t code);

// One step of device control: the controlwords to write, in order (none: the drive moves
// on by itself), and the states it leads to. `ramp`: the transition may wait for a stop
// ramp (605Ch, a fault reaction), so it can take longer than a switching transition.
struct Step {
  std::vector<uint16_t> controlwords;
  std::string command;          // the standard's name: "Shutdown", "Fault reset", ...
  std::vector<State> leads_to;  // any of these ends the step
  bool ramp = false;
};

// The next step from `state` toward Operation enabled (nullopt: there, or Unknown, which the
// caller refuses first). `controlword` is the last one written (6040h): a fault reset
// needs bit 7 at 0 before its rising edge.
//   Fault -> Fault reset (0x80, after 0x00 when bit 7 is set) -> Switch on disabled
//   -> Shutdown 0x06 -> Ready to switch on -> Switch on 0x07 -> Switched on
//   -> Enable operation 0x0F -> Operation enabled.
//   Not ready to switch on and Fault reaction active: wait (transitions 1 and 14 are the
//   drive's own). Quick stop active: Disable voltage 0x00 -> Switch on disabled (transition
//   12, every drive has it; 16 only some).
std::optional<Step> enable_step(State state, uint16_t controlword);
// Toward Ready to switch on: Operation enabled -> Disable operation 0x07 -> Switched on ->
// Shutdown 0x06 -> Ready to switch on. Quick stop active: Disable voltage -> Switch on
// disabled. Fault reaction active: wait for Fault. Nullopt in Ready to switch on and in the
// states that are disabled already (Not ready to switch on, Switch on disabled, Fault).
std::optional<Step> disable_step(State state, uint16_t controlword);
// Quick stop 0x0B: Operation enabled -> Quick stop active (then Switch on disabled with
// 605Ah 0..4); Switched on and Ready to switch on -> Switch on disabled (transitions 10, 7).
// Nullopt where there is nothing to stop (disabled, Quick stop active, a fault).
std::optional<Step> quick_stop_step(State state, uint16_t controlword);
// Fault reset: Fault -> Switch on disabled (transition 15); Fault reaction active: wait for
// Fault first. Nullopt in the states without a fault.
std::optional<Step> fault_reset_step(State state, uint16_t controlword);

// The profile position set-point controlword (bit 4 with bits 5, 6) on top of Enable
// operation: 0x1F, | 0x20 change set immediately, | 0x40 relative.
uint16_t set_point_controlword(bool immediately, bool relative);

}  // namespace stepnode::tools::drive
