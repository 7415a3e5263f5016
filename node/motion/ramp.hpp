// How a move's velocity changes, in one description for every front end. Velocity is an
// integer "level"; a level adds `level` phase units per clock tick and one step is
// `phase_per_step` phase units, so velocity = level * kClockHz / phase_per_step steps/s.
// Ramps change the level by one every `ticks_per_level` ticks (a rational number, so a
// continuous slope in Hz/s is as exact as the Horner module's integer Z_A).
#pragma once
#include <cstdint>
#include <string>

#include "node/motion/timebase.hpp"

namespace stepnode::motion {

struct Rational {
  int64_t num = 0;
  int64_t den = 1;
};

struct RampSpec {
  int64_t phase_per_step = 1;      // D
  int64_t base_level = 1;          // start/stop velocity
  int64_t run_level = 2;           // cruise velocity
  Rational accel_ticks_per_level;  // Z_A
  Rational decel_ticks_per_level;  // Z_D
  // The highest level a move of `distance` steps may reach: the run level, or with
  // ShortMove::StpcalcPeak STPCALC's peak velocity for triangular moves (B1.3.6).
  int64_t peak_level_for(int64_t distance) const;

  double velocity_of(int64_t level) const {
    return static_cast<double>(level) * kClockHz / static_cast<double>(phase_per_step);
  }
  // Exact pulses (times phase_per_step) spent going from base to `level` or back:
  // Z * sum(base+1 .. level).
  __int128 accel_phase(int64_t level) const;
  __int128 decel_phase(int64_t level) const;

  // How a move too short to reach the run level turns. Meet: after the step at which the
  // deceleration the rest of the move needs begins (the profile ramps). Halfway: the peak is
  // the highest level whose ramps up and down fit the move, so the ramps meet on it; with
  // equal ramps that is "halfway to its relative target position" (SPM30 3.4.5, 4 MOVE;
  // STP100 1.7, 5.3.4). (A literal halfway with AQ7 < AQ6 would keep trapezoidal moves of
  // STPCALC B1.3 from their running velocity: the acceleration may need more than half the
  // pulses.) StpcalcPeak: accelerate to STPCALC's peak velocity (B1.3.6) and cruise there
  // until the deceleration point (an option: STPCALC's figures, not the module's motion).
  enum class ShortMove : uint8_t { Meet, Halfway, StpcalcPeak };
  ShortMove short_move = ShortMove::Meet;
  // The slowest level a move creeps at when a ramp ends short of its target (the phase
  // accumulator may leave a step over). 1 keeps a 0 Hz base moving; the HP channel, whose
  // minimum may be 0 Hz, sets the velocity one step from standstill reaches.
  int64_t min_creep_level = 1;
  // CiA 402 6086h = 3: a jerk-limited profile (node/motion/s_curve.hpp) with the velocity
  // and slopes above and these jerks in steps/s^3 (60A4h:1..4: begin acceleration, begin
  // deceleration, end acceleration, end deceleration; 0: not limited).
  bool s_curve = false;
  uint32_t jerk[4] = {0, 0, 0, 0};
};

// Shortens `ramp`'s deceleration, in whole ticks per level as the module's Z, so that the
// ramp from `level` down to the base level fits in `steps` steps (one step kept for the phase
// accumulator's remainder): for an end point moved closer than the deceleration ramp (an
// indexed move's index). Unchanged if it already fits; false if not even one tick per level
// fits (fewer than two steps left), the ramp unchanged.
bool fit_deceleration(RampSpec& ramp, int64_t level, int64_t steps);

// The Horner module's ramp from %AQ3..%AQ7 (SPM30 3.4, STPCALC B1.3.1):
// D = 8192*AQ3, Z_A = ceil(AQ6*24576 / ((AQ5-AQ4)*5)), Z_D the same with AQ7 (0 = AQ6).
// Throws std::invalid_argument naming the register and its legal range.
RampSpec horner_ramp(int64_t aq3, int64_t aq4, int64_t aq5, int64_t aq6, int64_t aq7);

// A continuous-slope ramp given in Hz and Hz/s (HP 44714A PROFILE FREQ): velocity levels of
// 1/kLevelsPerHz Hz, one level every kClockHz / (slope * kLevelsPerHz) ticks (a rational
// number, so the slope is exact on average). slope_mhz_per_s is the slope in mHz/s.
constexpr int64_t kLevelsPerHz = 64;
RampSpec frequency_ramp(int64_t min_hz, int64_t max_hz, int64_t slope_mhz_per_s);

// A ramp from standstill to `velocity` steps/s, accelerating at `accel` and decelerating at
// `decel` steps/s^2 (CiA 402 6081h/6083h/6084h), on the grid `levels_per_hz` levels per
// step/s (profile_levels_per_hz): every whole velocity is a level, so a velocity mode holds
// any target exactly, and the slopes are exact rationals. All arguments > 0.
RampSpec profile_ramp(int64_t velocity, int64_t accel, int64_t decel, int64_t levels_per_hz);
// The finest grid whose level changes stay at least 64 ticks (13 us) apart at `steepest`
// steps/s^2 (their cost near that of the steps), 1..64 levels per step/s.
int64_t profile_levels_per_hz(int64_t steepest);
// Ticks per level of a slope of `accel` steps/s^2 on a grid of `levels_per_hz`.
inline Rational slope_ticks_per_level(int64_t accel, int64_t levels_per_hz) {
  return Rational{kClockHz, accel * levels_per_hz};
}

// Largest useful acceleration/deceleration time (SPM30 3.4.5): (AQ5-AQ4)/0.3 ms, capped at
// 27300; beyond it Z would exceed 16384, the longest interval the module's ramp takes per
// velocity level: a longer AQ6/AQ7 is legal and ramps in the maximum useful time.
int64_t horner_max_ramp_ms(int64_t aq4, int64_t aq5);
constexpr int64_t kHornerMaxZ = 16384;
// STPCALC's Z for a ramp time (B1.3.1, rounded up), without the module's limit.
int64_t horner_z(int64_t ms, int64_t aq4, int64_t aq5);

}  // namespace stepnode::motion
