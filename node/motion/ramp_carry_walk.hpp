// A ramp step found from the span of the step before, the interval cursor's carries walked
// with additions (issue 13: ramps at Horner cost). solve_to_step (ramp_step.hpp) finds the
// carries among the intervals up to its guess with divisions, every step afresh; a batch of
// steps solved one after another (StepGenerator::solve_batch) keeps the next carry instead
// and passes it on, so a step on a grid whose carries are a few intervals apart or more
// costs a handful of multiplications and a short walk, and no division but its tick's.
//
// The carries follow the dual Bresenham: the remainder after a carry, r < rho, grows by
// rho an interval and carries again on the first j with r + j·rho >= den; with den =
// Qd·rho + rd that is Qd intervals on where r >= rd, else Qd + 1, leaving r - rd, or
// r - rd + rho.
#pragma once
#include <cstdint>

#include "node/motion/ramp_step.hpp"

namespace stepnode::motion {

// A grid's interval lengths (q, q + 1 at a carry) with its carries' spacing.
struct CarryGrid {
  int64_t q = 0, rho = 0, qd = 0, rd = 0;
  explicit CarryGrid(const IntervalGrid& g)
      : q(g.q), rho(g.rho), qd(g.rho > 0 ? g.den / g.rho : 0), rd(g.rho > 0 ? g.den % g.rho : 0) {}
};

// The next interval whose remainder carries: `at` intervals after the walk's current one,
// leaving the remainder `rem` (it reached rem + den there). after() makes one; on a grid
// without carries (rho = 0, every remainder 0) it stays out of reach, its `rem` -den (so
// that remainder_before() is 0).
struct NextCarry {
  static constexpr int64_t kNone = INT64_MAX / 4;
  int64_t at = kNone, rem = 0;

  // From `rem`, the remainder after the current interval (one division, where a step is
  // solved otherwise and the walk takes over again).
  static NextCarry after(const IntervalGrid& g, int64_t rem) {
    if (g.rho == 0) return {kNone, -g.den};
    const int64_t at = (g.den - rem + g.rho - 1) / g.rho;
    return {at, rem + at * g.rho - g.den};
  }
  // On to the carry after this one.
  void pass(const CarryGrid& g) {
    const bool longer = rem < g.rd;
    at += g.qd + (longer ? 1 : 0);
    rem += (longer ? g.rho : 0) - g.rd;
  }
  // Back to the carry before this one (pass() undone: a longer gap left rem at rho - rd or
  // above, a shorter one below).
  void unpass(const CarryGrid& g) {
    const bool longer = rem >= g.rho - g.rd;
    at -= g.qd + (longer ? 1 : 0);
    rem -= (longer ? g.rho : 0) - g.rd;
  }
};

// How far walk_from_guess walks past its guess before it leaves the step to solve_to_step:
// a guess that far off (a ramp's first steps, whose spans change fast) is cheaper solved.
constexpr int64_t kWalkedPastGuess = 4;

// The remainder after the walk's current interval, from its next carry: no interval
// between them carries, so it is the carry's remainder before the carry took den off,
// less rho for each interval up to it.
inline int64_t remainder_before(const NextCarry& c, const IntervalGrid& g) {
  return c.rem + g.den - c.at * g.rho;
}

// The interval that holds the step, as walk_to_step finds it (ramp_step.hpp: `left` the
// phase to come after w's interval, intervals 1, 2, ... after it at levels L + Dir·j, q
// long or q + 1 at a carry), found from interval `guess` (>= 1, the span of the step
// before: a ramp's next step spans as many, or one fewer or more): the phase of the
// intervals before it in closed form, q·(n·L + Dir·n(n+1)/2) and each carry's level, then
// one interval down or a few up. True with w in the step's interval (all but its
// remainder, which remainder_before() finds from `c`) and `c` its next carry. False where
// the step is further from the guess, or beyond `room`: w and c unchanged, the caller
// solves it otherwise. The products stay within solve_to_step's bounds (solves_in_64 and
// the room).
template <int Dir>
[[gnu::always_inline]] inline bool walk_from_guess(RampWalk& w, NextCarry& c, const CarryGrid& g,
                                                   int64_t room, int64_t left, int64_t guess) {
  const int64_t q = g.q, level = w.level;
  int64_t j = std::min(guess, room), n = j - 1, carries = 0;
  // n·L + Dir·n(n+1)/2 = n·(2L + Dir·(n + 1))/2, its numerator even
  int64_t before = q * ((n * (2 * level + Dir * (n + 1))) >> 1);
  NextCarry k = c;  // the next carry after n
  for (; k.at <= n; ++carries) {
    before += level + Dir * k.at;
    k.pass(g);
  }
  if (before >= left) {  // the step is in an earlier interval: one down, or solved
    if (n < 1) return false;
    NextCarry below = k;  // the carry before k, if interval n is one
    if (carries > 0) below.unpass(g);
    const bool carry = carries > 0 && below.at == n;
    before -= (level + Dir * n) * (q + (carry ? 1 : 0));
    if (before >= left) return false;
    --j;
    if (carry) k = below, --carries;
  }
  for (const int64_t last = std::min(room, j + kWalkedPastGuess);; ++j) {
    const bool carry = j == k.at;
    const int64_t len = q + (carry ? 1 : 0);
    const int64_t phase = (level + Dir * j) * len;
    if (before + phase >= left) {
      w.t = w.end + q * (j - 1) + carries;
      w.end = w.t + len;
      w.level = level + Dir * j;
      w.left = left - before;
      w.passed += j;
      if (carry) k.pass(g);
      c = {k.at - j, k.rem};
      return true;
    }
    if (j >= last) return false;
    before += phase;
    if (carry) k.pass(g), ++carries;
  }
}

}  // namespace stepnode::motion
