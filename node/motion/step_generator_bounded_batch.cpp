// A ramp's steps in a batch without its carries (issue 13: ramps at Horner cost): each step
// found from the straight line the interval ends keep to, and proven by how far they may
// stray from it (ramp_spread.hpp), not by walking them.
//
// From the last step's tick t0, at level L0 in an interval that ends at E0, the intervals
// after it end at E_j = E0 + j·q + floor((rem + j·rho)/den); up to a tick c, J(c) of them
// end before c (one division), the level at c is L0 + dir·J(c), and the phase added over
// the ticks t0 + 1 .. c is exactly
//   Phi(c) = L0·(c - t0) + dir·(J·(c - E0) - q·J(J-1)/2 - G(J)),
//   G(J) = sum_{j<J} floor((rem + j·rho)/den).
// G differs from its straight line (rho·J(J-1)/2 + J·(rem - mu))/den by the residues'
// partial sum less J·mu, at most the grid's spread over den. So Phi(c) lies within the
// spread of A(c), the same with the line for G; in doubles A is off by far less than a
// unit. The n-th step (n from 1) is the first c where the accumulator acc0 + Phi(c) reaches
// n·d; c is taken where A(c) says so by more than the spread and the tick before, Phi(c)
// less the level at c, falls short by as much. Elsewhere (one step in a few hundred to a
// few thousand, as the levels are hundreds to thousands of phase units a tick and the
// spread a few) the batch ends and the exact solve (solve_batch) takes that step.
//
// A step costs a square root (its guess: Guess below), one division (J) and a few
// products, however many carries its span holds, and waits for no other step. Its
// accumulator is not kept: bounded_batch_state() finds the last taken step's exactly, with
// the floor sum G, once for the batch. peek_batch() asks for it on grids that carry at
// least every kBoundedCarries intervals; on sparser ones the walk is the faster.
#include <algorithm>
#include <cmath>

#include "node/motion/ramp_step.hpp"
#include "node/motion/step_generator.hpp"

namespace stepnode::motion {
namespace {

// A step's tick from a real estimate `u` (ticks after t0) of where its phase is reached:
// the tick after it, and after `last` (>= 0 ticks after t0).
// (A NaN, a ramp down's line ending before the target, or a guess beyond int64 gives the
// tick after `last`: the tries from there find it, or end the batch.)
Tick tick_after(double u, Tick last) {
  const auto ticks = static_cast<Tick>(u > 0 && u < 0x1p62 ? u : 0.0);
  return std::max(last + 1, ticks + 1);
}

// Where the phase from t0 reaches `target` on the ramp's straight line (its interval ends
// on E0 + (rem + j·num)/den exactly, the level half an interval on): the quadratic
// alpha·P² + beta·P + gamma in P = ticks from t0 - E0 - rem/den, solved. Within a few
// hundredths of a tick of the step's crossing on the profiles' grids (the line stays
// within ~Z level-ticks of the staircase), and every step's its own: no step waits for
// the one before (the steps' divisions overlap).
struct Guess {
  double alpha4, beta, beta2, gamma, shift, inv_l0, first, dir_z;
  Guess(double l0, double e, double phi, double z, double k, int dir)
      : alpha4(2 * dir / z),
        beta(l0 + dir * ((phi - k) / z + 0.5)),
        beta2(beta * beta),
        gamma(l0 * (e + phi) + dir * (phi + z / 4 - k) / 2),
        shift(e + phi),
        inv_l0(1 / l0),
        first(l0 * e),
        dir_z(dir * z) {}
  // Ticks from t0 (real): where the phase `target` is reached.
  double at(double target) const {
    if (target <= first) return target * inv_l0;  // in the interval the batch began in
    return shift + (std::sqrt(beta2 + alpha4 * (target - gamma)) - beta) * dir_z;
  }
};

}  // namespace

template <int Dir>
Tick StepGenerator::bounded_batch(int64_t last, int64_t most) {
  const IntervalGrid g = cursor_.grid();
  CarrySpread& spread = spreads_[Dir > 0 ? 0 : 1];  // the ramp up's grid, the ramp down's
  if (spread.rho != g.rho || spread.den != g.den) spread = carry_spread(g.rho, g.den);
  // Not on a grid whose residues repeat too seldom to count, nor with a step's phase beyond
  // doubles' whole numbers.
  if (spread.phase < 0) return kUnpeeked;
  const int64_t d = ramp_.phase_per_step, l0 = level_;
  // (peek_batch's solves_in_64 keeps d below 2^29: the targets below stay whole in doubles.)
  // The levels the batch may pass: the ramp's plain ones, at most a step per tick, and
  // few enough for bounded_batch_state's 64-bit products (J·(c - E0) <= J(J + 1)(q + 1)
  // and the floor sum's rho·J + rem below den·(J + 1): both below 2^60).
  int64_t room = Dir * (last - l0);
  if (Dir < 0) room = std::min(room, l0 - 1);
  if (Dir > 0) room = std::min(room, d - l0);
  room = std::min<int64_t>(room,
                           static_cast<int64_t>(std::sqrt(0x1p60 / static_cast<double>(g.q + 1))));
  room = std::min<int64_t>(room, (int64_t{1} << 60) / g.den - 1);
  if (room < 0) return kUnpeeked;
  const int64_t num = g.q * g.den + g.rho;  // Z·den: q, rho < 2^29 here, den < 2^32 below
  if (g.den >= (int64_t{1} << 32)) return kUnpeeked;
  const Tick t0 = t_, e0 = interval_end_;
  const int64_t rem = cursor_.remainder(), acc0 = acc_;
  // A(c) = L0·(c - t0) + Dir·J·((c - E0) - (J - 1)·Z/2 - k), k = (rem - mu)/den.
  const double half_z = cursor_.z() / 2;
  const double mu = static_cast<double>(rem % spread.g) + static_cast<double>(g.den - spread.g) / 2;
  const double k = (static_cast<double>(rem) - mu) / static_cast<double>(g.den);
  // The spread, and the doubles' error: where A is near the target every term is within
  // ~70·d (twice the batch's phase at most), each off by a few roundings: ~2^-49·d.
  const double margin = spread.phase + 0x1p-40 * 64 * static_cast<double>(d) + 1e-6;
  const auto l0d = static_cast<double>(l0);
  const double dd = static_cast<double>(d), acc0d = static_cast<double>(acc0);
  const Tick e = e0 - t0;  // ticks from t0 (c is t0 + c below)
  const Guess guess(l0d, static_cast<double>(e),
                    static_cast<double>(rem) / static_cast<double>(g.den), half_z * 2, k, Dir);
  double target = dd - acc0d;  // the step's phase from t0
  Tick prev = 0;
  int n = 0;
  for (; n < most; ++n, target += dd) {
    Tick c = tick_after(guess.at(target), prev);
    double over = 0;
    int64_t level = l0;
    bool found = false;
    for (int tries = 0; tries < 4; ++tries) {
      int64_t ticks = 0;  // J(c): the ends E_j < c, ceil(((c - E0)·den - rem) / num)
      if (__builtin_mul_overflow(c - e, g.den, &ticks)) break;  // a guess far beyond
      ticks -= rem;
      const int64_t j = ticks <= 0 ? 0 : (ticks - 1) / num + 1;
      if (j > room) break;
      const auto jd = static_cast<double>(j);
      const double a = l0d * static_cast<double>(c) +
                       Dir * jd * (static_cast<double>(c - e) - (jd - 1) * half_z - k);
      level = l0 + Dir * j;
      over = a - target;  // reached at c by this much (less: short of it)
      const auto ld = static_cast<double>(level);
      if (over >= margin && over < ld - margin) [[likely]] {
        found = true;
        break;
      }
      if (std::abs(over) < margin || std::abs(over - ld) < margin) break;  // too near to tell
      // Short of it, or reached a tick or more before: on to where the level points.
      const Tick next = tick_after(static_cast<double>(c) - over / ld, prev);
      c = next != c ? next : c + (over < 0 ? 1 : -1);
      if (c <= prev) break;
    }
    if (!found) break;
    prev = c;
    batch_.step[n] = t0 + c, batch_.level[n] = level;
  }
  if (n == 0) return kUnpeeked;
  // The levels the last step spanned: the solve's guess where it takes over.
  last_span_ = Dir * (batch_.level[n - 1] - (n > 1 ? batch_.level[n - 2] : l0));
  batch_.step[n] = kUnpeeked;
  batch_.count = n;
  batch_.level0 = l0;
  batch_.kept = StepBatch::Kept::Bounded;
  batch_.t0 = t0;
  return batch_.step[0];
}

template Tick StepGenerator::bounded_batch<1>(int64_t last, int64_t most);
template Tick StepGenerator::bounded_batch<-1>(int64_t last, int64_t most);

void StepGenerator::bounded_batch_state() {
  // The accumulator at the last step taken, t_ (its level already in level_): the exact
  // Phi above with the floor sum G, less a step's phase for each step taken. acc_,
  // interval_end_ and the cursor still stand where the batch began (batch_state moves
  // them after this).
  const IntervalGrid g = cursor_.grid();
  const int64_t dir = phase_ == MotionPhase::Accelerating ? 1 : -1;
  const int64_t j = dir * (level_ - batch_.level0);
  const int64_t sum = floor_sum<int64_t>(j, g.den, g.rho, cursor_.remainder());
  const int64_t phi = batch_.level0 * (t_ - batch_.t0) +
                      dir * (j * (t_ - interval_end_) - g.q * (j * (j - 1) / 2) - sum);
  acc_ += phi - ramp_.phase_per_step * batch_.pos;
}

}  // namespace stepnode::motion
