// CiA 402 homing mode (CiA 402-2 / IEC 61800-7-201 "Homing mode", 6098h homing methods):
// each method as the sequence of searches a drive performs, in the order of the standard's
// figures. A search runs in one direction at one of the two 6099h speeds until an input
// event; then the drive ramps down and starts the next search, goes straight on into the
// next one, or has found the home position (it stops there at once: the approach runs at
// the slow speed). Pure: the drive (drive.hpp) carries the searches out on the motion core.
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

namespace stepnode::cia402 {

// The inputs homing looks at, as 60FDh names them, and the index pulse (the encoder marker).
struct HomingInputs {
  bool negative_limit = false;
  bool positive_limit = false;
  bool home = false;
  bool index = false;
};

enum class HomingEvent : uint8_t {
  NegativeLimitOn,
  NegativeLimitOff,
  PositiveLimitOn,
  PositiveLimitOff,
  HomeOn,
  HomeOff,
  IndexOn,  // the rising edge of the index pulse
  // A hard stop (a block): the load no longer follows the steps. Not an input: the drive
  // detects it with the encoder (drive_homing.cpp), so happened() never reports it.
  Block,
};

// Whether `event` happened between two samples of the inputs (after a step).
bool happened(HomingEvent event, const HomingInputs& before, const HomingInputs& after);

struct HomingSearch {
  enum class Then : uint8_t {
    Stop,      // ramp down (6099h:1 speed, 609Ah), then the next search from where it stopped
    Continue,  // the next search at once, in the same motion (same direction and speed)
    Home,      // the home position: stop on this step
  };
  int direction = +1;  // +1 positive, -1 negative
  bool fast = true;    // 6099h:1 "speed during search for switch", else :2 "for zero"
  HomingEvent until = HomingEvent::HomeOn;
  Then then = Then::Home;
  // The limit switch in the direction of travel, reached before `until`, reverses the
  // search once (ramp down, then the same search the other way): methods 7..14 and 23..30,
  // whose first search may lead away from the home switch. Otherwise it ends the homing
  // with an error.
  bool reverse_at_limit = false;
};

// The searches of `method` for a drive whose home switch is `home_active` at the start
// (methods 3..6 and 19..22 begin differently on either side of the switch). Empty: the
// current position is the home position (35, 37). Nullopt: a method not performed: this
// drive performs 1, 2 (limit switch and index pulse), 3..6 (home switch and index pulse),
// 7..14 (a home switch between the limit switches, reversing at them, and the index pulse),
// 17, 18 (limit switch), 19..22 (home switch), 23..30 (as 7..14 without the index pulse),
// 33, 34 (index pulse), 35 and 37; and stepnode's manufacturer-specific methods on a hard
// stop (CiA 402 leaves -128..-1 to the manufacturer), numbered as the limit-switch methods
// whose switch the hard stop replaces: -17 / -18 the hard stop in the negative / positive
// direction, -1 / -2 the same and then the first index pulse away from it.
std::optional<std::vector<HomingSearch>> homing_plan(int8_t method, bool home_active);

}  // namespace stepnode::cia402
