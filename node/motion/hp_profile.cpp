#include "node/motion/hp_profile.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace stepnode::motion::hp {

Conflict check_profile(const Profile& p) {
  const bool freq = p.mode == ProfileMode::Freq;
  const double top = freq ? kMaxPulseRateHz : kMaxWidthS;
  const double top_slope = freq ? kMaxSlopeHzPerS : kMaxWidthSlope;
  if (!(p.min >= 0 && p.max >= 0 && p.slope >= 0 && p.last >= 0) || p.min > top || p.max > top ||
      p.slope > top_slope)
    return Conflict::OutOfRange;
  if (freq ? (p.last < kTimeResolutionS || p.last > kMaxWidthS) : (p.last <= 0 || p.last > kMaxWidthS))
    return Conflict::OutOfRange;
  if (p.min > p.max) return Conflict::MinAboveMax;
  if (p.min == 0 && p.max == 0 && p.slope == 0) return Conflict::AllZero;
  if (p.min == 0 && p.slope == 0) return Conflict::MinZeroSlopeZero;
  if (p.slope == 0 && p.min < p.max) return Conflict::SlopeZeroRangeUnattainable;
  if (freq) {
    // "pwidth larger than period of max frequency"
    if (p.max > 0 && p.last > 1.0 / p.max) return Conflict::WidthVersusPeriod;
  } else if (p.last < p.max) {
    return Conflict::WidthVersusPeriod;  // "period < max width"
  }
  return Conflict::None;
}

int64_t levels_per_hz(double slope) {
  constexpr int64_t kFinest = int64_t{1} << 16;
  if (slope <= 0) return kFinest;
  // ticks per level = kClockHz / (slope * L) must be >= 1; at least 64 keeps the cost of a
  // ramp (one engine interval per level) near that of the steps themselves.
  double most = static_cast<double>(kClockHz) / (slope * 64);
  if (most >= static_cast<double>(kFinest)) return kFinest;
  return std::max<int64_t>(1, static_cast<int64_t>(std::bit_floor(static_cast<uint64_t>(most))));
}

RampSpec freq_ramp(const Profile& p, double run_hz) {
  const int64_t per_hz = levels_per_hz(p.slope);
  RampSpec r;
  r.phase_per_step = kClockHz * per_hz;
  r.base_level = std::llround(p.min * static_cast<double>(per_hz));
  r.run_level = std::max<int64_t>(r.base_level, std::llround(run_hz * static_cast<double>(per_hz)));
  if (p.slope > 0) {
    // ticks per level = kClockHz / (slope * L), kept as a fraction with the slope in uHz/s.
    int64_t slope_uhz = std::max<int64_t>(1, std::llround(p.slope * 1e6));
    r.accel_ticks_per_level = Rational{kClockHz * 1'000'000, slope_uhz * per_hz};
  } else {
    r.accel_ticks_per_level = Rational{1, 1};  // unused: min == max
  }
  r.decel_ticks_per_level = r.accel_ticks_per_level;
  int64_t one_step = std::llround(std::sqrt(2.0 * p.slope) * static_cast<double>(per_hz));
  r.min_creep_level = std::max<int64_t>({int64_t{1}, r.base_level, one_step});
  r.horner_triangle_rule = false;
  return r;
}

RampSpec constant_rate(double hz) {
  constexpr int64_t kPerHz = 1024;
  RampSpec r;
  r.phase_per_step = kClockHz * kPerHz;
  r.base_level = r.run_level = std::max<int64_t>(1, std::llround(hz * static_cast<double>(kPerHz)));
  r.min_creep_level = r.base_level;
  r.accel_ticks_per_level = r.decel_ticks_per_level = Rational{1, 1};
  return r;
}

double clamp_to_profile(const Profile& p, double magnitude) { return std::clamp(magnitude, p.min, p.max); }

}  // namespace stepnode::motion::hp
