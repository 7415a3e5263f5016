// The S-curve's steps in a batch (s_curve.hpp, issue 13): the steps after the last one in
// its segment, found in doubles alone and each proven by an error bound, not by the exact
// integers. From the last step's tick the cubic rises by
//   rise(D) = D (b1 + D (b2 + D c3))
// (b1, b2 exact there), and the batch's n-th step (n from 0) is the smallest D with
// rise(D) >= gap + n S. With every term kept relative to that one exact place, rise(D)
// less the target is off in doubles by no more than ~14 roundings of
//   M(D, n) = D (|b1| + D (|b2| + D |c3|)) + gap + n S
// (the conversions of b1, b2, gap and S, two roundings each at most; three products and
// three sums; the target's product and sum), under 2^-49 M. M rises with D and n, so one
// bound serves the whole batch: 2^-44 M at its reach (a tick no step of it passes) and
// its last n. A step is taken where the value at its tick is at least that far above 0
// and at the tick before at least that far below: then the exact integers would say the
// same. The value moves by S / interval a tick and M stays within ~100 S, so this leaves
// out about one step in 10^7 at intervals of 10^4 ticks: the batch ends there, and the
// exact search takes that step.
//
// A step costs two evaluations of the cubic, no 128-bit product: the guess comes from the
// last crossings (where the two before point), the crossing from the two values (linear
// between the ticks), and Newton only where the guess missed its tick.
#include <algorithm>
#include <cmath>

#include "node/motion/s_curve.hpp"
#include "node/motion/s_curve_scale.hpp"

namespace stepnode::motion {
namespace {

using scurve::approx;
using scurve::kS;
using scurve::kSd;

// How far below the bound a value must lie to be certain (2^5 times the ~2^-49 M the
// roundings reach).
constexpr double kCertain = 0x1p-44;

// The cubic from the last step's tick, in doubles, and its coefficients' sizes.
struct Rise {
  double b1, b2, b3, m1, m2, m3;
  double at(double d) const { return ((b3 * d + b2) * d + b1) * d; }
  double slope(double d) const { return (3 * b3 * d + 2 * b2) * d + b1; }
  double bound(double d, double target) const {
    return (((m3 * d + m2) * d + m1) * d + target) * kCertain;
  }
};

// The step's tick after `last` from the guess `u` (below `reach`): true with `c` the tick,
// `above` and `below` the values at it and the tick before, where the bound `e` (the
// batch's, at its reach) makes that certain. Inline: its results stay in registers.
[[gnu::always_inline]] inline bool certain_step(const Rise& r, double target, double e, Tick last,
                                                double reach, double u, Tick& c, double& above,
                                                double& below) {
  if (!(u > -1 && u < reach)) return false;          // NaN too
  c = std::max(last + 1, static_cast<Tick>(u + 1));  // ceil(u), or one more for a whole u
  const auto d = static_cast<double>(c);
  above = r.at(d) - target;
  below = r.at(d - 1) - target;
  return above >= e && below < -e;
}

// Newton from `u` toward the root of rise(D) = target (a guess that missed its tick).
double newton(const Rise& r, double target, double u) {
  for (int i = 0; i < 8; ++i) {
    const double slope = r.slope(u);
    if (!(slope > 0)) return u;
    const double du = (r.at(u) - target) / slope;
    u -= du;
    if (std::abs(du) < 0.01) break;
  }
  return u;
}

}  // namespace

int SCurve::batch(Tick* out, int most) const {
  const Local& l = local_[cur_];
  if (l.seg < 0 || l.seg == even_.seg || ended_) return 0;  // none, or the even path's
  if (distance_) most = static_cast<int>(std::min<int64_t>(most, *distance_ - steps_ - 1));
  // Only the steps whose positions the segment's end reaches: where the velocity dips
  // below 0 before its end (its phases are whole ticks), the position may pass a step's
  // and fall back, and that step is the next segment's (as the exact search finds it).
  const __int128 spare = l.left - l.gap;
  if (spare < 0) return 0;
  if (spare < static_cast<__int128>(most - 1) * kS) most = static_cast<int>(1 + spare / kS);
  const Segment& g = segs_[l.seg];
  const Tick room = std::min(g.len - l.tau, kLongestStep);
  const double b1 = approx(l.b1), b2 = approx(l.b2), b3 = static_cast<double>(g.c3);
  const Rise r{b1, b2, b3, std::abs(b1), std::abs(b2), std::abs(b3)};
  const double gap = approx(l.gap);
  const Tick from = g.start + l.tau;
  double x = l.x, w = l.w, dw = l.dw;  // the last crossing (from `from`), interval, change
  // One bound for the whole batch, the one at its furthest step (M rises with D and n):
  // its steps within `reach` ticks, twice as far as the last interval points (a step
  // beyond ends the batch), and within the segment.
  const double most_d = most, room_d = static_cast<double>(room);
  const double reach = std::min(room_d, std::floor(2 * (most_d + 1) * std::max(w, 1.0) + 64));
  const double e = r.bound(reach, gap + most_d * kSd);
  Tick last = 0;
  int n = 0;
  double nd = 0;  // n
  for (; n < most; ++n, nd += 1) {
    const double target = gap + nd * kSd;
    double u = x + w + dw;
    Tick c = 0;
    double above = 0, below = 0;
    if (!certain_step(r, target, e, last, reach, u, c, above, below)) [[unlikely]] {
      u = newton(r, target, u);
      if (!certain_step(r, target, e, last, reach, u, c, above, below)) break;
    }
    if (static_cast<double>(c) > reach) break;  // beyond (the step before was at its end)
    const double crossing = static_cast<double>(c) - above / (above - below);
    const double interval = crossing - x;
    dw = interval - w;
    w = interval;
    x = crossing;
    last = c;
    out[n] = from + c;
  }
  return n;
}

void SCurve::take_batch(const Tick* steps, int k) {
  const Tick prev = k >= 2 ? steps[k - 2] : last_;
  last_ = steps[k - 1];
  steps_ += k;
  quick_steps_ += k;
  peeked_.reset();
  seat_local(prev);  // the exact cubic at the last one: the next steps go on from there
}

__int128 SCurve::peak_slope(const Tick* steps, int k) const {
  // The slope is a parabola in the tick, rising where the acceleration (c2 + 3 c3 tau, a
  // line) is above 0. Where that line has one sign at both ends the highest is at the last
  // step or the first; c3 > 0, a dip between: at one of them; c3 < 0, a crest between: at
  // the first step where the acceleration is no longer above 0, or the one before.
  const Segment& g = segs_[seg_];
  auto accel = [&](int i) { return g.c2 + 3 * static_cast<__int128>(g.c3) * (steps[i] - g.start); };
  const __int128 first = accel(0), last = accel(k - 1);
  if (first >= 0 && last >= 0) return slope_at(steps[k - 1]);
  if (first <= 0 && last <= 0) return slope_at(steps[0]);
  if (g.c3 > 0) return std::max(slope_at(steps[0]), slope_at(steps[k - 1]));
  int a = 0, b = k - 1;  // accel(a) > 0, accel(b) <= 0
  while (b - a > 1) {
    const int m = a + (b - a) / 2;
    if (accel(m) > 0) {
      a = m;
    } else {
      b = m;
    }
  }
  return std::max(slope_at(steps[a]), slope_at(steps[b]));
}

}  // namespace stepnode::motion
