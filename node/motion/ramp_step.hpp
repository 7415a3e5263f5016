// Where in a ramp the next step falls, without a pass per velocity level (issue 13: ramps
// at Horner cost).
//
// In a ramp the level moves by one (dir = +1 up, -1 down) at the end of every interval, and
// the intervals are q or q + 1 ticks long: q + 1 where the interval cursor's remainder
// carries (ramp_intervals.hpp: rem grows by rho per interval and carries past den). Between
// two carries every interval is q long, so the phase of the first n of such a run, at the
// levels L + dir, ..., L + dir·n, is the closed form
//   P(n) = q·(n·L + dir·n(n+1)/2),
// and the interval in it that holds the step is the first n with P(n) >= the phase still to
// come: a quadratic. The walk therefore goes from carry to carry (one every den/rho
// intervals) and solves the run it ends in, instead of visiting each of the tens of levels
// a step spans on the grids the profiles choose. With q = 0 (Z < 1) a run of 0-long
// intervals follows each 1-long one instead: the walk goes from tick to tick, solved the
// same way (ramp_step.cpp). Every answer is the level-by-level walk's (the reference in
// the tests).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "node/motion/timebase.hpp"

namespace stepnode::motion {

// A ramp's interval lengths: q ticks, q + 1 where the remainder carries (IntervalCursor).
struct IntervalGrid {
  int64_t q = 0, rho = 0, den = 1;
  // The next interval's length given `rem`, the remainder after the one before (moved on
  // to the remainder after it): q, or q + 1 where it carries past den.
  Tick next_length(int64_t& rem) const {
    rem += rho;
    const bool carry = rem >= den;
    rem -= carry ? den : 0;
    return q + (carry ? 1 : 0);
  }
};

// Where the walk to the next step stands: at tick t, in an interval at `level` that ends at
// `end`, with `left` phase still to come before the step, `passed` level changes made and
// `rem` the cursor's remainder after this interval.
struct RampWalk {
  Tick t = 0, end = 0;
  int64_t level = 0, left = 0, passed = 0, rem = 0;
};

// Moves w into the interval in which the step falls (level * (end - t) >= left), at most
// `room` level changes on (where the ramp has its top or its end), w's own interval not
// holding it (the caller has looked). False if the step lies beyond that: w at the room's
// last interval, where the generator's own loop would be (walk_levels' answer; with
// intervals of 0 ticks, q = 0, several levels at one tick, a slope steeper than one level
// per tick: where the generator passes them, ramp_step.cpp: the walk from tick to tick
// solved as the ramp with the roles of ticks and levels swapped). Levels in a ramp are >= 1.
bool walk_to_step(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room);

// Moves w where the generator's advance_to(until) stops passing intervals: the first that
// holds the step or tick `until` (>= w.end, > w.t; w's own interval not holding the
// step), or the room's last (`room` level changes on, > 0), where the generator's own loop
// goes on.
void walk_until(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room, Tick until);

// sum_{i=0}^{n-1} floor((a·i + b)/m) for n >= 0, m > 0, a, b >= 0, a·n + b and the sum
// within T. Each round cuts the terms to the whole parts of a/m and b/m plus a remainder
// line whose lattice points are counted the other way round (the axes swapped), so n
// shrinks like the numbers in Euclid's algorithm.
template <typename T>
[[gnu::always_inline]] inline T floor_sum(T n, T m, T a, T b) {
  T sum = 0;
  for (;;) {
    if (a >= m) {
      sum += n * (n - 1) / 2 * (a / m);
      a %= m;
    }
    if (b >= m) {
      sum += n * (b / m);
      b %= m;
    }
    const T y = a * n + b;  // the line's height at i = n
    if (y < m) return sum;
    n = y / m;
    b = y % m;
    std::swap(m, a);
  }
}

// J(C) = sum_{i=1}^{C} j_i, j_i = ceil((i·den - rem)/rho): the intervals (counted from the
// walk's start) whose remainder carries, the i-th carry where rem + j·rho first reaches
// i·den. A few are added directly; more with the floor sum. Both inlined: solve_to_step
// calls them for every step, and a call costs as much as the few additions.
template <typename T>
[[gnu::always_inline]] inline T carry_positions(T count, T rho, T den, T rem) {
  const T first = den - rem + rho - 1;  // i·den - rem + rho - 1 at i = 1
  if (count > 8) return floor_sum<T>(count, rho, den, first);
  T sum = 0;
  for (T i = 0, num = first; i < count; ++i, num += den) sum += num / rho;
  return sum;
}

// Whether solve_to_step's 64-bit products are safe for a walk from `level` with `left` phase
// to come after its interval (below): every product below 2^62 with all four below 2^29,
// as on every grid the profiles make.
inline bool solves_in_64(int64_t left, int64_t level, const IntervalGrid& g) {
  return ((left | g.q | level | g.rho) >> 29) == 0;
}

// The real m of the continuous ramp (Z = z ticks per level) from `level` with `left` phase
// to come, in the form without cancellation: with b = 2L + dir and c = 2·left/z,
// m = 2c / (b + sqrt(b² + 4·dir·c)), in 1..room. The carries' levels move W (below) by less
// than a level.
[[gnu::always_inline]] inline int64_t root_guess(int64_t level, int64_t left, double z, int64_t dir,
                                                 int64_t room) {
  const double c = 2.0 * static_cast<double>(left) / z;
  const double b = static_cast<double>(2 * level + dir);
  const double disc = std::max(b * b + 4.0 * static_cast<double>(dir) * c, 0.0);
  return std::clamp<int64_t>(static_cast<int64_t>(2.0 * c / (b + std::sqrt(disc))) + 1, 1, room);
}

// The largest hint solve_to_step takes: larger spans come near rest, where they change fast
// from one step to the next (as 1/sqrt(k) at a ramp's k-th step) and the root guesses better.
constexpr int64_t kHintedMost = 64;

// walk_to_step for q >= 1 where solves_in_64(): `left` is the phase to come after w's
// interval (w.left less that interval's), `z` = q + rho/den as a double (the cursor keeps
// it), room >= 1. Inline where each ramp step asks it (StepGenerator::peek_solved): its
// set-up costs as much as the solve.
//
// The first guess is `hint` (1..kHintedMost, within left/q + 2), the levels the step
// before spanned: a ramp's consecutive steps span nearly as many, so one or two exact
// evaluations settle it. Else the real root of the continuous ramp; its square root and
// divisions are a chain of ~100 cycles, the hint's a division or two.
//
// Interval j = 1, 2, ... after w's runs at level L + dir·j for q + c_j ticks, c_j the carry
// of rem + j·rho past a multiple of den. Of the first m, C(m) = floor((rem + m·rho)/den)
// carry, so they last S(m) = q·m + C(m) ticks and add the phase
//   W(m) = q·(m·L + dir·m(m+1)/2) + C(m)·L + dir·J(C(m)).
// The step falls in the first interval m with W(m) >= left. m stays below left/q + 2 (each
// interval adds at least q), so every product is below (left + q + 1)·(L + left + 2) and
// m·rho below (left + 2)·rho.
[[gnu::always_inline]] inline bool solve_to_step(RampWalk& w, const IntervalGrid& g, double z,
                                                 int64_t dir, int64_t room, int64_t left,
                                                 int64_t hint = 0) {
  const int64_t q = g.q, rho = g.rho, den = g.den, level = w.level, rem = w.rem;
  int64_t m = hint > 0 && hint <= kHintedMost && hint * q <= left + 2 * q
                  ? std::min(hint, room)
                  : root_guess(level, left, z, dir, room);
  int64_t carries = (rem + (m - 1) * rho) / den;  // C(m - 1)
  int64_t before = q * ((m - 1) * level + dir * ((m - 1) * m / 2)) + carries * level +
                   dir * carry_positions<int64_t>(carries, rho, den, rem);  // W(m - 1)
  // One interval at a time to the first m with W(m - 1) < left <= W(m).
  for (;;) {
    if (m > 1 && before >= left) [[unlikely]] {  // the step is in an earlier interval
      const int64_t earlier = (rem + (m - 2) * rho) / den;
      --m;
      before -= (level + dir * m) * (q + carries - earlier);
      carries = earlier;
      continue;
    }
    const int64_t through = (rem + m * rho) / den;  // C(m)
    const Tick len = q + through - carries;
    const int64_t after = before + (level + dir * m) * len;
    if (after >= left || m >= room) [[likely]] {  // the step's interval, or the room's last
      w.t = w.end + q * (m - 1) + carries;
      w.end = w.t + len;
      w.level = level + dir * m;
      w.left = left - before;
      w.passed += m;
      w.rem = rem + m * rho - through * den;
      return after >= left;
    }
    before = after;
    carries = through;
    ++m;
  }
}

// The reference: the same walk one level at a time (0-long intervals pass, adding no phase).
bool walk_levels(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room);

}  // namespace stepnode::motion
