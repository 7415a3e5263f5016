// The S-curve's steps: the first tick at which the exact position reaches each step
// (s_curve.hpp). A Newton estimate in doubles, then the integers decide.
#include <cmath>

#include "node/motion/s_curve.hpp"
#include "node/motion/s_curve_scale.hpp"

namespace stepnode::motion {
using scurve::approx;
using scurve::kS;

Tick SCurve::find(const Segment& g, Tick lo, __int128 target) {
  // The smallest tau in (lo, g.len] with g.at(tau) >= target, given g.at(lo) < target (the
  // position rises in a segment: its velocity is >= 0 throughout).
  const double r = approx(target - g.at(lo));
  const double v = approx(g.slope(lo));
  const double a = approx(g.c2 + 3 * static_cast<__int128>(g.c3) * lo);
  const double j = static_cast<double>(g.c3);
  double u = v > 0 ? r / v : std::cbrt(r / std::max(j, 1.0));
  for (int i = 0; i < 6; ++i) {
    const double f = ((j * u + a) * u + v) * u - r, d = (3 * j * u + 2 * a) * u + v;
    if (!(d > 0)) break;
    const double du = f / d;
    u -= du;
    if (std::abs(du) < 0.05) break;
  }
  const Tick hi = g.len;
  Tick t = lo + 1;
  if (u > 1 && u < static_cast<double>(hi - lo)) t = lo + static_cast<Tick>(std::ceil(u));
  // The estimate is within a tick; the exact test decides, a bisection takes over if it
  // was further off.
  const bool reached = g.at(t) >= target;
  if (reached && (t - 1 <= lo || g.at(t - 1) < target)) return t;
  if (!reached && t < hi && g.at(t + 1) >= target) return t + 1;
  Tick below = lo, above = t;
  if (!reached) {
    below = t;
    above = t + 1;
    while (above < hi && g.at(above) < target) above = std::min(hi, below + 2 * (above - lo));
  }
  while (above - below > 1) {
    const Tick mid = below + (above - below) / 2;
    (g.at(mid) >= target ? above : below) = mid;
  }
  return above;
}

std::optional<Tick> SCurve::compute(int& k) const {
  if (ended_ || (distance_ && steps_ >= *distance_)) return std::nullopt;
  const __int128 target = static_cast<__int128>(steps_ + 1) * kS;
  for (; k < count_; ++k) {
    const Segment& g = segs_[k];
    const Tick lo = std::max(last_, g.start) - g.start;
    if (lo >= g.len) continue;
    if (g.len != kOpen && g.end < target) continue;
    if (g.len == kOpen && g.c1 <= 0 && g.c2 <= 0) return std::nullopt;
    if (g.at(lo) >= target && last_ < g.start) return g.start + lo;  // a step where it begins
    return g.start + find(g, lo, target);
  }
  return std::nullopt;
}

std::optional<Tick> SCurve::search() {
  // The quick search where it decides; the full one otherwise (a step in another segment,
  // the first after a start or replan, an estimate that missed).
  even_.ready = false;
  if (!full_search_only_) {
    if (const std::optional<Tick> t = quick()) return t;
  }
  pending_quick_ = false;
  peeked_seg_ = seg_;
  return compute(peeked_seg_);
}

std::optional<Tick> SCurve::next_step() {
  const std::optional<Tick> t = peek();
  if (even_.ready) return take_even();  // at a constant velocity (s_curve_even.cpp)
  peeked_.reset();
  if (!t) {
    ended_ = true;
    if (distance_ && steps_ >= *distance_) end_ = last_;
    still_ = true;
    return std::nullopt;
  }
  const Tick prev = last_;
  seg_ = peeked_seg_;
  last_ = *t;
  ++steps_;
  if (pending_quick_) {
    cur_ ^= 1;
    ++quick_steps_;
  } else {
    seat_local(prev);
  }
  still_ = false;  // velocity(): local_[cur_].b1, the exact slope at this tick
  if (distance_ && steps_ >= *distance_) {
    ended_ = true;
    end_ = last_;
  }
  return t;
}

}  // namespace stepnode::motion
