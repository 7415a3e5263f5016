// PROFILE FREQ / PROFILE WIDTH: the settings-conflict rules (manual 3-9, 3-26) and the
// continuous-slope ramp a FREQ profile gives the pulse engine.
#pragma once
#include <cstdint>

#include "node/motion/hp_settings.hpp"
#include "node/motion/ramp.hpp"

namespace stepnode::motion::hp {

// The conflict a PROFILE would cause, or Conflict::None.
Conflict check_profile(const Profile& p);

// The finest level size (Hz) a ramp of this slope may use: one level change every 64 ticks
// (13 us) or slower, and never below 2^-16 Hz.
double level_resolution_hz(double slope_hz_per_s);

// The engine's ramp for a FREQ profile: base = min, run = `run_hz` (max for a MOVE, the
// SUSTAIN velocity for SUSTAIN), slope in Hz/s both ways. With min = 0 the last step of a
// ramp-down that the accumulator left over goes at the velocity one step from standstill
// reaches (sqrt(2 * slope)), not at 0 Hz.
// `run_hz` is exact to 0.5 / phase_per_step relative; the level size is at most
// level_resolution_hz.
RampSpec freq_ramp(const Profile& p, double run_hz);
// The level of `hz` in a ramp from freq_ramp (SUSTAIN to a new velocity while running).
int64_t level_of(const RampSpec& ramp, double hz);
// A constant rate (WIDTH profile: 1/period) as a ramp without ramps.
RampSpec constant_rate(double hz);

// SUSTAIN: a requested velocity (or width) clamped into [min, max] (3-12 NOTE).
double clamp_to_profile(const Profile& p, double magnitude);

}  // namespace stepnode::motion::hp
