// The S-curve's quick step search (s_curve.hpp): the cubic of the last step's segment moved
// to that step's tick, so the next step is the smallest d >= 1 with
// rise(d) = d (b1 + d (b2 + d c3)) >= gap. Newton in doubles, started where the last
// crossings point, estimates d; one exact evaluation and the exact shift of the cubic to
// tau + d decide it (the tick before rises by b1' - b2' + c3, the backward difference).
// Where that does not decide, the full search (s_curve_steps.cpp) does.
#include <algorithm>
#include <cmath>

#include "node/motion/s_curve.hpp"
#include "node/motion/s_curve_scale.hpp"

namespace stepnode::motion {
using scurve::approx;
using scurve::kS;
using scurve::kSd;

int SCurve::try_step(const Local& l, const Segment& g, Tick d, Local& n) {
  // d against the exact cubic: -1 the step lies beyond, +1 before, 0 it is d (n the cubic
  // moved to tau + d). Unsigned: the same products modulo 2^128, without sign extensions.
  using U = unsigned __int128;
  const U ud = static_cast<uint64_t>(d);
  // c3 d: one 64 x 64 -> 128 bit product (both fit 64 bits signed).
  const U b2_0 = static_cast<U>(l.b2), jerk = static_cast<U>(static_cast<__int128>(g.c3) * d);
  const U b2 = b2_0 + 3 * jerk;
  const U b1 = static_cast<U>(l.b1) + ud * (b2_0 + b2);
  const U rise = ud * (static_cast<U>(l.b1) + ud * (b2_0 + jerk));
  const auto over = static_cast<__int128>(rise - static_cast<U>(l.gap));  // S p - target
  if (over < 0) return -1;
  if (over >= static_cast<__int128>(b1 - b2) + g.c3) return +1;  // the tick before reached it
  n.tau = l.tau + d;
  n.gap = kS - over;
  n.b1 = static_cast<__int128>(b1);
  n.b2 = static_cast<__int128>(b2);
  n.left = l.left - static_cast<__int128>(rise);
  n.gapd = kSd - approx(over);
  return 0;
}

std::optional<Tick> SCurve::quick() {
  const Local& l = local_[cur_];
  if (l.seg < 0 || ended_ || (distance_ && steps_ >= *distance_)) return std::nullopt;
  const Segment& g = segs_[l.seg];
  if (l.seg == even_.seg) return even_step(l, g);  // a constant velocity (s_curve_even.cpp)
  const Tick room = std::min(g.len - l.tau, kLongestStep);
  if (l.left < l.gap) return std::nullopt;  // the segment ends below: the full search skips it
  // Newton from where the last two intervals point (within a fraction of a tick while the
  // velocity changes smoothly).
  const double b1 = l.b1d, b2 = l.b2d, b3 = static_cast<double>(g.c3), r = l.gapd;
  double u = l.x + l.w + l.dw;
  for (int i = 0; i < 6; ++i) {
    const double f = ((b3 * u + b2) * u + b1) * u - r, slope = (3 * b3 * u + 2 * b2) * u + b1;
    const double du = f / slope;
    u -= du;
    if (std::abs(du) < 0.01) break;
  }
  if (!(u > 0 && u < static_cast<double>(room))) return std::nullopt;  // NaN too
  Local& n = local_[cur_ ^ 1];
  Tick d = static_cast<Tick>(u) + 1;  // ceil(u) but for a whole u (the exact test decides)
  int side = try_step(l, g, d, n);
  if (side != 0) {
    d -= side;
    if (d < 1 || d > room || try_step(l, g, d, n) != 0) return std::nullopt;
  }
  n.seg = l.seg;
  if (n.gap <= 0) n.seg = -1;  // more than a step per tick: the full search next
  const double jerk = 3 * b3 * static_cast<double>(d);
  n.b1d = b1 + static_cast<double>(d) * (2 * b2 + jerk);
  n.b2d = b2 + jerk;
  n.x = u - static_cast<double>(d);
  n.w = u - l.x;
  n.dw = n.w - l.w;
  pending_quick_ = true;
  peeked_seg_ = l.seg;
  return g.start + n.tau;
}

void SCurve::seat_local(Tick prev) {
  // A step the full search found: the cubic of its segment moved to its tick.
  Local& l = local_[cur_];
  const Segment& g = segs_[seg_];
  l.tau = last_ - g.start;
  l.b1 = g.slope(l.tau);
  l.b2 = g.c2 + 3 * static_cast<__int128>(g.c3) * l.tau;
  const __int128 here = g.at(l.tau);
  l.gap = static_cast<__int128>(steps_ + 1) * kS - here;
  l.left = g.len == kOpen ? kS * (Tick{1} << 40) : g.end - here;  // open: 2^40 steps more
  l.b1d = approx(l.b1);
  l.b2d = approx(l.b2);
  l.gapd = approx(l.gap);
  l.x = 0;
  l.w = static_cast<double>(std::max<Tick>(1, last_ - prev));
  l.dw = 0;
  l.seg = l.gap > 0 ? seg_ : -1;
  if (g.c3 == 0 && g.c2 == 0 && l.seg >= 0) seat_even(l.seg, g);  // the cruise's steps
}

}  // namespace stepnode::motion
