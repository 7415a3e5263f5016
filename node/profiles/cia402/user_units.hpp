// CiA 402's factor group (608Fh position encoder resolution, 6091h gear ratio, 6092h feed
// constant): user position units <-> the drive's internal increments, which here are motor
// steps. increments per unit = (608Fh:1 / 608Fh:2) * (6091h:1 / 6091h:2) / (6092h:1 / 6092h:2);
// velocities (per s) and accelerations (per s^2) use the same factor. Pure.
#pragma once
#include <cstdint>
#include <numeric>

namespace stepnode::cia402 {

class UserUnits {
 public:
  UserUnits() = default;
  // All six terms >= 1 (the objects refuse 0).
  UserUnits(uint32_t increments, uint32_t motor_revs, uint32_t gear_motor, uint32_t gear_shaft,
            uint32_t feed, uint32_t feed_shaft) {
    __int128 n = static_cast<__int128>(increments) * gear_motor * feed_shaft;
    __int128 d = static_cast<__int128>(motor_revs) * gear_shaft * feed;
    // Reduced, so the common 1:1 case (and ratios of small numbers) stay exact integers.
    while (n > INT64_MAX || d > INT64_MAX) n = (n + 1) / 2, d = (d + 1) / 2;
    const int64_t g = std::gcd(static_cast<int64_t>(n), static_cast<int64_t>(d));
    steps_ = static_cast<int64_t>(n) / g;
    units_ = static_cast<int64_t>(d) / g;
  }
  // Rounded to the nearest step (half away from zero).
  int64_t to_steps(int64_t units) const {
    return div_round(static_cast<__int128>(units) * steps_, units_);
  }
  int64_t to_units(int64_t steps) const {
    return div_round(static_cast<__int128>(steps) * units_, steps_);
  }
  int64_t steps_per() const { return steps_; }
  int64_t units_per() const { return units_; }

 private:
  static int64_t div_round(__int128 n, int64_t d) {
    const __int128 half = d / 2;
    return static_cast<int64_t>(n >= 0 ? (n + half) / d : -((-n + half) / d));
  }
  int64_t steps_ = 1, units_ = 1;  // steps_ steps are units_ user units
};

}  // namespace stepnode::cia402
