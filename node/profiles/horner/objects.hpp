// The Horner profile's objects: the register set of each axis (0x2000-0x27FF, one block of
// 0x100 per axis: SPM30 chapter 3, STP100 chapter 4) and their default PDOs (the first
// three RPDOs and TPDOs of each axis). Pure table, shared by the node, stepctl and the
// bridge; node/profiles/horner/service.cpp connects the objects to the axes.
#pragma once
#include <cstdint>

#include "od/dictionary.hpp"

namespace stepnode::horner {

// Index of an axis object: 0x2000 + 0x100 * axis + offset.
namespace obj {
constexpr uint16_t kCommandBits = 0x00;      // U16 rw, %Q1..%Q16
constexpr uint16_t kStatusBits = 0x01;       // U16 ro, %I1..%I16
constexpr uint16_t kDestination = 0x02;      // I32 rw, %AQ1/2
constexpr uint16_t kProfile = 0x03;          // RECORD %AQ3..%AQ7
constexpr uint16_t kIndexedMove = 0x04;      // RECORD %AQ8..%AQ14
constexpr uint16_t kMotorPosition = 0x05;    // I32 ro, %AI1/2
constexpr uint16_t kEncoderPosition = 0x06;  // I32 ro, %AI3/4
constexpr uint16_t kVelocity = 0x07;         // I32 ro, steps/s (signed)
constexpr uint16_t kMotionPhase = 0x08;      // U8 ro: 0 idle, 1 acc, 2 run, 3 dec, 4 base
constexpr uint16_t kConfiguration = 0x09;    // RECORD: encoder, homing, options
constexpr uint16_t kDirOutput = 0x0A;        // BOOLEAN ro: DIR+ level
inline uint16_t index(unsigned axis, uint16_t offset) {
  return static_cast<uint16_t>(0x2000 + 0x100 * axis + offset);
}
}  // namespace obj

// Sub-indices of the records.
namespace profile_sub {
constexpr uint8_t kVelocityDivisor = 1, kBaseVelocity = 2, kRunningVelocity = 3, kAcceleration = 4,
                  kDeceleration = 5;
}
namespace indexed_sub {
constexpr uint8_t kDestination = 1, kDeceleration = 2, kWindowOpen = 3, kWindowClose = 4;
}
namespace config_sub {
constexpr uint8_t kEncoderType = 1, kMultiplier = 2, kDivisor = 3, kTolerance = 4,
                  kStallDetection = 5, kHomeMethod = 6, kOriginSource = 7, kLimitQualified = 8,
                  kLimitStartedMoves = 9, kIndexedMoves = 10, kModuleModel = 11,
                  kQuadratureDecoding = 12, kStpcalcPeakShortMoves = 13, kDirectionSetup = 14;
}

// The axis' PDOs: RPDO/TPDO numbers 4a+1..4a+4 (0x1400/0x1800 + 4a + k). The fourth TPDO
// is the HP channel's (node/profiles/hp44714a).
constexpr unsigned kPdosPerAxis = 4;

// The register objects of `axes` axes, and the default mappings of their PDOs (the PDO
// objects must exist).
void add_objects(od::Dictionary& od, unsigned axes);

}  // namespace stepnode::horner
