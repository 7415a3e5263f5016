// The S-curve's integer scale and its conversions to doubles (node/motion/s_curve.hpp):
// positions are kept as S p with S = 6 T^3, velocities (slopes per tick) as 6 T^2 v.
#pragma once
#include <cstdint>

#include "node/motion/timebase.hpp"

namespace stepnode::motion::scurve {

inline constexpr __int128 kS = static_cast<__int128>(6) * kClockHz * kClockHz * kClockHz;
inline constexpr double kSd = static_cast<double>(kS);
inline constexpr double kV = 6.0 * static_cast<double>(kClockHz) * static_cast<double>(kClockHz);

// An estimate of a large integer in a double without the library's exact conversion
// (|x| < 2^95 here: positions and velocities of the scale S).
inline double approx(__int128 x) {
  return static_cast<double>(static_cast<int64_t>(x >> 32)) * 4294967296.0 +
         static_cast<double>(static_cast<uint32_t>(x));
}

// Exactly static_cast<double>(x) (one rounding), without the library's conversion when x
// fits in 64 bits.
inline double to_double(__int128 x) {
  const auto low = static_cast<int64_t>(x);
  return low == x ? static_cast<double>(low) : static_cast<double>(x);
}

}  // namespace stepnode::motion::scurve
