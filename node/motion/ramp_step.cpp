// The walk of ramp_step.hpp: from carry to carry, each run of q-long intervals solved.
#include "node/motion/ramp_step.hpp"

#include <algorithm>
#include <cmath>

namespace stepnode::motion {

namespace {

// P(n) = q·(n·L + dir·n(n+1)/2): the phase of the first n intervals of a run after level
// L, in 128 bits: the callers keep q·n within one step's phase, so q·n·(L + n) < 2^126.
__int128 run_phase(int64_t q, int64_t level, int64_t dir, int64_t n) {
  const __int128 wide = n;
  return q * (wide * level + dir * (wide * (wide + 1) / 2));
}

// The first n in 1..most with P(n) >= left, given P(most) >= left (P grows with n: every
// level in a ramp is >= 1), and P(n - 1) in `before`. The real root of P(x) = left guesses
// it, in the form without cancellation: with b = 2L + dir and c = 2·left/q,
// x = 2c / (b + sqrt(b² + 4·dir·c)). The guess is off by a level at most where the double
// rounds; the exact P settles it.
int64_t first_reaching(int64_t q, int64_t level, int64_t dir, int64_t most, int64_t left,
                       __int128& before) {
  const double c = 2.0 * static_cast<double>(left) / static_cast<double>(q);
  const double b = static_cast<double>(2 * level + dir);
  const double disc = std::max(b * b + 4.0 * static_cast<double>(dir) * c, 0.0);
  int64_t n =
      std::clamp<int64_t>(static_cast<int64_t>(2.0 * c / (b + std::sqrt(disc))) + 1, 1, most);
  before = run_phase(q, level, dir, n - 1);
  while (n > 1 && before >= left) before = run_phase(q, level, dir, --n - 1);
  for (__int128 at; (at = run_phase(q, level, dir, n)) < left; ++n) before = at;
  return n;
}

// The walk from carry to carry, one run of q-long intervals solved at a time, in 128 bits:
// walk_to_step's answer where its 64-bit products could overflow.
bool walk_runs(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room, int64_t phase) {
  const int64_t q = g.q;
  for (;;) {
    w.left -= phase;
    w.t = w.end;
    // The q-long intervals before the next carry (rem + j·rho < den), no further than the
    // room, nor past left/q + 1 of them: each adds at least q (levels >= 1), so the step
    // is among those, and the products stay bounded.
    int64_t run = room - w.passed;
    if (g.rho > 0) run = std::min(run, (g.den - 1 - w.rem) / g.rho);
    run = std::min(run, w.left / q + 1);
    if (run > 0) {
      const __int128 all = run_phase(q, w.level, dir, run);
      if (all >= w.left) {
        __int128 before = 0;
        const int64_t n = first_reaching(q, w.level, dir, run, w.left, before);
        w.left -= static_cast<int64_t>(before);
        w.t += q * (n - 1);
        w.end = w.t + q;
        w.level += dir * n;
        w.passed += n;
        w.rem += n * g.rho;
        return true;
      }
      w.left -= static_cast<int64_t>(all);
      w.t += q * run;
      w.level += dir * run;
      w.passed += run;
      w.rem += run * g.rho;
    }
    if (w.passed >= room) return false;
    // The carry's interval, q + 1 ticks.
    w.level += dir;
    ++w.passed;
    w.rem += g.rho - g.den;
    w.end = w.t + q + 1;
    phase = w.level * (q + 1);
    if (phase >= w.left) return true;
  }
}

// sum_{i=0}^{n-1} floor((a·i + b)/m) for n >= 0, m > 0, a, b >= 0, a·n + b below 2^62.
// Each round cuts the terms to the whole parts of a/m and b/m plus a remainder line whose
// lattice points are counted the other way round (the axes swapped), so n shrinks like
// the numbers in Euclid's algorithm.
int64_t floor_sum(int64_t n, int64_t m, int64_t a, int64_t b) {
  int64_t sum = 0;
  for (;;) {
    if (a >= m) {
      sum += n * (n - 1) / 2 * (a / m);
      a %= m;
    }
    if (b >= m) {
      sum += n * (b / m);
      b %= m;
    }
    const int64_t y = a * n + b;  // the line's height at i = n
    if (y < m) return sum;
    n = y / m;
    b = y % m;
    std::swap(m, a);
  }
}

// J(C) = sum_{i=1}^{C} j_i, j_i = ceil((i·den - rem)/rho): the intervals (counted from the
// walk's start) whose remainder carries, the i-th carry where rem + j·rho first reaches
// i·den. A few are added directly; more with the floor sum.
int64_t carry_positions(int64_t count, const IntervalGrid& g, int64_t rem) {
  const int64_t first = g.den - rem + g.rho - 1;  // i·den - rem + rho - 1 at i = 1
  if (count > 8) return floor_sum(count, g.rho, g.den, first);
  int64_t sum = 0;
  for (int64_t i = 0, num = first; i < count; ++i, num += g.den) sum += num / g.rho;
  return sum;
}

}  // namespace

bool walk_to_step(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room) {
  const int64_t q = g.q, rho = g.rho, den = g.den, level = w.level, rem = w.rem;
  if (q == 0 || room <= 0) return false;
  const int64_t phase = level * (w.end - w.t);
  const int64_t left = w.left - phase;  // after this interval
  // Interval j = 1, 2, ... after this one runs at level L + dir·j for q + c_j ticks, c_j
  // the carry of rem + j·rho past a multiple of den. Of the first m, C(m) =
  // floor((rem + m·rho)/den) carry, so they last S(m) = q·m + C(m) ticks and add the phase
  //   W(m) = q·(m·L + dir·m(m+1)/2) + C(m)·L + dir·J(C(m)).
  // The step falls in the first interval m with W(m) >= left. In 64 bits: m stays below
  // left/q + 2 (each interval adds at least q), so every product here is below
  // (left + q + 1)·(L + left + 2) and m·rho below (left + 2)·rho: under 2^62 with all four
  // below 2^29, as on every grid the profiles make; else the doubles decide, and beyond
  // them the walk from carry to carry in 128 bits.
  if (((left | q | level | rho) >> 29) != 0) {
    const double ld = static_cast<double>(left), qd = static_cast<double>(q);
    const double most = ld / qd + 2.0;
    if ((ld + qd + 1.0) * (static_cast<double>(level) + most) >= 0x1p62 ||
        most * static_cast<double>(rho) >= 0x1p61)
      return walk_runs(w, g, dir, room, phase);
  }
  // The real m of the continuous ramp (Z = q + rho/den ticks per level) guesses it, in the
  // form without cancellation: with b = 2L + dir and c = 2·left/Z,
  // m = 2c / (b + sqrt(b² + 4·dir·c)). The carries' levels move W by less than a level.
  const double z = static_cast<double>(q) + static_cast<double>(rho) / static_cast<double>(den);
  const double c = 2.0 * static_cast<double>(left) / z;
  const double b = static_cast<double>(2 * level + dir);
  const double disc = std::max(b * b + 4.0 * static_cast<double>(dir) * c, 0.0);
  int64_t m =
      std::clamp<int64_t>(static_cast<int64_t>(2.0 * c / (b + std::sqrt(disc))) + 1, 1, room);
  int64_t carries = (rem + (m - 1) * rho) / den;  // C(m - 1)
  int64_t before = q * ((m - 1) * level + dir * ((m - 1) * m / 2)) + carries * level +
                   dir * carry_positions(carries, g, rem);  // W(m - 1)
  // One interval at a time to the first m with W(m - 1) < left <= W(m).
  for (;;) {
    if (m > 1 && before >= left) {  // the step is in an earlier interval
      const int64_t earlier = (rem + (m - 2) * rho) / den;
      --m;
      before -= (level + dir * m) * (q + carries - earlier);
      carries = earlier;
      continue;
    }
    const int64_t through = (rem + m * rho) / den;  // C(m)
    const Tick len = q + through - carries;
    const int64_t after = before + (level + dir * m) * len;
    if (after >= left) {
      w.t += w.end - w.t + q * (m - 1) + carries;
      w.end = w.t + len;
      w.level = level + dir * m;
      w.left = left - before;
      w.passed += m;
      w.rem = rem + m * rho - through * den;
      return true;
    }
    if (m >= room) return false;
    before = after;
    carries = through;
    ++m;
  }
}

bool walk_levels(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room) {
  for (int64_t phase; (phase = w.level * (w.end - w.t)) < w.left;) {
    if (w.passed >= room) return false;
    w.left -= phase;
    w.t = w.end;
    w.level += dir;
    ++w.passed;
    w.rem += g.rho;
    const bool carry = w.rem >= g.den;
    w.rem -= carry ? g.den : 0;
    const Tick len = g.q + (carry ? 1 : 0);
    if (len == 0) return false;
    w.end = w.t + len;
  }
  return true;
}

}  // namespace stepnode::motion
