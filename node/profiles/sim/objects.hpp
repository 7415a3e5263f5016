// The simulated machine's objects (0x5000-0x57FF per motor, 0x5F00 shared): its switches,
// encoder and faults as settings, its mechanical position and inputs as readings. Pure
// table; node/profiles/sim/service.cpp connects it to the simulated machine (node/sim).
#pragma once
#include <cstdint>

#include "od/dictionary.hpp"

namespace stepnode::sim {

// The simulated machine: 0x5000 + 0x100 * axis.
namespace obj {
constexpr uint16_t kSwitches = 0x00;            // RECORD positions/widths of home, limits, index
constexpr uint16_t kEncoder = 0x01;             // RECORD steps/rev, lines, marker
constexpr uint16_t kFaults = 0x02;              // RECORD stall, missed steps, displacement
constexpr uint16_t kMechanicalPosition = 0x03;  // I32 ro
constexpr uint16_t kInputs = 0x04;  // U8 ro: bit0 home, 1 lower, 2 upper, 3 index, 4 marker
inline uint16_t index(unsigned axis, uint16_t offset) {
  return static_cast<uint16_t>(0x5000 + 0x100 * axis + offset);
}
constexpr uint16_t kEmergencyStop = 0x5F00;  // U8 rw: 1 = e-stop input active
}  // namespace obj
namespace switches_sub {
constexpr uint8_t kHomePosition = 1, kHomeWidth = 2, kLowerLimitEnabled = 3, kLowerLimit = 4,
                  kUpperLimitEnabled = 5, kUpperLimit = 6, kIndexPosition = 7, kIndexWidth = 8;
}
namespace encoder_sub {
constexpr uint8_t kStepsPerRev = 1, kLines = 2, kMarkerOffset = 3, kMarkerWidth = 4;
}
namespace faults_sub {
constexpr uint8_t kStallBelowEnabled = 1, kStallBelow = 2, kStallAboveEnabled = 3, kStallAbove = 4,
                  kMissEvery = 5, kDisplace = 6, kMoveEvery = 7;
}

// The objects of `motors` simulated motors and the shared e-stop input.
void add_objects(od::Dictionary& od, unsigned motors);

}  // namespace stepnode::sim
