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
    if (w.passed >= room) return false;  // w at the room's last interval
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
      // The room ends in the run: w at its last interval, which holds no step.
      const int64_t to = w.passed + run >= room ? run - 1 : run;
      w.left -= static_cast<int64_t>(to == run ? all : run_phase(q, w.level, dir, to));
      w.t += q * to;
      w.level += dir * run;
      w.passed += run;
      w.rem += run * g.rho;
      if (to < run) {
        w.end = w.t + q;
        return false;
      }
    }
    // The carry's interval, q + 1 ticks.
    w.level += dir;
    ++w.passed;
    w.rem += g.rho - g.den;
    w.end = w.t + q + 1;
    phase = w.level * (q + 1);
    if (phase >= w.left) return true;
  }
}

// The steep walk (q = 0: several levels at one tick) in T: int64_t where the bounds below
// fit, else __int128. With the roles of ticks and levels swapped, tick i (1, 2, ...) after
// the walk's interval is the interval of the i-th carry, j_i = ceil((i·den - rem)/rho),
// at level L + dir·j_i; the 0-long intervals between carries add no phase. With den =
// Q'·rho + rho' the level rises by Q' or Q' + 1 per tick (the dual Bresenham), and the
// first m ticks add
//   V(m) = m·L + dir·J(m),  J(m) = sum_{i=1}^{m} j_i = Q'·m(m+1)/2 + sum ceil((i·rho' - rem)/rho),
// W(m)'s shape with one carry per tick: J is the floor sum of walk_to_step's carries.
template <typename T>
class SteepWalk {
 public:
  SteepWalk(const RampWalk& w, const IntervalGrid& g, int64_t dir)
      : level_(w.level), rem_(w.rem), rho_(g.rho), den_(g.den), dir_(dir) {}

  // The interval (counted from the walk's) of tick i >= 1.
  T interval_of(T i) const { return (i * den_ - rem_ + rho_ - 1) / rho_; }
  // The level of tick i.
  T level_of(T i) const { return level_ + dir_ * interval_of(i); }
  // V(m): the phase of the first m ticks.
  T phase_of(T m) const { return m * level_ + dir_ * carry_positions<T>(m, rho_, den_, rem_); }

  // Settles `m` (a guess in 1..most) to the first tick with V(m) >= left, `before` =
  // V(m - 1); false (m = most) if V(most) < left, `before` = V(most - 1) then.
  bool settle(int64_t& m, int64_t most, T left, T& before) const {
    before = phase_of(m - 1);
    while (m > 1 && before >= left) before -= level_of(--m);
    for (T here; before + (here = level_of(m)) < left; ++m) {
      if (m >= most) return false;
      before += here;
    }
    return true;
  }

 private:
  T level_, rem_, rho_, den_;
  int64_t dir_;
};

// The ticks the room holds, C(room) = floor((rem + room·rho)/den), and the remainder after
// the room's last interval.
struct RoomEnd {
  int64_t ticks = 0, rem = 0;
};
RoomEnd room_end(const IntervalGrid& g, int64_t rem, int64_t room) {
  int64_t at = 0;
  if (!__builtin_mul_overflow(room, g.rho, &at) && !__builtin_add_overflow(at, rem, &at))
    return {at / g.den, at % g.den};
  const __int128 wide = static_cast<__int128>(room) * g.rho + rem;
  return {static_cast<int64_t>(wide / g.den), static_cast<int64_t>(wide % g.den)};
}

// The first tick whose level reaches the phase `left`: the real root of the continuous
// V(x) = x·B + dir·x²·den/(2·rho), B = L + dir·(1/2 - rem/rho + den/(2·rho)) (each j_i's
// ceiling taken as its mean, +1/2), in the form without cancellation
// x = 2·left / (B + sqrt(B² + 2·dir·left·den/rho)), rounded up, in 1..most. The ceilings'
// deviations from 1/2 stay within a few levels, so the guess is within a tick or two
// (fewer the higher the levels).
// Inlined: the steep walk asks it for every step.
[[gnu::always_inline]] inline int64_t guess_tick(const RampWalk& w, const IntervalGrid& g,
                                                 int64_t dir, int64_t left, int64_t most) {
  const double zi = static_cast<double>(g.den) / static_cast<double>(g.rho);  // levels per tick
  const double b = static_cast<double>(w.level) +
                   static_cast<double>(dir) *
                       (0.5 - static_cast<double>(w.rem) / static_cast<double>(g.rho) + zi / 2);
  const double ld = static_cast<double>(left);
  const double disc = std::max(b * b + 2.0 * static_cast<double>(dir) * ld * zi, 0.0);
  const double x = 2.0 * ld / (b + std::sqrt(disc));
  if (!(x < static_cast<double>(most))) return most;  // also where b + sqrt <= 0 (NaN, inf)
  return std::clamp<int64_t>(static_cast<int64_t>(x) + 1, 1, most);
}

// A bound on the tick holding the step, in 1..ticks (the walk's answer is at most it, so
// the values the solve computes are bounded by those at it): going up every tick adds more
// than L and J(m) >= Q'·m(m-1)/2 + m, so m <= left/L + 1 and m < sqrt(2·left/Q') + 2;
// going down each of the room's levels is >= 1, so m <= left. In doubles, with slack.
int64_t tick_bound(const RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t left,
                   int64_t ticks) {
  const double ld = static_cast<double>(left);
  double most = ld + 2.0;
  if (dir > 0) {
    const double q_dual =
        std::max(static_cast<double>(g.den) / static_cast<double>(g.rho) - 1, 1.0);
    most = std::min(ld / static_cast<double>(w.level) + 2.0, std::sqrt(2.0 * ld / q_dual) + 3.0);
  }
  return most < static_cast<double>(ticks) ? static_cast<int64_t>(most) : ticks;
}

// Whether the steep solve's numbers up to tick `most` fit in int64_t: m·L, J(m) <=
// m·min(m·den/rho + 1, room), i·den and the floor sum's lines below 2^61. Inlined: a call
// for every steep ramp step costs as much as the test.
[[gnu::always_inline]] inline bool steep_fits_64(const RampWalk& w, const IntervalGrid& g,
                                                 int64_t room, int64_t most) {
  const double m = static_cast<double>(most), den = static_cast<double>(g.den);
  const double j = std::min(m * den / static_cast<double>(g.rho) + 1.0, static_cast<double>(room));
  return std::max({m * static_cast<double>(w.level), m * j, (m + 2.0) * den}) < 0x1p61;
}

// walk_to_step for q = 0 in T: the tick holding the step, or the room's end. The guess is
// kept within `bound` (tick_bound), so every value stays within T.
template <typename T>
bool walk_steep_in(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room, int64_t left,
                   const RoomEnd& end, int64_t bound) {
  const SteepWalk<T> s(w, g, dir);
  int64_t m = guess_tick(w, g, dir, left, bound);
  T before = 0;
  if (s.settle(m, end.ticks, left, before)) {
    // Tick m: interval j of the walk, one tick long, its remainder rem + j·rho - m·den.
    const T j = s.interval_of(m);
    w.t = w.end + m - 1;
    w.end = w.t + 1;
    w.level += dir * static_cast<int64_t>(j);
    w.left = left - static_cast<int64_t>(before);
    w.passed += static_cast<int64_t>(j);
    w.rem = static_cast<int64_t>(w.rem + j * g.rho - static_cast<T>(m) * g.den);
    return true;
  }
  // No step within the room: w at its last interval, as the generator leaves it there
  // (one tick long if the last tick's carry is the room's last interval, else 0 long at
  // the room's last tick).
  const bool last_carries = s.interval_of(m) == room;
  const T through = last_carries ? before : before + s.level_of(m);
  w.t = w.end + m - (last_carries ? 1 : 0);
  w.end += m;
  w.level += dir * room;
  w.left = left - static_cast<int64_t>(through);
  w.passed += room;
  w.rem = end.rem;
  return false;
}

// walk_to_step for q = 0 (see the header).
bool walk_steep(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room) {
  if (room <= 0 || g.rho <= 0) return false;
  const int64_t left = w.left - w.level * (w.end - w.t);  // after this interval
  const RoomEnd end = room_end(g, w.rem, room);
  if (end.ticks == 0) {  // every interval in the room 0 long
    w.t = w.end;
    w.left = left;
    w.level += dir * room;
    w.passed += room;
    w.rem = end.rem;
    return false;
  }
  const int64_t bound = tick_bound(w, g, dir, left, end.ticks);
  if (steep_fits_64(w, g, room, bound))
    return walk_steep_in<int64_t>(w, g, dir, room, left, end, bound);
  return walk_steep_in<__int128>(w, g, dir, room, left, end, bound);
}

// Where the generator's loop parks at tick `until` = the start of tick m (1 <= m, tick m's
// interval strictly inside the room, no step before it): past the interval that ends
// there, and past the 0-long ones after it but the last (skip_empty_intervals() leaves the
// motion on that one), or on tick m's interval if none is 0 long.
template <typename T>
void park_at_tick(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t left, int64_t m) {
  const SteepWalk<T> s(w, g, dir);
  const T carry = s.interval_of(m);                      // tick m's interval
  const T ending = m > 1 ? s.interval_of(m - 1) : T{0};  // the one that ends at `until`
  const bool zeros = carry - 1 > ending;
  const T j = zeros ? carry - 1 : carry;
  const T carries = zeros ? m - 1 : m;  // carries among intervals 1..j
  w.t = w.end + m - 1;
  w.end = w.t + (zeros ? 0 : 1);
  w.level += dir * static_cast<int64_t>(j);
  w.left = left - static_cast<int64_t>(s.phase_of(m - 1));
  w.passed += static_cast<int64_t>(j);
  w.rem = static_cast<int64_t>(w.rem + j * g.rho - carries * g.den);
}

// For q >= 1: where the generator's loop parks at tick `until` (>= w.end, before the
// interval of the step and inside the room): in the interval that holds that tick, past
// every one that ends by it. Of the intervals after w's, the first m last S(m) =
// floor((m·(q·den + rho) + rem)/den) ticks, so m = floor(((X + 1)·den - rem - 1)/(q·den +
// rho)) of them end by X = until - w.end, and the (m + 1)-th holds it; those m add the
// phase W(m) of walk_to_step. In 128 bits: only a stop or a change between two steps
// comes here.
void park_in_interval(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t left, Tick until) {
  using W = __int128;
  const W q = g.q, rho = g.rho, den = g.den, rem = w.rem, level = w.level;
  const W m = ((until - w.end + W{1}) * den - rem - 1) / (q * den + rho);
  const W carries = (rem + m * rho) / den, j = m + 1, through = (rem + j * rho) / den;
  const W phase = q * (m * level + dir * (m * (m + 1) / 2)) + carries * level +
                  dir * carry_positions<W>(carries, rho, den, rem);  // W(m)
  w.t = w.end + static_cast<Tick>(q * m + carries);
  w.end = w.t + static_cast<Tick>(q + through - carries);
  w.level += dir * static_cast<int64_t>(j);
  w.left = left - static_cast<int64_t>(phase);
  w.passed += static_cast<int64_t>(j);
  w.rem = static_cast<int64_t>(rem + j * rho - through * den);
}

}  // namespace

void walk_until(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room, Tick until) {
  RampWalk to_step = w;
  walk_to_step(to_step, g, dir, room);  // walk_steep, inlined in walk_to_step alone
  // The step's interval, or the room's last, begun by `until` (at q = 0: before it, or the
  // room's last, 0 long, at it): the generator's loop passes every interval before it
  // (none holds the step, each ends by `until`) and stops there.
  const bool reached = g.q > 0 ? to_step.t <= until
                               : to_step.t < until || (to_step.t == until && to_step.end == until);
  if (reached) {
    w = to_step;
    return;
  }
  const int64_t left = w.left - w.level * (w.end - w.t);
  if (g.q > 0) return park_in_interval(w, g, dir, left, until);
  // At q = 0 the loop stops at `until`, the start of tick m after w's interval.
  const int64_t m = until - w.end + 1;
  if (steep_fits_64(w, g, room, m)) park_at_tick<int64_t>(w, g, dir, left, m);
  else park_at_tick<__int128>(w, g, dir, left, m);
}

bool walk_to_step(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room) {
  if (g.q == 0) return walk_steep(w, g, dir, room);
  if (room <= 0) return false;
  const int64_t phase = w.level * (w.end - w.t);
  const int64_t left = w.left - phase;  // after this interval
  // Beyond solve_to_step's 64 bits the doubles decide, and beyond them the walk from carry
  // to carry in 128 bits.
  if (!solves_in_64(left, w.level, g)) {
    const double ld = static_cast<double>(left), qd = static_cast<double>(g.q);
    const double most = ld / qd + 2.0;
    if ((ld + qd + 1.0) * (static_cast<double>(w.level) + most) >= 0x1p62 ||
        most * static_cast<double>(g.rho) >= 0x1p61)
      return walk_runs(w, g, dir, room, phase);
  }
  const double z =
      static_cast<double>(g.q) + static_cast<double>(g.rho) / static_cast<double>(g.den);
  return solve_to_step(w, g, z, dir, room, left);
}

bool walk_levels(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room) {
  for (int64_t phase; (phase = w.level * (w.end - w.t)) < w.left;) {
    if (w.passed >= room) return false;
    w.left -= phase;
    w.t = w.end;
    w.level += dir;
    ++w.passed;
    w.end = w.t + g.next_length(w.rem);  // 0 long at q = 0: its level adds no phase
  }
  return true;
}

}  // namespace stepnode::motion
