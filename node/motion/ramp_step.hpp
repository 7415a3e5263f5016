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
#include <cstdint>

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

// The reference: the same walk one level at a time (0-long intervals pass, adding no phase).
bool walk_levels(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room);

}  // namespace stepnode::motion
