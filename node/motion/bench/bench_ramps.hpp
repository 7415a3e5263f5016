// The continuous-slope ramps the ramp benches share (ramp_cost_bench's kinds hp, cia402 and
// slow, and ramp_solve_floor_bench's), so their figures are for the same ramps.
#pragma once
#include "node/motion/hp_profile.hpp"
#include "node/motion/ramp.hpp"

namespace stepnode::motion::bench {

// HP 44714A PROFILE FREQ 0 10000 100000 (Hz, Hz/s).
inline RampSpec hp_ramp() {
  hp::Profile p;
  p.min = 0, p.max = 10'000, p.slope = 100'000, p.last = 50e-6;
  return hp::freq_ramp(p, p.max);
}

// CiA 402 PP: 6081h 10,000 steps/s, 6083h = 6084h 100,000 steps/s^2.
inline RampSpec cia402_ramp() {
  return profile_ramp(10'000, 100'000, 100'000, profile_levels_per_hz(100'000));
}

// CiA 402 PP at 1,000 steps/s^2 to 1,000 steps/s (the finest grid, 64 levels per step/s).
inline RampSpec slow_ramp() {
  return profile_ramp(1'000, 1'000, 1'000, profile_levels_per_hz(1'000));
}

}  // namespace stepnode::motion::bench
