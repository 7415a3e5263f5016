// The CiA 402 power drive system state machine (PDS FSA: CiA 402-2 / IEC 61800-7-201, "device
// control"): its eight states, the controlword commands (6040h command coding), the
// statusword state bits (6041h state coding), the transitions 0..16 (CiA 402-2 Table 26
// "Transition events and actions") and what the option codes 605Ah..605Eh and 6007h make
// the drive do. Pure: no dictionary, no clock. The CiA 402 profile's service gives it the
// controlword and the drive's events and carries out the Stop it returns; the objects are
// node/profiles/cia402/objects.*.
#pragma once
#include <cstdint>

namespace stepnode::cia402 {

enum class State : uint8_t {
  NotReadyToSwitchOn,
  SwitchOnDisabled,
  ReadyToSwitchOn,
  SwitchedOn,
  OperationEnabled,
  QuickStopActive,
  FaultReactionActive,
  Fault,
};
const char* name(State state);  // "Operation enabled", as the standard names it

// Controlword bits (6040h). Bit 2 is active low: 0 commands a quick stop.
namespace cw {
constexpr uint16_t kSwitchOn = 1u << 0;
constexpr uint16_t kEnableVoltage = 1u << 1;
constexpr uint16_t kQuickStop = 1u << 2;
constexpr uint16_t kEnableOperation = 1u << 3;
constexpr uint16_t kFaultReset = 1u << 7;
constexpr uint16_t kHalt = 1u << 8;  // mode-specific: the caller's (halt_stop)
}  // namespace cw

// Statusword bits (6041h). The state machine owns bits 0-6 and 9 (state_bits); bit 7
// (warning), bit 8 and bits 10-15 (target reached, internal limit, mode-specific) are the
// caller's.
namespace sw {
constexpr uint16_t kReadyToSwitchOn = 1u << 0;
constexpr uint16_t kSwitchedOn = 1u << 1;
constexpr uint16_t kOperationEnabled = 1u << 2;
constexpr uint16_t kFault = 1u << 3;
constexpr uint16_t kVoltageEnabled = 1u << 4;
constexpr uint16_t kQuickStop = 1u << 5;  // active low: 0 while a quick stop is being carried out
constexpr uint16_t kSwitchOnDisabled = 1u << 6;
constexpr uint16_t kWarning = 1u << 7;
constexpr uint16_t kRemote = 1u << 9;
constexpr uint16_t kTargetReached = 1u << 10;
constexpr uint16_t kInternalLimitActive = 1u << 11;
constexpr uint16_t kOwnedBits = 0x027F;  // bits 0-6 and 9: what state_bits sets
}  // namespace sw

// The commands of the controlword (6040h command coding, bits 7 and 3..0). "Switch on" and
// "Disable operation" share the code 0xxx 0111, "Switch on + enable operation" and "Enable
// operation" the code 0xxx 1111: the state decides which one it is.
enum class Command : uint8_t {
  None,
  Shutdown,           // 0xxx x110: transitions 2, 6, 8
  SwitchOn,           // 0xxx 0111: transition 3
  SwitchOnAndEnable,  // 0xxx 1111 in Ready to switch on: transitions 3 + 4
  EnableOperation,    // 0xxx 1111: transitions 4, 16
  DisableOperation,   // 0xxx 0111 in Operation enabled: transition 5
  DisableVoltage,     // 0xxx xx0x: transitions 7, 9, 10, 12
  QuickStop,          // 0xxx x01x: transitions 7, 10, 11
  FaultReset,         // bit 7 rising (0 -> 1): transition 15
};
const char* name(Command command);

// The command a controlword carries, whatever the state: the two shared codes come out as
// SwitchOn and SwitchOnAndEnable. A fault reset is the rising edge of bit 7 only; while bit
// 7 stays 1 no command of the table matches (the host clears it after the reset), so the
// result is None.
Command decode(uint16_t controlword, uint16_t previous_controlword);
// The same, read in `state`: 0xxx 0111 is Disable operation in Operation enabled, 0xxx 1111
// is Enable operation in Switched on, Operation enabled and Quick stop active.
Command decode(uint16_t controlword, uint16_t previous_controlword, State state);

// The statusword bits of a state: bits 0-3, 5, 6 as the 6041h state coding table (a bit the
// table leaves open, "x", is 0), bit 4 "voltage enabled" and bit 9 "remote".
//   Bit 4 is set whenever the motor is powered (the power section is on: the windings carry
//   current and hold the rotor): in Switched on, Operation enabled, Quick stop active and
//   Fault reaction active. Ready to switch on leaves the power section off (transition 3
//   switches it on), and transition 14 switches it off again (the standard allows it), so a
//   drive in Fault does not hold the motor.
//   Bit 9 is always 1: this drive always processes the controlword (there is no local
//   control).
uint16_t state_bits(State state);
// Whether the motor is powered in `state` (bit 4 above).
bool powered(State state);

// How the drive stops its motion, for the caller to carry out.
enum class Stop : uint8_t {
  None,           // nothing to stop
  DisableDrive,   // the drive function is disabled at once: pulses stop now, no ramp. The motor's
                  // power is then what powered() says: off, but for transition 5 with 605Ch = 0
                  // (Switched on keeps the power section on)
  SlowDownRamp,   // decelerate with the ramp of the mode (6084h profile deceleration)
  QuickStopRamp,  // decelerate with 6085h quick stop deceleration
  Immediate,      // "current limit" / "voltage limit": for a stepper, stop pulses at once and keep
                  // the motor powered (the fastest stop that holds the position)
};
const char* name(Stop stop);

// Option code values (CiA 402-2 object descriptions 605Ah..605Eh and 6007h). Negative values
// are manufacturer-specific; this drive defines none, and the objects refuse them.
namespace option {
// 605Ah quick stop: 0 disable drive function; 1 slow-down ramp, 2 quick stop ramp, 3 current
// limit, 4 voltage limit, then Switch on disabled; 5..8 the same four, then stay in Quick
// stop active. Default 2.
constexpr int16_t kQuickStopMin = 0, kQuickStopMax = 8, kQuickStopDefault = 2;
// 605Bh shutdown (transition 8) and 605Ch disable operation (transition 5): 0 disable drive
// function, 1 slow down with the slow-down ramp, then disable the drive function. Defaults
// 605Bh 0, 605Ch 1.
constexpr int16_t kShutdownDefault = 0, kDisableOperationDefault = 1;
// 605Dh halt: 1 slow-down ramp, 2 quick stop ramp, 3 current limit, 4 voltage limit, each
// staying in Operation enabled (0 is reserved). Default 1.
constexpr int16_t kHaltMin = 1, kHaltMax = 4, kHaltDefault = 1;
// 605Eh fault reaction: 0 disable drive function (the motor is free to rotate), 1 slow-down
// ramp, 2 quick stop ramp, 3 current limit, 4 voltage limit. Default 2.
constexpr int16_t kFaultReactionMax = 4, kFaultReactionDefault = 2;
// 6007h abort connection: 0 no action, 1 fault signal, 2 disable voltage command, 3 quick
// stop command. Default 1.
constexpr int16_t kAbortNoAction = 0, kAbortFault = 1, kAbortDisableVoltage = 2,
                  kAbortQuickStop = 3;
constexpr int16_t kAbortConnectionDefault = kAbortFault;
}  // namespace option

// The Stop each option code asks for. A value outside the standard's range (manufacturer-
// specific or reserved) acts as the object's default.
Stop quick_stop_stop(int16_t option_605a);
Stop shutdown_stop(int16_t option_605b);
Stop disable_operation_stop(int16_t option_605c);
Stop halt_stop(int16_t option_605d);
Stop fault_reaction_stop(int16_t option_605e);
// 605Ah 5..8: the drive stays in Quick stop active after the ramp (transition 16 possible).
bool quick_stop_stays_active(int16_t option_605a);

// The option codes the state machine applies, as plain values (the service copies them from
// 605Ah..605Eh). Defaults are the standard's.
struct Options {
  int16_t quick_stop = option::kQuickStopDefault;                // 605Ah
  int16_t shutdown = option::kShutdownDefault;                   // 605Bh
  int16_t disable_operation = option::kDisableOperationDefault;  // 605Ch
  int16_t halt = option::kHaltDefault;                           // 605Dh
  int16_t fault_reaction = option::kFaultReactionDefault;        // 605Eh
};

// The EMCY code a lost connection records as its fault (CiA 301: 8130h life guard or
// heartbeat error).
constexpr uint16_t kConnectionLostError = 0x8130;

// One axis' PDS FSA. Every call returns the Stop the caller must carry out now; after it the
// caller applies powered() to the motor and lets motion commands run only while
// operation_enabled().
//
// A transition whose action is a ramp (605Ch = 1: transition 5; 605Bh = 1: transition 8; a
// quick stop with 605Ah 1..4: transition 12 after 11; a fault reaction 1..4: transition 14
// after 13) waits for the caller's motion_stopped(). Meanwhile the statusword shows the
// state the drive is in: Operation enabled during the 605Bh/605Ch ramps (the transition to
// Ready to switch on / Switched on is taken when the ramp has ended: those option codes say
// "slow down, then disable the drive function"), Quick stop active during a quick stop,
// Fault reaction active during a fault reaction. Every Stop but None and DisableDrive waits
// (Immediate too: the caller stops the pulses, then calls motion_stopped()); a DisableDrive
// stop needs no waiting, its transitions complete in the call.
//
// While a transition waits, a command is read in the state the statusword shows; one that
// makes a transition from it replaces the waiting one (Disable voltage during a ramp cuts it
// short: transition 9 or 12), the same command again changes nothing, and Enable operation
// in Operation enabled cancels a waiting transition 5 or 8 (the last command wins).
class DriveStateMachine {
 public:
  DriveStateMachine() = default;
  explicit DriveStateMachine(const Options& options) : options_(options) {}
  void set_options(const Options& options) { options_ = options; }
  const Options& options() const { return options_; }

  // Transitions 0 and 1, both automatic: the drive (re)initialises into Not ready to switch
  // on, then enables communication: Switch on disabled. The error code is cleared; a fault
  // whose cause persists must be reported again (fault()). A new machine is in Not ready to
  // switch on, transition 0 taken.
  void power_on();

  // A controlword written by the master: decoded against the previous one (the fault reset
  // edge) and the state, then applied.
  Stop on_controlword(uint16_t controlword);
  // A command from the drive itself (6007h, an NMT state change): applied as if it came in
  // a controlword; the previous controlword stays the reference for the fault reset edge.
  Stop apply(Command command);
  // The ramp the last Stop asked for has ended: the waiting transition completes (nothing
  // waits: no effect).
  void motion_stopped();

  // A fault (transition 13: Fault reaction active, from every state but Fault reaction
  // active and Fault), with its 603Fh error code. In Operation enabled and Quick stop active
  // the motion stops per 605Eh and transition 14 waits for motion_stopped(); elsewhere
  // nothing moves and transition 14 follows at once. In Fault reaction active or Fault a new
  // fault only replaces the error code (603Fh holds the last error).
  Stop fault(uint16_t error_code);
  // Whether the cause of the fault persists. A fault reset (transition 15) while it does is
  // refused: the drive stays in Fault with its error code.
  void set_fault_condition_active(bool active) { fault_condition_ = active; }
  bool fault_condition_active() const { return fault_condition_; }

  // Halt (controlword bit 8) is mode-specific and the caller's; this is 605Dh's stop.
  Stop halt_stop() const { return cia402::halt_stop(options_.halt); }
  // The master is lost (heartbeat, bus off): 6007h's reaction. 1 is a fault with
  // `error_code`; 2 and 3 are the Disable voltage and Quick stop commands; another value acts
  // as 1.
  Stop abort_connection(int16_t option, uint16_t error_code = kConnectionLostError);

  State state() const { return state_; }
  // The number of the last transition taken (0 for a new machine). Transitions 3 + 4, 11 +
  // 12 and 13 + 14 taken in one call leave the second.
  int last_transition() const { return last_transition_; }
  bool powered() const { return cia402::powered(state_); }
  bool operation_enabled() const { return state_ == State::OperationEnabled && !waiting(); }
  // A ramp is running that motion_stopped() ends.
  bool stopping() const { return pending_.stop != Stop::None; }
  Stop pending_stop() const { return pending_.stop; }
  uint16_t statusword() const { return state_bits(state_); }  // bits 0-6 and 9
  uint16_t error_code() const { return error_code_; }         // 603Fh

 private:
  // A transition waiting for the end of a ramp; transition 0 = none (605Ah 5..8: the ramp
  // ends in Quick stop active).
  struct Pending {
    int transition = 0;
    State target = State::NotReadyToSwitchOn;
    Stop stop = Stop::None;
  };
  bool waiting() const { return pending_.stop != Stop::None; }
  void take(int transition, State target);
  Stop ramp_then(int transition, State target, Stop stop);
  Stop from_operation_enabled(Command command);
  Stop from_quick_stop_active(Command command);
  Stop quick_stop();

  Options options_;
  State state_ = State::NotReadyToSwitchOn;
  int last_transition_ = 0;
  Pending pending_;
  uint16_t previous_controlword_ = 0;
  uint16_t error_code_ = 0;
  bool fault_condition_ = false;
};

}  // namespace stepnode::cia402
