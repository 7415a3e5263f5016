// The HP 44714A channel's settings, codes and numbers as the manual names them (HP 3852A
// HP 44714A Configuration and Programming Manual, chapter 3). Power-on values are those of
// "Power-On/Reset State" (3-2).
#pragma once
#include <cstdint>

namespace stepnode::motion::hp {

// DONE? codes ("Asking For the Status of a Move", 3-19).
enum class Done : int8_t {
  WaitingForTrigger = -3,
  Running = -2,
  SustainRunning = -1,  // SUSTAIN at its velocity (or width): ready for the next command
  Completed = 0,
  Halted = 1,
  HardLimit = 2,
};

// Error numbers ("Error Message Summary", 3-3). 0 = the last command was accepted.
enum class Error : uint8_t {
  None = 0,
  AccessoryBusy = 89,
  NoActionDefined = 90,
  MustStopToChangeDirection = 91,
  NotValidInWidthMode = 92,
  TestJumperSet = 93,
  CannotMoveWhileStandbyOn = 94,
  // Not an HP error number: a value outside appendix A's specifications (a SUSTAIN rate
  // finer than the 2.5 µHz resolution). The command is refused and nothing changes; on the
  // bus it is the SDO range abort, and 0x2n19 keeps the last HP error.
  ValueOutOfRange = 255,
};

// Which row of the PROFILE settings-conflict tables (3-9 FREQ, 3-26 WIDTH) a PROFILE hit.
// OutOfRange: outside the module's specifications (appendix A), not a table row.
// ModeVersusWaitingCommand: not a table row either; a PROFILE of the other mode while a
// MOVE or SUSTAIN waits for its trigger (Channel::profile says why).
enum class Conflict : uint8_t {
  None = 0,
  SlopeZeroRangeUnattainable = 1,  // "slope = 0; min-to-max ... range unattainable"
  MinZeroSlopeZero = 2,            // "min = 0; slope = 0; no pulses can be generated"
  AllZero = 3,                     // "min = max = slope = 0; no pulses ...", any slope
  WidthVersusPeriod = 4,           // FREQ: pwidth > period of max; WIDTH: period < max width
  MinAboveMax = 5,                 // "min > max"
  OutOfRange = 6,
  ModeVersusWaitingCommand = 7,
};

enum class ProfileMode : uint8_t { Freq = 0, Width = 1 };
enum class TrigMode : uint8_t { Hold = 0, Auto = 1, Sgl = 2, Sys = 3, Chan0 = 4 };
enum class StandbyMode : uint8_t { Off = 0, On = 1, Auto = 2 };
enum class PulseMode : uint8_t { StepDirection = 0, StepStep = 1 };  // SD / SS
enum class HaltMode : uint8_t { Lo = 0, Hi = 1, Off = 2 };           // sense of HALTn, or ignored
enum class QIndexMode : uint8_t { Off = 0, Once = 1, Sgl = 2 };

// The five interrupt conditions ("Selecting Interrupts", 3-16), as bits of the event word.
namespace intr {
constexpr uint8_t kMoveDone = 1u << 0;        // 1. pulses stop following a MOVE
constexpr uint8_t kSustainReached = 1u << 1;  // 2. SUSTAIN frequency or width reached
constexpr uint8_t kHardLimit = 1u << 2;       // 3. a hard limit stopped pulses
constexpr uint8_t kHaltSgl = 1u << 3;         // 4. HALT SGL stopped pulses
constexpr uint8_t kHaltSwitch = 1u << 4;      // 5. the HALT switch stopped pulses
}  // namespace intr

struct Profile {
  ProfileMode mode = ProfileMode::Freq;
  // FREQ: Hz, Hz, Hz/s, pulse width s. WIDTH: s, s, s/s, period s.
  double min = 0, max = 250, slope = 500, last = 50e-6;
};

// The module's limits (appendix A "HP 44714A Specifications").
constexpr double kMaxPulseRateHz = 10'000;
constexpr double kMaxSlopeHzPerS = 1'000'000;
constexpr double kMaxWidthS = 65.535e-3;
constexpr double kMaxWidthSlope = 1.0;  // s/s
// Resolutions of the rates of change: a slope above 0 but finer than these is out of range.
constexpr double kSlopeResolutionHzPerS = 25e-3;
constexpr double kWidthSlopeResolution = 1e-6;  // s/s
constexpr double kTimeResolutionS = 1e-6;
// "Pulse Rate ... Resolution 2.5 µHz": a rate above 0 but finer is out of range (a SUSTAIN
// of 1E-12 overflowed the engine's phase arithmetic). And 10 kHz at most: a WIDTH period
// under 100 µs is out of range too.
constexpr double kRateResolutionHz = 2.5e-6;
constexpr double kMinPeriodS = 1.0 / kMaxPulseRateHz;
// The longest move the engine's tick clock (int64 at 4.9152 MHz) holds, with margin: 2^60 ticks.
constexpr double kLongestMoveS = 1.152921504606846976e18 / 4.9152e6;
constexpr uint16_t kMaxDelayMs = 65'535;  // DELAY 0.000..65.535 s in 1 ms steps (3-14)

}  // namespace stepnode::motion::hp
