// The ramp steps StepGenerator solves in batches (solve_batch, issue 13): each step beyond
// its interval walked from the span of the step before with the next carry kept
// (ramp_carry_walk.hpp), and the motion after a batch's step moved to lazily (take_known
// moves the time, accumulator and level; sync_batch the interval's place). Held to the
// level-by-level walk and to a generator that solves one step at a time (walk_ramps(): no
// batch), after every step and across changes in the middle of a batch. The S-curve's
// batches (SCurve::batch, found in doubles and proven by an error bound) are held to its
// exact search the same way.
#include <gtest/gtest.h>

#include <array>
#include <optional>
#include <random>

#include "node/motion/ramp.hpp"
#include "node/motion/ramp_carry_walk.hpp"
#include "node/motion/step_generator.hpp"
#include "node/motion/tests/ramp_walk_check.hpp"

namespace stepnode::motion {
namespace {

using walk_check::pick;

TEST(CarryWalk, TheNextCarryIsTheRemaindersCarry) {
  // NextCarry::after and pass() against the cursor's additions, interval by interval.
  std::mt19937_64 rng(4096);
  for (int i = 0; i < 2'000; ++i) {
    const int64_t den = pick(rng, 1, 100'000);
    const IntervalGrid g{pick(rng, 1, 200), pick(rng, 0, den - 1), den};
    const CarryGrid cg(g);
    int64_t rem = pick(rng, 0, den - 1);
    NextCarry c = NextCarry::after(g, rem);
    for (int64_t j = 1; j <= 300; ++j) {
      const Tick len = g.next_length(rem);
      ASSERT_EQ(len == g.q + 1, j == c.at) << "den " << den << " rho " << g.rho << " j " << j;
      if (j == c.at) {
        ASSERT_EQ(rem, c.rem);
        c.pass(cg);
      }
      NextCarry from_here = c;
      from_here.at -= j;
      EXPECT_EQ(remainder_before(from_here, g), rem);
    }
  }
}

// A guess near the walk's answer m (a ramp's next step spans as many levels, one fewer or
// more), or further off.
int64_t pick_guess(std::mt19937_64& rng, int64_t m) {
  switch (rng() % 4) {
    case 0: return m;
    case 1: return std::max<int64_t>(1, m - 1);
    case 2: return m + 1;
    default: return std::max<int64_t>(1, m + pick(rng, -8, 8));
  }
}

TEST(CarryWalk, AWalkFromAGuessIsTheLevelWalksOrLeavesTheStepAlone) {
  // The profiles' grids, as solve_to_step's hint test: where walk_from_guess answers, the
  // answer is walk_levels' every field (the remainder from the next carry); where it does
  // not, the walk and the carry are as they were.
  std::mt19937_64 rng(1714);
  int answered = 0, left_alone = 0;
  for (int i = 0; i < 200'000 && !::testing::Test::HasFailure(); ++i) {
    const walk_check::ProfileWalk r = walk_check::random_profile_walk(rng);
    const IntervalGrid& g = r.g;
    const RampWalk& start = r.start;
    const int64_t dir = r.dir, room = r.room, after = r.after;
    if (after <= 0 || room < 1) continue;
    RampWalk walked = start;
    const bool found = walk_levels(walked, g, dir, room);
    RampWalk w = start;
    NextCarry c = NextCarry::after(g, start.rem);
    const NextCarry c0 = c;
    const int64_t guess = pick_guess(rng, walked.passed);
    const bool ok = dir > 0 ? walk_from_guess<1>(w, c, CarryGrid(g), room, after, guess)
                            : walk_from_guess<-1>(w, c, CarryGrid(g), room, after, guess);
    if (ok) {
      ++answered;
      ASSERT_TRUE(found);
      w.rem = remainder_before(c, g);
      walk_check::expect_same(walked, w);
      const NextCarry want = NextCarry::after(g, walked.rem);
      EXPECT_EQ(c.at, want.at);
      EXPECT_EQ(c.rem, want.rem);
    } else {
      ++left_alone;
      walk_check::expect_same(start, w);
      EXPECT_EQ(c.at, c0.at);
      EXPECT_EQ(c.rem, c0.rem);
    }
  }
  EXPECT_GT(answered, 30'000);
  EXPECT_GT(left_alone, 1'000);
}

// A ramp as the generator batches them: a continuous slope on the HP channel's or the CiA
// 402 profiles' grids, a Horner module's (whole ticks per level, most steps in the
// interval of the one before), or a jerk-limited one (SCurve::batch; a jerk of 0 now and
// then: that phase takes no time).
RampSpec batched_ramp(std::mt19937_64& rng) {
  const uint64_t kind = rng() % 4;
  if (kind == 3) {
    const int64_t accel = pick(rng, 100, 400'000), decel = pick(rng, 100, 400'000);
    RampSpec r = profile_ramp(pick(rng, 5, 40'000), accel, decel,
                              profile_levels_per_hz(std::max(accel, decel)));
    r.s_curve = true;
    for (uint32_t& j : r.jerk)
      j = rng() % 8 == 0 ? 0 : static_cast<uint32_t>(pick(rng, 1'000, 100'000'000));
    return r;
  }
  if (kind == 2) {
    const int64_t base = pick(rng, 1, 4'000);
    return horner_ramp(pick(rng, 20, 65'535), base, pick(rng, base + 1, 8'191),
                       pick(rng, 1, 27'300), pick(rng, 0, 27'300));
  }
  // Half of them round (2^a 3^b 5^c, as kClockHz): grids whose residues repeat within
  // kSpreadPeriodMost intervals, solved without their carries (bounded_batch).
  const bool round = rng() % 2 == 0;
  auto slope = [&](int64_t lo, int64_t hi) {
    if (!round) return pick(rng, lo, hi);
    int64_t v = 1;
    while (v * 5 <= hi) v *= std::array<int64_t, 3>{2, 3, 5}[rng() % 3];
    return std::max(lo, v);
  };
  if (kind == 0)
    return frequency_ramp(pick(rng, 0, 50), pick(rng, 500, 40'000),
                          slope(10'000'000, 2'000'000'000));
  const int64_t accel = slope(2'000, 2'000'000), decel = slope(2'000, 2'000'000);
  return profile_ramp(pick(rng, 500, 40'000), accel, decel,
                      profile_levels_per_hz(std::max(accel, decel)));
}

// What a caller can read of the motion, the same with batches as without.
void expect_same_state(const StepGenerator& a, const StepGenerator& b) {
  EXPECT_EQ(a.time(), b.time());
  EXPECT_EQ(a.level(), b.level());
  EXPECT_EQ(a.phase(), b.phase());
  EXPECT_EQ(a.steps_done(), b.steps_done());
  EXPECT_EQ(a.steps_to_stop(), b.steps_to_stop());
  const StepGenerator::Marks ma = a.marks(), mb = b.marks();
  EXPECT_EQ(ma.accel_steps, mb.accel_steps);
  EXPECT_EQ(ma.run_steps, mb.run_steps);
  EXPECT_EQ(ma.decel_steps, mb.decel_steps);
  EXPECT_EQ(ma.creep_steps, mb.creep_steps);
  EXPECT_EQ(ma.peak_level, mb.peak_level);
  EXPECT_EQ(ma.run_start, mb.run_start);
  EXPECT_EQ(ma.decel_start, mb.decel_start);
  EXPECT_EQ(ma.decel_end, mb.decel_end);
  EXPECT_EQ(ma.end, mb.end);
}

// One change at `at` (between the last step and the next), the same on both.
void change_both(StepGenerator& a, StepGenerator& b, const RampSpec& r, Tick at,
                 std::mt19937_64& rng) {
  const int64_t level = pick(rng, 1, r.run_level), steps = pick(rng, 1, 3'000);
  const Rational quick{r.decel_ticks_per_level.num, 2 * r.decel_ticks_per_level.den};
  const uint64_t kind = rng() % 4;
  for (StepGenerator* g : {&a, &b}) {
    switch (kind) {
      case 0: g->stop(at); break;
      case 1: g->stop(at, quick); break;
      case 2: g->change_velocity(at, level); break;
      default: g->retarget(at, steps, r); break;
    }
  }
}

TEST(RampBatch, EveryStepLeavesTheMotionAsOneStepAtATime) {
  // Random moves, peeked before every step as the axes do, changed now and then in the
  // middle of a batch (at a step, or a few ticks after it, before the next): after every
  // step the batched generator reads as the one solving one step at a time. A planner's
  // copy taken in the middle of a batch goes on with the same steps as a copy of the other.
  std::mt19937_64 rng(2611);
  int64_t steps = 0, changes = 0;
  for (int move = 0; move < 300 && !::testing::Test::HasFailure(); ++move) {
    const RampSpec r = batched_ramp(rng);
    const std::optional<int64_t> distance =
        rng() % 3 ? std::optional<int64_t>(pick(rng, 50, 6'000)) : std::nullopt;
    StepGenerator batched, alone;
    alone.walk_ramps(true);
    batched.start(r, 0, 1, distance);
    alone.start(r, 0, 1, distance);
    int64_t change_at = pick(rng, 5, 600), copy_at = pick(rng, 5, 600);
    Step a, b;
    for (int i = 0; i < 8'000; ++i) {
      const std::optional<Tick> pa = batched.peek(), pb = alone.peek();
      ASSERT_EQ(pa, pb) << "move " << move << " step " << i;
      if (!pa) break;
      ASSERT_TRUE(batched.next(a));
      ASSERT_TRUE(alone.next(b));
      ASSERT_EQ(a.time, b.time) << "move " << move << " step " << i;
      expect_same_state(batched, alone);
      ++steps;
      if (i == copy_at) {
        copy_at += pick(rng, 5, 600);
        StepGenerator planner = batched, reference = alone;
        Step p, q;
        for (int k = 0; k < 40 && planner.peek(); ++k) {
          ASSERT_TRUE(planner.next(p));
          ASSERT_TRUE(reference.next(q));
          ASSERT_EQ(p.time, q.time) << "move " << move << " copy's step " << k;
        }
      }
      if (i == change_at) {
        change_at += pick(rng, 5, 600);
        StepGenerator ahead = alone;
        Step following;
        Tick at = a.time;
        if (rng() % 2 && ahead.next(following) && following.time > a.time + 1)
          at += pick(rng, 0, std::min<Tick>(following.time - a.time - 1, 50));
        change_both(batched, alone, r, at, rng);
        ++changes;
      }
    }
  }
  EXPECT_GT(steps, 100'000);
  EXPECT_GT(changes, 300);
}

}  // namespace
}  // namespace stepnode::motion
