// How far a ramp's interval ends stray from the straight line (issue 13: the bounded batch,
// StepGenerator::bounded_batch). With Z = q + rho/den ticks per level, the ends of the
// intervals after the current one fall at
//   E_j = E_0 + j·q + floor((rem + j·rho)/den),   j = 0, 1, 2, ...
// and the phase a ramp adds up to a tick sums them. Their floors differ from the straight
// line (rem + j·rho)/den by the residues r_j = (rem + j·rho) mod den; over a period of the
// residues (P = den/g intervals, g = gcd(rho, den)) those sum to P times their mean
//   mu = (rem mod g) + (den - g)/2,
// and the partial sums wander from J·mu by a bounded amount: the spread. Writing
// r_j = (rem mod g) + g·s_j, the s_j run through (s_0 + j·rho/g) mod P, every one of them
// (s_0 + J) rho/g's for some start, so with T(k) the sum of (i·rho/g mod P) - (P - 1)/2
// over i < k (periodic, T(P) = 0), every partial sum is T(k0 + J) - T(k0): within
// max T - min T. Divided by den that is a phase, in level-ticks:
//   |sum_{j<J} r_j - J·mu| / den <= (max T - min T) / P.
#pragma once
#include <cstdint>

namespace stepnode::motion {

struct CarrySpread {
  int64_t rho = -1, den = 0;  // the grid it is for (rho -1: none yet)
  int64_t g = 1;              // gcd(rho, den)
  double phase = -1;          // the bound above; < 0: the period is too long to count
};

// The longest period counted: its cost is a few additions an interval, once per grid and
// generator (16,384 intervals: ~250,000 instructions, ~25 us, in the peek after a ramp's
// first step), where a longer one would hold up that step's peek more; such grids keep the
// walk. A CiA 402 slope's period is accel·levels-per-Hz over its common factor with
// kClockHz = 2^16·3·5^2 (100,000 steps/s^2 on 1 level per Hz: 125).
constexpr int64_t kSpreadPeriodMost = 16384;

// The spread of the grid's residues (rho >= 0, den > 0), counted over one period.
CarrySpread carry_spread(int64_t rho, int64_t den);

}  // namespace stepnode::motion
