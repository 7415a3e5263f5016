// PROFILE FREQ / PROFILE WIDTH: the settings-conflict rules (manual 3-9, 3-26) and the
// continuous-slope ramp a FREQ profile gives the pulse engine.
#pragma once
#include <cstdint>

#include "node/motion/hp_settings.hpp"
#include "node/motion/ramp.hpp"

namespace stepnode::motion::hp {

// The conflict a PROFILE would cause, or Conflict::None.
Conflict check_profile(const Profile& p);

// Velocity levels per Hz the ramp of a FREQ profile uses: as fine as this slope allows with
// one level change every 64 ticks (13 us) or slower, capped at 2^16 (15 uHz). The pulse rate
// of a constant-velocity stretch is exact to 1/levels Hz (200 Hz/s: 1/256 Hz).
int64_t levels_per_hz(double slope_hz_per_s);

// The engine's ramp for a FREQ profile: base = min, run = `run_hz` (max for a MOVE, the
// SUSTAIN velocity for SUSTAIN), slope in Hz/s both ways. With min = 0 the last step of a
// ramp-down that the accumulator left over goes at the velocity one step from standstill
// reaches (sqrt(2 * slope)), not at 0 Hz.
RampSpec freq_ramp(const Profile& p, double run_hz);
// A constant rate (WIDTH profile: 1/period) as a ramp without ramps.
RampSpec constant_rate(double hz);

// SUSTAIN: a requested velocity (or width) clamped into [min, max] (3-12 NOTE).
double clamp_to_profile(const Profile& p, double magnitude);

}  // namespace stepnode::motion::hp
