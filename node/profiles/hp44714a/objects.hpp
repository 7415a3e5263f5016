// The HP 44714A channel objects of each axis (0x2n10-0x2n1F, next to the Horner registers
// 0x2n00-0x2n0A of node/profiles/horner), the simulated terminal-module inputs (0x5n05) and
// the default mapping of TPDO 4n+4. Pure table: node/profiles/hp44714a/service.cpp connects them to
// the channels. Commands are writes: a write that the channel refuses is answered with an SDO
// abort, and the channel's error number / conflict code stays readable.
#pragma once
#include <cstdint>

#include "od/dictionary.hpp"

namespace stepnode::hp44714a {

namespace obj {
constexpr uint16_t kProfile =
    0x10;                           // RECORD: PROFILE FREQ|WIDTH min max slope pwidth|period, apply
constexpr uint16_t kPscale = 0x11;  // REAL64 rw, stored: units per step
constexpr uint16_t kMove = 0x12;    // RECORD: 1 MOVE d REL, 2 MOVE d ABS, 3 NOWAIT
constexpr uint16_t kSustain = 0x13;     // REAL64: SUSTAIN velocity (units/s) or width (s)
constexpr uint16_t kTrig = 0x14;        // U8: TRIG 0 HOLD, 1 AUTO, 2 SGL, 3 SYS, 4 CHAN0
constexpr uint16_t kDelay = 0x15;       // U16 ms, stored
constexpr uint16_t kOutput = 0x16;      // RECORD: STANDBY and PULSE, STBY level, pulse counts
constexpr uint16_t kLimits = 0x17;      // RECORD: HARDLIM senses, HALT mode, HALT SGL
constexpr uint16_t kDone = 0x18;        // I8 ro: DONE? -3..+2
constexpr uint16_t kError = 0x19;       // U8 ro: last HP error number 89..94, 0 none
constexpr uint16_t kConflict = 0x1A;    // U8 ro: last PROFILE settings conflict (table row)
constexpr uint16_t kPosition = 0x1B;    // REAL64: write POS, read POS?
constexpr uint16_t kQuadrature = 0x1C;  // RECORD: QSCALE, QINDEX, QPOS?, raw count
constexpr uint16_t kInterrupt = 0x1D;   // RECORD: ENABLE/DISABLE INTR, event word
constexpr uint16_t kTiming = 0x1E;      // RECORD: trigger and first-step times (node clock)
constexpr uint16_t kTest = 0x1F;  // RECORD: TEST (write 1), result (0 pass, 1 fail), failed checks
inline uint16_t index(unsigned axis, uint16_t offset) {
  return static_cast<uint16_t>(0x2000 + 0x100 * axis + offset);
}
constexpr uint16_t kSimInputs =
    0x05;  // 0x5n05 RECORD: HALT input level, TEST jumper, last pulse width
inline uint16_t sim_index(unsigned axis) {
  return static_cast<uint16_t>(0x5000 + 0x100 * axis + kSimInputs);
}
}  // namespace obj

namespace profile_sub {
constexpr uint8_t kMode = 1, kMin = 2, kMax = 3, kSlope = 4, kLast = 5, kApply = 6,
                  kGivenAtPscale = 7;
}
namespace move_sub {
constexpr uint8_t kRelative = 1, kAbsolute = 2, kNowait = 3;
}
namespace output_sub {
constexpr uint8_t kStandbyMode = 1, kStandbySense = 2, kPulseMode = 3, kPstpSense = 4,
                  kNdirSense = 5, kStbyLevel = 6, kMotorPowered = 7, kPstpPulses = 8,
                  kNdirPulses = 9, kPulseWidth = 10;
}
namespace limits_sub {
constexpr uint8_t kPlimSense = 1, kNlimSense = 2, kHaltMode = 3, kHaltSgl = 4;
}
namespace quad_sub {
constexpr uint8_t kQscale = 1, kQindex = 2, kQpos = 3, kCount = 4;
}
namespace intr_sub {
constexpr uint8_t kEnable = 1, kEvents = 2;
}
namespace timing_sub {
constexpr uint8_t kTriggerUs = 1, kFirstStepUs = 2, kFirstStepAfterTriggerUs = 3;
}
namespace test_sub {
constexpr uint8_t kRun = 1, kResult = 2, kFailedChecks = 3;
}
namespace sim_sub {
constexpr uint8_t kHaltInputHigh = 1, kTestJumper = 2, kLastPulseWidthNs = 3;
}

// EMCY codes (manufacturer-specific): an HP error number n is 0xFF00 + n (0xFF59..0xFF5E);
// an interrupt for a hard limit, HALT SGL or the HALT switch is 0xFF43 / 0xFF44 / 0xFF45.
constexpr uint16_t kErrorEmcyBase = 0xFF00;
constexpr uint16_t kInterruptEmcyBase = 0xFF40;
// The manual's words for those codes ("HP error 91 MUST STOP TO CHANGE DIRECTION"), or
// nullptr for a code that is not the channels'.
const char* emcy_text(uint16_t code);

// The channel objects of `axes` axes and the default mapping of their TPDO 4n+4 (the PDO
// objects must exist).
void add_objects(od::Dictionary& od, unsigned axes);

}  // namespace stepnode::hp44714a
