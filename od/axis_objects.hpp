// The manufacturer objects of the axes (0x2000-0x27FF, one block of 0x100 per axis) and of
// the simulated machine (0x5000-0x57FF per axis, 0x5F00 shared), with their default PDO
// mappings. Pure table: node/motion_service.cpp connects them to the axes.
#pragma once
#include <cstdint>

#include "od/device_dictionary.hpp"
#include "od/dictionary.hpp"

namespace stepnode::od {

// Index of an axis object: 0x2000 + 0x100 * axis + offset.
namespace axis_obj {
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
}  // namespace axis_obj

// Sub-indices of the records.
namespace profile_sub {
constexpr uint8_t kVelocityDivisor = 1, kBaseVelocity = 2, kRunningVelocity = 3,
                  kAcceleration = 4, kDeceleration = 5;
}
namespace indexed_sub {
constexpr uint8_t kDestination = 1, kDeceleration = 2, kWindowOpen = 3, kWindowClose = 4;
}
namespace config_sub {
constexpr uint8_t kEncoderType = 1, kMultiplier = 2, kDivisor = 3, kTolerance = 4,
                  kStallDetection = 5, kHomeMethod = 6, kOriginSource = 7, kLimitQualified = 8,
                  kLimitStartedMoves = 9, kIndexedMoves = 10;
}

// The simulated machine: 0x5000 + 0x100 * axis.
namespace sim_obj {
constexpr uint16_t kSwitches = 0x00;   // RECORD positions/widths of home, limits, index
constexpr uint16_t kEncoder = 0x01;    // RECORD steps/rev, lines, marker
constexpr uint16_t kFaults = 0x02;     // RECORD stall, missed steps, displacement
constexpr uint16_t kMechanicalPosition = 0x03;  // I32 ro
constexpr uint16_t kInputs = 0x04;     // U8 ro: bit0 home, 1 lower, 2 upper, 3 index, 4 marker
inline uint16_t index(unsigned axis, uint16_t offset) {
  return static_cast<uint16_t>(0x5000 + 0x100 * axis + offset);
}
constexpr uint16_t kEmergencyStop = 0x5F00;  // U8 rw: 1 = e-stop input active
}  // namespace sim_obj
namespace switches_sub {
constexpr uint8_t kHomePosition = 1, kHomeWidth = 2, kLowerLimitEnabled = 3, kLowerLimit = 4,
                  kUpperLimitEnabled = 5, kUpperLimit = 6, kIndexPosition = 7, kIndexWidth = 8;
}
namespace encoder_sub {
constexpr uint8_t kStepsPerRev = 1, kLines = 2, kMarkerOffset = 3, kMarkerWidth = 4;
}
namespace faults_sub {
constexpr uint8_t kStallBelowEnabled = 1, kStallBelow = 2, kStallAboveEnabled = 3, kStallAbove = 4,
                  kMissEvery = 5, kDisplace = 6;
}

void add_axis_objects(Dictionary& dictionary, const DeviceInfo& info);

}  // namespace stepnode::od
