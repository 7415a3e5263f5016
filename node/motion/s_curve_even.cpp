// The S-curve's steps at a constant velocity (s_curve.hpp, SCurve::Even): a cruise, a held
// velocity or a creep is c1 per tick exactly (c2 = c3 = 0), so from the overshoot of the
// last step past its target, over = kS - gap (0 <= over < c1), the next step lies
//   d = ceil((kS - over) / c1) = q + (r > over ? 1 : 0)   with kS = q c1 + r, 0 <= r < c1,
// ticks on, and its overshoot is over - r, plus c1 where that went negative. The smallest
// d with d c1 >= gap is exactly what the quick and the full search find (the property test
// compares every step); here it costs two additions and a compare.
#include <algorithm>

#include "node/motion/s_curve.hpp"
#include "node/motion/s_curve_scale.hpp"

namespace stepnode::motion {

using scurve::kS;

void SCurve::seat_even(int seg, const Segment& g) {
  // Once per segment of constant velocity (c2 = c3 = 0: seat_local() asks), one division;
  // not for a velocity so low its steps are 2^40 ticks apart (62 hours), nor above a step
  // per tick: the quick search finds those.
  if (g.c1 <= (kS >> 40) || g.c1 > kS) return;
  even_.seg = seg;
  even_.q = static_cast<Tick>(kS / g.c1);
  even_.r = kS % g.c1;
  even_.c1 = g.c1;
  even_.bound = g.start + g.len;  // kOpen: far beyond any tick
}

std::optional<Tick> SCurve::even_step(const Local& l, const Segment& g) {
  // The path's first step in the segment, from the last step's Local (the quick search's
  // place): the one division, as that step's overshoot may be c1 or more (the tick before
  // it rose at another velocity).
  const __int128 c1 = even_.c1;
  const auto d = static_cast<Tick>((l.gap + c1 - 1) / c1);
  if (d > g.len - l.tau) return std::nullopt;  // beyond the segment: the full search
  even_.over = d * c1 - l.gap;
  even_.ready = true;
  even_.entered = false;
  Local& n = local_[cur_ ^ 1];  // the slope at the step, read by slope()
  n.seg = -1;
  n.b1 = c1;
  pending_quick_ = true;
  peeked_seg_ = l.seg;
  return g.start + l.tau + d;
}

Tick SCurve::take_even() {
  // next_step() for a step of this path (same segment, no seat): taken, and the one after
  // it peeked at once (the generator peeks after every step), with no search.
  const Tick t = *peeked_;  // even_step()'s, or the one the last take_even() peeked
  last_ = t;
  ++steps_;
  ++quick_steps_;
  ++even_steps_;
  still_ = false;
  if (!even_.entered) {
    cur_ ^= 1;  // even_step()'s Local
    even_.entered = true;
  }
  if (distance_ && steps_ >= *distance_) {
    ended_ = true;
    end_ = last_;
    even_.ready = false;
    peeked_.reset();
    return t;
  }
  // kS - over = q c1 + (r - over) with |r - over| < c1: q + 1 ticks on where r > over.
  __int128 over = even_.over - even_.r;
  Tick next = t + even_.q;
  if (over < 0) {
    ++next;
    over += even_.c1;
  }
  if (next > even_.bound) {  // beyond the segment: the full search (Local's seg is -1)
    even_.ready = false;
    peeked_.reset();
    return t;
  }
  even_.over = over;
  peeked_ = next;
  return t;
}

}  // namespace stepnode::motion
