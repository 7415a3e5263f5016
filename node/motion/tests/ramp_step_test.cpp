// The ramp walk of ramp_step.hpp against the level-by-level walk (every field, on random
// grids from Horner's whole Z to fine fractional ones, across the 64- and 128-bit paths),
// and the generator's peeked steps against its own step loop on random moves changed
// mid-way (peek() then next() takes the walk's state; next() alone walks level by level).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "node/motion/ramp_step.hpp"
#include "node/motion/step_generator.hpp"
#include "node/motion/tests/ramp_walk_check.hpp"

namespace stepnode::motion {
namespace {

using walk_check::expect_same;
using walk_check::pick;

IntervalGrid grid_of(int64_t num, int64_t den) { return IntervalGrid{num / den, num % den, den}; }

// Walks that ended at the room's last interval, 5 or more levels on (the step beyond it).
int64_t beyond_the_room = 0;

// A start of a walk on grid g: levels and phases of every size up to the top, most of
// them far below it, a room of levels going up or down (levels stay >= 1 going down).
RampWalk random_start(std::mt19937_64& rng, const IntervalGrid& g, int64_t top_level,
                      int64_t top_left, int64_t& dir, int64_t& room) {
  dir = rng() % 2 ? 1 : -1;
  RampWalk start;
  start.level = pick(rng, 1, int64_t{1} << pick(rng, 0, 63 - __builtin_clzll(top_level)));
  start.t = pick(rng, 0, 1'000'000);
  start.end = start.t + pick(rng, 0, g.q + 1);
  // At most a few thousand intervals to the step (the reference walks each).
  const int64_t reach = std::min(top_left, start.level * (g.q + 1) * 2'000);
  start.left = pick(rng, 1, int64_t{1} << pick(rng, 0, 63 - __builtin_clzll(reach)));
  start.rem = pick(rng, 0, g.den - 1);
  room = dir > 0 ? pick(rng, 0, 1'000'000) : pick(rng, 0, start.level - 1);
  return start;
}

// The level changes the walk made to reach its step (0 where it did not, or not asked).
int64_t expect_same_walk(std::mt19937_64& rng, const IntervalGrid& g, int64_t top_level,
                         int64_t top_left) {
  int64_t dir = 0, room = 0;
  const RampWalk start = random_start(rng, g, top_level, top_left, dir, room);
  if (start.level * (start.end - start.t) >= start.left) return 0;  // the caller's case
  RampWalk walked = start, solved = start;
  const bool a = walk_levels(walked, g, dir, room);
  const bool b = walk_to_step(solved, g, dir, room);
  EXPECT_EQ(a, b) << "q " << g.q << " rho " << g.rho << " den " << g.den << " L " << start.level
                  << " left " << start.left << " dir " << dir;
  if (a != b) return 0;
  // Found or not (then at the room's last interval, where the generator's loop goes on).
  expect_same(walked, solved);
  if (!a && walked.passed >= 5) ++beyond_the_room;
  return a ? walked.passed : 0;
}

// Walks `cases` random starts on grids from `make`; most of them must span many levels.
template <typename MakeGrid>
void expect_same_walks(uint64_t seed, int cases, int64_t top_level, int64_t top_left,
                       MakeGrid make) {
  std::mt19937_64 rng(seed);
  int spanning = 0;
  beyond_the_room = 0;
  for (int i = 0; i < cases; ++i) {
    const IntervalGrid g = make(rng);
    if (expect_same_walk(rng, g, top_level, top_left) >= 5) ++spanning;
    if (::testing::Test::HasFailure()) return;
  }
  EXPECT_GT(spanning, cases / 20);  // the cases the solve is for were tried
  EXPECT_GT(beyond_the_room, cases / 100);
}

TEST(RampWalk, EveryAnswerIsTheLevelWalksOnProfileGrids) {
  // CiA 402 and HP grids: Z of 1 to 200 ticks, a fraction of any size (den up to 10^6),
  // levels up to 10^6, up to a step of 5·10^6 phase units.
  expect_same_walks(402, 200'000, 1'000'000, 5'000'000, [](std::mt19937_64& rng) {
    const int64_t den = rng() % 4 == 0 ? 1 : pick(rng, 2, 1'000'000);
    return grid_of(pick(rng, den, den * pick(rng, 1, 200)), den);
  });
}

TEST(RampWalk, ManyCarriesPerStepAndNearlyHalfFractions) {
  // rho/den near 1/2 and near 1: more than 8 carries per step (the floor sum).
  expect_same_walks(13, 100'000, 100'000, 2'000'000, [](std::mt19937_64& rng) {
    const int64_t den = pick(rng, 1'000, 100'000);
    const int64_t rho = rng() % 2 ? den / 2 + pick(rng, -3, 3) : den - pick(rng, 1, 20);
    return grid_of(pick(rng, 1, 3) * den + rho, den);
  });
}

TEST(RampWalk, HugeLevelsAndStepsTakeTheWidePath) {
  // Phases and levels past 2^29 (HP's µHz levels, 64 levels per step/s at 10^8 steps/s):
  // the checks in doubles and the 128-bit walk.
  expect_same_walks(7, 50'000, int64_t{1} << 40, int64_t{1} << 50, [](std::mt19937_64& rng) {
    const int64_t den = pick(rng, 1, 1'000'000'000);
    return grid_of(pick(rng, den, den * 100), den);
  });
}

// The reference of walk_until: StepGenerator::advance_to()'s loop, an interval at a time,
// passing each that holds no step and ends by `until`, at most to the room.
void walk_levels_until(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room, Tick until) {
  while (w.level * (w.end - w.t) < w.left && w.end <= until && w.passed < room) {
    w.left -= w.level * (w.end - w.t);
    w.t = w.end;
    w.level += dir;
    ++w.passed;
    w.end = w.t + g.next_length(w.rem);
  }
}

TEST(RampWalk, UntilATickIsTheLevelWalks) {
  // advance_to() between two steps (a stop, a new velocity) on grids of q >= 1 ticks a
  // level: to the interval of the step, of `until`, or the room's last, whichever comes
  // first; every field against the loop's.
  std::mt19937_64 rng(1206);
  int at_tick = 0, at_step = 0, at_room = 0;
  for (int i = 0; i < 200'000 && !::testing::Test::HasFailure(); ++i) {
    const int64_t den = rng() % 4 == 0 ? 1 : pick(rng, 2, 1'000'000);
    const IntervalGrid g = grid_of(pick(rng, den, den * pick(rng, 1, 200)), den);
    int64_t dir = 0, room = 0;
    const RampWalk start = random_start(rng, g, 1'000'000, 5'000'000, dir, room);
    if (rng() % 2 == 0) room = std::min(room, pick(rng, 1, 40));  // ends before the step too
    if (start.level * (start.end - start.t) >= start.left || room <= 0) continue;
    RampWalk to_step = start;
    walk_levels(to_step, g, dir, room);
    // After w's tick and at or after its interval's end, as advance_to() calls it; up to
    // past the end of the interval the walk to the step stops in.
    const Tick first = std::max(start.end, start.t + 1);
    const Tick until = first + pick(rng, 0, std::max<Tick>(to_step.end - first + 2, 0));
    RampWalk walked = start, solved = start;
    walk_levels_until(walked, g, dir, room, until);
    walk_until(solved, g, dir, room, until);
    expect_same(walked, solved);
    if (::testing::Test::HasFailure()) {
      ADD_FAILURE() << "q " << g.q << " rho " << g.rho << " den " << g.den << " L " << start.level
                    << " left " << start.left << " rem " << start.rem << " end-t "
                    << start.end - start.t << " dir " << dir << " room " << room << " until-end "
                    << until - start.end;
    }
    const bool holds_step = walked.level * (walked.end - walked.t) >= walked.left;
    at_step += holds_step ? 1 : 0;
    at_tick += !holds_step && walked.end > until ? 1 : 0;  // the interval that holds it
    at_room += !holds_step && walked.end <= until ? 1 : 0;
  }
  // Each way of stopping was tried.
  EXPECT_GT(at_tick, 20'000);
  EXPECT_GT(at_step, 20'000);
  EXPECT_GT(at_room, 1'000);
}

TEST(RampWalk, IntervalsOfNoTicksAreSolvedTickByTick) {
  // Z = 1/3: three levels at each tick, tick i at level 10 + 3i; the first 22 add 979 of
  // the 1,000 phase to come, the 23rd holds the step (ramp_step_steep_test.cpp for more).
  RampWalk w{0, 0, 10, 1'000, 0, 0};
  EXPECT_TRUE(walk_to_step(w, grid_of(1, 3), 1, 100));
  EXPECT_EQ(w.t, 22);
  EXPECT_EQ(w.level, 79);
  EXPECT_EQ(w.left, 21);
}

// A move's steps: peeking before each (as the axes do), next() alone, or next() alone with
// every ramp interval walked (walk_ramps(): the generator's loop, nothing solved).
enum class Taking { Peeked, Next, Walked };

std::vector<Tick> run(const RampSpec& r, int64_t distance, Taking taking, std::mt19937_64 rng,
                      int changes) {
  const bool peek = taking == Taking::Peeked;
  StepGenerator g;
  g.walk_ramps(taking == Taking::Walked);
  g.start(r, 0, 1, distance > 0 ? std::optional<int64_t>(distance) : std::nullopt);
  std::vector<Tick> out;
  Step s;
  int64_t change_at = pick(rng, 10, 400);
  while (out.size() < 20'000) {
    if (peek && !g.peek()) break;
    if (!g.next(s)) break;
    out.push_back(s.time);
    if (changes > 0 && static_cast<int64_t>(out.size()) == change_at) {
      --changes;
      change_at += pick(rng, 10, 400);
      // At the step, or (1 in 2) a tick before the next one: the generator first passes
      // the intervals between (advance_to), thousands of them near rest on a fine grid.
      Tick at = s.time;
      if (rng() % 2 == 0) {
        StepGenerator ahead = g;
        Step following;
        if (ahead.next(following)) at += pick(rng, 0, following.time - s.time - 1);
      }
      switch (rng() % 4) {
        case 0: g.change_velocity(at, pick(rng, 1, r.run_level)); break;
        case 1: g.retarget(at, pick(rng, 1, 3'000), r); break;
        case 2: g.stop(at); break;
        default:
          g.stop(at, Rational{r.decel_ticks_per_level.num, 2 * r.decel_ticks_per_level.den});
          break;
      }
    }
  }
  return out;
}

// Random moves with up to three changes (at a step or between two) on grids of `accels`
// and `velocities`: every step peeked, taken by next() alone and walked falls on the same
// tick.
void expect_same_moves(uint64_t seed, int moves, int64_t accel_lo, int64_t accel_hi, int64_t v_lo,
                       int64_t v_hi, int64_t distance_hi) {
  std::mt19937_64 rng(seed);
  int64_t steps = 0;
  for (int i = 0; i < moves; ++i) {
    const int64_t accel = pick(rng, accel_lo, accel_hi), decel = pick(rng, accel_lo, accel_hi);
    const int64_t velocity = pick(rng, v_lo, v_hi);
    const RampSpec r =
        profile_ramp(velocity, accel, decel, profile_levels_per_hz(std::max(accel, decel)));
    const int64_t distance = rng() % 4 == 0 ? 0 : pick(rng, 1, distance_hi);
    const int changes = static_cast<int>(rng() % 4);
    const std::mt19937_64 script(rng());
    const std::vector<Tick> walked = run(r, distance, Taking::Walked, script, changes);
    ASSERT_EQ(run(r, distance, Taking::Peeked, script, changes), walked)
        << "move " << i << ": v " << velocity << " a " << accel << " d " << decel << " distance "
        << distance;
    ASSERT_EQ(run(r, distance, Taking::Next, script, changes), walked) << "move " << i;
    steps += static_cast<int64_t>(walked.size());
  }
  EXPECT_GT(steps, moves * 200);
}

TEST(RampWalk, PeekedStepsAreTheStepLoopsOnRandomMoves) {
  expect_same_moves(2026, 300, 1'000, 2'000'000, 100, 50'000, 30'000);
}

TEST(RampWalk, SlowRampsEndingThousandsOfLevelsFromTheirLastStep) {
  // Slopes of 10 to 5,000 steps/s^2 on their fine grids (64 levels per step/s and finer):
  // near rest a step spans thousands of levels, and a ramp down's last one lies beyond the
  // plain levels peek() solves, so next() solves its way there.
  expect_same_moves(1205, 150, 10, 5'000, 5, 2'000, 3'000);
}

}  // namespace
}  // namespace stepnode::motion
