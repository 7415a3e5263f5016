#include "node/motion/ramp.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace stepnode::motion {
namespace {

// sum(base+1 .. level) = (level-base)(level+base+1)/2
__int128 level_sum(int64_t base, int64_t level) {
  if (level <= base) return 0;
  return static_cast<__int128>(level - base) * (level + base + 1) / 2;
}

__int128 ramp_phase(Rational z, int64_t base, int64_t level) {
  // Z may be fractional (num/den); the phase of interval lengths is within one tick per
  // interval of this, which the generator tracks exactly as it runs.
  return level_sum(base, level) * z.num / z.den;
}

void check(int64_t value, int64_t low, int64_t high, const char* name) {
  if (value < low || value > high)
    throw std::invalid_argument(std::string(name) + " = " + std::to_string(value) + " is outside " +
                                std::to_string(low) + ".." + std::to_string(high));
}

}  // namespace

__int128 RampSpec::accel_phase(int64_t level) const {
  return ramp_phase(accel_ticks_per_level, base_level, level);
}

__int128 RampSpec::decel_phase(int64_t level) const {
  return ramp_phase(decel_ticks_per_level, base_level, level);
}

int64_t RampSpec::peak_level_for(int64_t distance) const {
  const __int128 total = static_cast<__int128>(distance) * phase_per_step;
  if (short_move == ShortMove::Meet) return run_level;
  if (short_move == ShortMove::Halfway) {
    // The highest level whose ramp up and ramp down together fit the move (both grow with
    // the level): the move turns on it, having cruised less than one level's pulses.
    if (accel_phase(run_level) + decel_phase(run_level) <= total) return run_level;
    int64_t fits = base_level, too_high = run_level;
    while (too_high - fits > 1) {
      int64_t mid = fits + (too_high - fits) / 2;
      (accel_phase(mid) + decel_phase(mid) <= total ? fits : too_high) = mid;
    }
    return fits;
  }
  // STPCALC B1.3.8: the move is triangular when Pulse_A + Pulse_D > total; the peak is
  // base + R_T * (run - base) (B1.3.6 with Time_A scaled by R_T), R_T = total/(A+D).
  __int128 both = accel_phase(run_level) + decel_phase(run_level);  // in phase units
  if (total >= both) return run_level;
  int64_t rise = static_cast<int64_t>(total * (run_level - base_level) / both);
  return base_level + rise;
}

RampSpec frequency_ramp(int64_t min_hz, int64_t max_hz, int64_t slope_mhz_per_s) {
  if (min_hz < 0 || max_hz < 1 || min_hz > max_hz || slope_mhz_per_s <= 0)
    throw std::invalid_argument(
        "frequency ramp needs 0 <= min <= max, max >= 1 Hz and a slope > 0");
  RampSpec r;
  r.phase_per_step = kClockHz * kLevelsPerHz;
  r.base_level = min_hz * kLevelsPerHz;
  r.run_level = max_hz * kLevelsPerHz;
  // ticks per level = kClockHz / (slope_hz * kLevelsPerHz) = kClockHz * 1000 / (slope_mhz * 64)
  r.accel_ticks_per_level = Rational{kClockHz * 1000, slope_mhz_per_s * kLevelsPerHz};
  r.decel_ticks_per_level = r.accel_ticks_per_level;
  return r;
}

int64_t profile_levels_per_hz(int64_t steepest) {
  const int64_t fine = kClockHz / (64 * std::max<int64_t>(steepest, 1));
  return std::clamp<int64_t>(fine, 1, 64);
}

RampSpec profile_ramp(int64_t velocity, int64_t accel, int64_t decel, int64_t levels_per_hz) {
  if (velocity < 1 || accel < 1 || decel < 1 || levels_per_hz < 1)
    throw std::invalid_argument(
        "a profile ramp needs a velocity, acceleration and deceleration > 0");
  RampSpec r;
  r.phase_per_step = kClockHz * levels_per_hz;
  r.base_level = 0;  // from and to standstill
  r.run_level = velocity * levels_per_hz;
  r.accel_ticks_per_level = slope_ticks_per_level(accel, levels_per_hz);
  r.decel_ticks_per_level = slope_ticks_per_level(decel, levels_per_hz);
  // The last step a ramp down leaves over goes at the velocity one step from standstill
  // reaches (sqrt(2 * decel)), never faster than the run velocity.
  const auto one_step = static_cast<int64_t>(std::llround(
      std::sqrt(2.0 * static_cast<double>(decel)) * static_cast<double>(levels_per_hz)));
  r.min_creep_level = std::clamp<int64_t>(one_step, 1, r.run_level);
  return r;
}

bool fit_deceleration(RampSpec& ramp, int64_t level, int64_t steps) {
  const __int128 room = static_cast<__int128>(steps - 1) * ramp.phase_per_step;
  if (ramp.decel_phase(level) <= room) return true;
  const __int128 per_tick = level_sum(ramp.base_level, level);  // the phase of Z = 1
  const __int128 z = per_tick > 0 && room > 0 ? room / per_tick : 0;
  if (z < 1) return false;
  ramp.decel_ticks_per_level = Rational{static_cast<int64_t>(z), 1};
  return true;
}

int64_t horner_max_ramp_ms(int64_t aq4, int64_t aq5) {
  int64_t max_useful = (aq5 - aq4) * 10 / 3;  // (AQ5-AQ4)/0.3
  return max_useful < 27300 ? max_useful : 27300;
}

int64_t horner_z(int64_t ms, int64_t aq4, int64_t aq5) {
  int64_t num = ms * 24576, den = (aq5 - aq4) * 5;
  return (num + den - 1) / den;  // rounded up (B1.3.1)
}

RampSpec horner_ramp(int64_t aq3, int64_t aq4, int64_t aq5, int64_t aq6, int64_t aq7) {
  check(aq3, 20, 65535, "velocity resolution %AQ3");
  check(aq4, 1, 8190, "base velocity %AQ4");
  check(aq5, aq4 + 1, 8191, "running velocity %AQ5 (must exceed the base velocity)");
  // SPM30 3.4 table: 1..27300 and 0..27,300 are the registers' ranges; (AQ5-AQ4)/0.3 is only
  // the "maximum useful value" (3.4.5, 3.4.6): a longer time ramps no longer than it does.
  check(aq6, 1, 27300, "acceleration time %AQ6 (ms)");
  check(aq7, 0, 27300, "deceleration time %AQ7 (ms)");
  if (aq7 == 0) aq7 = aq6;  // SPM30 3.4.6: 0 means "same as acceleration"
  auto z = [&](int64_t ms) { return Rational{std::min(horner_z(ms, aq4, aq5), kHornerMaxZ), 1}; };
  RampSpec r;
  r.phase_per_step = 8192 * aq3;  // one level = 600/AQ3 steps/s = level/(8192*AQ3) per tick
  r.base_level = aq4;
  r.run_level = aq5;
  r.accel_ticks_per_level = z(aq6);
  r.decel_ticks_per_level = z(aq7);
  r.short_move = RampSpec::ShortMove::Halfway;  // SPM30 3.4.5 (StpcalcPeak is the axis' option)
  return r;
}

}  // namespace stepnode::motion
