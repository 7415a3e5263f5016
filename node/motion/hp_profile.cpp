#include "node/motion/hp_profile.hpp"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>

namespace stepnode::motion::hp {

Conflict check_profile(const Profile& p) {
  const bool freq = p.mode == ProfileMode::Freq;
  const double top = freq ? kMaxPulseRateHz : kMaxWidthS;
  const double top_slope = freq ? kMaxSlopeHzPerS : kMaxWidthSlope;
  const double finest_slope = freq ? kSlopeResolutionHzPerS : kWidthSlopeResolution;
  if (!(p.min >= 0 && p.max >= 0 && p.slope >= 0 && p.last >= 0) || p.min > top || p.max > top ||
      p.slope > top_slope || (p.slope > 0 && p.slope < finest_slope))
    return Conflict::OutOfRange;
  // Appendix A: a FREQ pulse width of 1 us..65.535 ms; a WIDTH period of 100 us (10 kHz)
  // up to the slowest rate the 2.5 uHz resolution gives (a period is not a width: 100 ms is
  // a 10 Hz pulse train).
  if (freq ? (p.last < kTimeResolutionS || p.last > kMaxWidthS)
           : (p.last < kMinPeriodS || p.last * kRateResolutionHz > 1.0 + 1e-9))
    return Conflict::OutOfRange;
  // Above 0, nothing finer than the resolutions: 2.5 uHz for rates, 1 us for widths.
  const double resolution = freq ? kRateResolutionHz : kTimeResolutionS;
  auto finer_than_resolution = [&](double v) { return v > 0 && v < resolution; };
  if (finer_than_resolution(p.min) || finer_than_resolution(p.max)) return Conflict::OutOfRange;
  if (p.min > p.max) return Conflict::MinAboveMax;
  // Rows 2 and 3 are conflicts because "no pulses can be generated". With min = max = 0 none
  // can whatever the slope: "You cannot operate at a frequency less than min or greater
  // than max" (3-8), and a width of 0 is no pulse. Row 3, whose reason it is (a MOVE under
  // PROFILE FREQ 0 0 500 never sent a pulse and never ended).
  if (p.min == 0 && p.max == 0) return Conflict::AllZero;
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

double level_resolution_hz(double slope) {
  // A ramp changes the level once per interval of kClockHz * resolution / slope ticks; at
  // least 64 ticks (13 us) keeps its cost near that of the steps. Never finer than 2^-16 Hz.
  return std::max(64.0 * slope / static_cast<double>(kClockHz), 1.0 / 65536.0);
}

RampSpec freq_ramp(const Profile& p, double run_hz) {
  RampSpec r;
  run_hz = std::max(run_hz, p.min);
  // The run rate is exact: the level size is run_hz divided by a whole number of levels
  // (no coarser than level_resolution_hz), and phase_per_step = kClockHz / level size,
  // rounded to an integer (relative error <= 0.5 / phase_per_step: < 2e-7 at 100 kHz/s,
  // < 2e-6 at the module's 1 MHz/s). The minimum and later
  // SUSTAIN velocities are within half a level of what was asked.
  const double fine = level_resolution_hz(p.slope);
  const double target = run_hz > 0 ? run_hz : std::max(p.max, 1.0);
  // Of the level counts near the finest, the one whose phase_per_step is nearest an integer.
  // A rate only a few levels above 0 (a steep slope) may use up to 8x finer levels (one
  // change per 8 ticks at least): its ramp is short, and its rate needs the choice.
  const int64_t most = std::max<int64_t>(1, static_cast<int64_t>(std::floor(target / fine)));
  const int64_t top = most < 256 ? most * 8 : most;
  int64_t run_levels = most;
  double best = 1.0;
  for (int64_t n = top; n >= std::max<int64_t>(1, most - 255); --n) {
    double d = static_cast<double>(kClockHz) * static_cast<double>(n) / target;
    double off = std::fabs(d - std::round(d)) / d;
    if (off < best) best = off, run_levels = n;
  }
  r.phase_per_step =
      std::llround(static_cast<double>(kClockHz) * static_cast<double>(run_levels) / target);
  const double per_hz =
      static_cast<double>(r.phase_per_step) / static_cast<double>(kClockHz);  // levels per Hz
  r.run_level = run_hz > 0 ? run_levels : 0;
  r.base_level = std::min<int64_t>(r.run_level, std::llround(p.min * per_hz));
  if (p.slope > 0) {
    // ticks per level = kClockHz / (slope * levels per Hz), in 1/4096 ticks (the slope to a
    // few ppm; small terms keep the engine's k * num products far from overflow).
    double ticks = static_cast<double>(kClockHz) / (p.slope * per_hz);
    r.accel_ticks_per_level = Rational{std::max<int64_t>(4096, std::llround(ticks * 4096)), 4096};
  } else {
    r.accel_ticks_per_level = Rational{1, 1};  // unused: min == max
  }
  r.decel_ticks_per_level = r.accel_ticks_per_level;
  int64_t one_step = std::llround(std::sqrt(2.0 * p.slope) * per_hz);
  // ... but never faster than the run rate: PROFILE FREQ 10 10 500 crept at 31.6 Hz.
  r.min_creep_level = std::min(std::max<int64_t>({int64_t{1}, r.base_level, one_step}),
                               std::max<int64_t>(1, r.run_level));
  r.short_move = RampSpec::ShortMove::Meet;
  // The engine's invariants (checked in the sanitizer build): every rate the PROFILE and
  // SUSTAIN checks accept gives a positive step size far from int64 overflow.
  assert(r.phase_per_step > 0 && r.phase_per_step < (int64_t{1} << 52));
  assert(r.base_level >= 0 && r.base_level <= r.run_level + 1 && r.min_creep_level >= 1);
  assert(r.min_creep_level <= std::max<int64_t>(1, r.run_level));
  return r;
}

int64_t level_of(const RampSpec& r, double hz) {
  return std::llround(hz * static_cast<double>(r.phase_per_step) / static_cast<double>(kClockHz));
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

double clamp_to_profile(const Profile& p, double magnitude) {
  return std::clamp(magnitude, p.min, p.max);
}

}  // namespace stepnode::motion::hp
