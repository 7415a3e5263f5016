// The steep ramp walk (q = 0: Z < 1 tick per level, several levels at one tick) against a
// walk from tick to tick that passes each run of 0-long intervals at once as the generator
// does (and that walk against the level-by-level one where levels are few), every field
// compared, on the step and at the room's end; and the generator's steps on random steep
// moves changed mid-way, at a step or between two, against its own step loop with no
// solve (walk_ramps()).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "node/motion/ramp_step.hpp"
#include "node/motion/step_generator.hpp"
#include "node/motion/tests/ramp_walk_check.hpp"

namespace stepnode::motion {
namespace {

using walk_check::expect_same;
using walk_check::pick;

// Log-uniform in 1..hi: every size, most far below hi.
int64_t pick_size(std::mt19937_64& rng, int64_t hi) {
  return pick(rng, 1, int64_t{1} << pick(rng, 0, 63 - __builtin_clzll(hi)));
}

// The reference: one tick at a time, the 0-long intervals after a 1-long one passed
// together (their count the remainder's room before it carries), at most to the room, as
// StepGenerator::end_interval() and skip_empty_intervals() pass them.
void pass_interval(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room) {
  w.left -= w.level * (w.end - w.t);
  w.t = w.end;
  w.level += dir;
  ++w.passed;
  w.rem += g.rho;
  const bool carry = w.rem >= g.den;
  w.rem -= carry ? g.den : 0;
  w.end = w.t + (carry ? 1 : 0);
  if (carry) return;
  const int64_t zeros = std::min((g.den - 1 - w.rem) / g.rho, room - w.passed);
  w.rem += zeros * g.rho;
  w.passed += zeros;
  w.level += dir * zeros;
}

bool walk_ticks(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room) {
  while (w.level * (w.end - w.t) < w.left) {
    if (w.passed >= room) return false;
    pass_interval(w, g, dir, room);
  }
  return true;
}

// A q = 0 grid: Z = num/den log-uniform from just below 1 down to `finest`, den up to top_den.
IntervalGrid steep_grid(std::mt19937_64& rng, double finest, int64_t top_den) {
  const double z = std::exp(std::log(finest) * std::uniform_real_distribution<>(0, 1)(rng));
  const int64_t den = std::max<int64_t>(pick_size(rng, top_den), static_cast<int64_t>(2.0 / z));
  const auto num =
      std::clamp<int64_t>(static_cast<int64_t>(z * static_cast<double>(den)), 1, den - 1);
  return IntervalGrid{0, num, den};
}

// A start on g at most `ticks` ticks from its step (the reference walks each) and a room.
RampWalk steep_start(std::mt19937_64& rng, const IntervalGrid& g, int64_t dir, int64_t top_level,
                     int64_t ticks, int64_t& room) {
  RampWalk w;
  // Past 2^32, half of them near the top (the 128-bit solve's).
  w.level = top_level > (int64_t{1} << 32) && rng() % 2 ? pick(rng, top_level >> 10, top_level)
                                                        : pick_size(rng, top_level);
  w.t = pick(rng, 0, 1'000'000);
  w.end = w.t + pick(rng, 0, 1);
  w.rem = pick(rng, 0, g.den - 1);
  // The phase `ticks` ticks of the ramp add: L·T + (den/rho)·T²/2.
  const double zi = static_cast<double>(g.den) / static_cast<double>(g.rho);
  const auto t = static_cast<double>(pick(rng, 1, ticks));
  const double reach = std::min(static_cast<double>(w.level) * t + zi * t * t / 2, 0x1p62);
  const int64_t most = std::max<int64_t>(static_cast<int64_t>(reach), 1);
  w.left = rng() % 2 ? pick(rng, most / 2 + 1, most) : pick_size(rng, most);
  // Rooms cutting the first tick's run of levels, a few ticks' or (up) all.
  const auto per_tick = static_cast<int64_t>(std::min(zi, 0x1p40)) + 1;
  const int64_t top = dir > 0 ? per_tick * pick(rng, 1, 3 * ticks) : w.level - 1;
  room = rng() % 4 == 0 ? pick(rng, 0, std::min(top, per_tick * 2)) : pick(rng, 0, top);
  return w;
}

struct Spans {
  int found = 0, far = 0, ends = 0;
};

// Solves one random start against the tick walk; counts what it tried.
void expect_same_walk(std::mt19937_64& rng, const IntervalGrid& g, int64_t top_level, int64_t ticks,
                      Spans& spans) {
  const int64_t dir = rng() % 2 ? 1 : -1;
  int64_t room = 0;
  const RampWalk start = steep_start(rng, g, dir, top_level, ticks, room);
  if (start.level * (start.end - start.t) >= start.left) return;  // the caller's case
  RampWalk walked = start, solved = start;
  const bool a = walk_ticks(walked, g, dir, room);
  const bool b = walk_to_step(solved, g, dir, room);
  EXPECT_EQ(a, b);
  expect_same(walked, solved);  // at the step, or where the room ends
  if (::testing::Test::HasFailure()) {
    ADD_FAILURE() << "rho " << g.rho << " den " << g.den << " L " << start.level << " left "
                  << start.left << " rem " << start.rem << " end-t " << start.end - start.t
                  << " dir " << dir << " room " << room;
  }
  spans.found += a ? 1 : 0;
  spans.far += walked.t - start.t >= 5 ? 1 : 0;
  spans.ends += a ? 0 : 1;
}

void expect_same_walks(uint64_t seed, int cases, double finest, int64_t top_den, int64_t top_level,
                       int64_t ticks) {
  std::mt19937_64 rng(seed);
  Spans spans;
  for (int i = 0; i < cases && !::testing::Test::HasFailure(); ++i)
    expect_same_walk(rng, steep_grid(rng, finest, top_den), top_level, ticks, spans);
  // The cases the solve is for were tried: steps many ticks on, and rooms ending first.
  EXPECT_GT(spans.far, cases / 4);
  EXPECT_GT(spans.found, cases / 4);
  EXPECT_GT(spans.ends, cases / 20);
}

TEST(SteepWalk, EveryAnswerIsTheTickWalksOnProfileGrids) {
  // CiA 402 above 4.9 M steps/s^2 (1 level per step/s): num 4,915,200, den the
  // acceleration, levels up to 10^6, up to 3,000 ticks to the step.
  std::mt19937_64 rng(402);
  Spans spans;
  const int cases = 100'000;
  for (int i = 0; i < cases && !::testing::Test::HasFailure(); ++i) {
    const IntervalGrid g{0, kClockHz, pick(rng, kClockHz + 1, 2'000'000'000)};
    expect_same_walk(rng, g, 1'000'000, 3'000, spans);
  }
  EXPECT_GT(spans.far, cases / 4);
  EXPECT_GT(spans.ends, cases / 20);
}

TEST(SteepWalk, EveryAnswerIsTheTickWalksOnFineGrids) {
  // Z from just below 1 down to 10^-6, den up to 2^40.
  expect_same_walks(13, 100'000, 1e-6, int64_t{1} << 40, 1'000'000, 2'000);
}

TEST(SteepWalk, HugeLevelsAndStepsTakeTheWidePath) {
  // Levels to 2^40 and phases to 2^60: the 128-bit solve.
  expect_same_walks(7, 30'000, 1e-6, int64_t{1} << 40, int64_t{1} << 40, 1'000);
}

TEST(SteepWalk, TheTickWalkIsTheLevelWalk) {
  // The reference itself against walk_levels, which passes each level (Z near 1: few
  // levels per tick).
  std::mt19937_64 rng(5);
  for (int i = 0; i < 50'000 && !::testing::Test::HasFailure(); ++i) {
    const IntervalGrid g = steep_grid(rng, 0.05, 1'000'000);
    const int64_t dir = rng() % 2 ? 1 : -1;
    int64_t room = 0;
    const RampWalk start = steep_start(rng, g, dir, 10'000, 300, room);
    RampWalk by_ticks = start, by_levels = start;
    EXPECT_EQ(walk_ticks(by_ticks, g, dir, room), walk_levels(by_levels, g, dir, room));
    expect_same(by_ticks, by_levels);
  }
}

// The reference of walk_until: StepGenerator::advance_to()'s loop, an interval at a
// time (the 0-long ones after a 1-long one together), passing each that holds no step and
// ends by `until` until it reaches that tick, at most to the room.
void walk_ticks_until(RampWalk& w, const IntervalGrid& g, int64_t dir, int64_t room, Tick until) {
  while (w.level * (w.end - w.t) < w.left && w.end <= until && w.t < until && w.passed < room)
    pass_interval(w, g, dir, room);
}

TEST(SteepWalk, UntilATickIsTheTickWalks) {
  // advance_to() between two steps: to the interval of the step, of `until`, or the room's
  // last, whichever comes first; every field against the loop's.
  std::mt19937_64 rng(304);
  int at_tick = 0, at_step = 0, at_room = 0;
  for (int i = 0; i < 100'000 && !::testing::Test::HasFailure(); ++i) {
    const IntervalGrid g = rng() % 2
                               ? IntervalGrid{0, kClockHz, pick(rng, kClockHz + 1, 2'000'000'000)}
                               : steep_grid(rng, 1e-6, int64_t{1} << 40);
    const int64_t dir = rng() % 2 ? 1 : -1;
    int64_t room = 0;
    const RampWalk start = steep_start(rng, g, dir, 1'000'000, 3'000, room);
    if (start.level * (start.end - start.t) >= start.left || room <= 0) continue;
    RampWalk to_step = start;
    walk_ticks(to_step, g, dir, room);
    // After w's tick and at or after its interval's end, as advance_to() calls it.
    const Tick first = std::max(start.end, start.t + 1);
    const Tick until = first + pick(rng, 0, std::max<Tick>(to_step.t - first + 2, 0));
    RampWalk walked = start, solved = start;
    walk_ticks_until(walked, g, dir, room, until);
    walk_until(solved, g, dir, room, until);
    expect_same(walked, solved);
    if (::testing::Test::HasFailure()) {
      ADD_FAILURE() << "rho " << g.rho << " den " << g.den << " L " << start.level << " left "
                    << start.left << " rem " << start.rem << " end-t " << start.end - start.t
                    << " dir " << dir << " room " << room << " until-end " << until - start.end;
    }
    const bool holds_step = walked.level * (walked.end - walked.t) >= walked.left;
    at_step += holds_step ? 1 : 0;
    at_tick += !holds_step && walked.t == until ? 1 : 0;  // its interval, or a 0-long one at it
    at_room += !holds_step && walked.t < until ? 1 : 0;
  }
  // Each way of stopping was tried.
  EXPECT_GT(at_tick, 10'000);
  EXPECT_GT(at_step, 10'000);
  EXPECT_GT(at_room, 2'000);
}

TEST(SteepWalk, ThreeLevelsPerTick) {
  // Z = 1/3 from level 10, 1,000 phase to come: tick i runs at level 10 + 3i, the first
  // 22 add 979, the 23rd (level 79) holds the step.
  RampWalk w{0, 0, 10, 1'000, 0, 0};
  EXPECT_TRUE(walk_to_step(w, IntervalGrid{0, 1, 3}, 1, 100));
  expect_same(w, RampWalk{22, 23, 79, 21, 69, 0});
  // A room of 50 levels ends in the 16th tick's run (levels 59, 60: 0 long) first, the 16
  // ticks adding 568.
  RampWalk cut{0, 0, 10, 1'000, 0, 0};
  EXPECT_FALSE(walk_to_step(cut, IntervalGrid{0, 1, 3}, 1, 50));
  expect_same(cut, RampWalk{16, 16, 60, 432, 50, 2});
}

// A steep move's steps: peek() then next() (as the axes do), next() alone, or the loop
// with nothing solved; changed mid-way by the same script.
enum class Taking { Peeked, Next, Walked };

std::vector<Tick> run(const RampSpec& r, int64_t distance, Taking taking, std::mt19937_64 rng,
                      int changes, Rational quick) {
  StepGenerator g;
  g.walk_ramps(taking == Taking::Walked);
  g.start(r, 0, 1, distance > 0 ? std::optional<int64_t>(distance) : std::nullopt);
  std::vector<Tick> out;
  Step s;
  int64_t change_at = pick(rng, 1, 300);
  while (out.size() < 20'000) {
    if (taking == Taking::Peeked && !g.peek()) break;
    if (!g.next(s)) break;
    out.push_back(s.time);
    if (changes > 0 && static_cast<int64_t>(out.size()) == change_at) {
      --changes;
      change_at += pick(rng, 1, 300);
      // At the step, or (3 in 4) a tick before the next one: the generator first passes
      // the ticks between (advance_to), up to thousands of them near rest.
      const double within = rng() % 4 == 0 ? 0.0 : std::uniform_real_distribution<>(0, 1)(rng);
      StepGenerator ahead = g;
      Step following;
      const Tick gap = ahead.next(following) ? following.time - s.time : 0;
      const Tick at = s.time + static_cast<Tick>(within * static_cast<double>(gap));
      switch (rng() % 4) {
        case 0: g.change_velocity(at, pick(rng, 1, r.run_level)); break;
        case 1: g.retarget(at, pick(rng, 1, 3'000), r); break;
        case 2: g.stop(at); break;
        default: g.stop(at, quick); break;
      }
    }
  }
  return out;
}

TEST(SteepWalk, PeekedStepsAreTheStepLoopsOnRandomSteepMoves) {
  std::mt19937_64 rng(2027);
  int64_t steps = 0;
  for (int i = 0; i < 400; ++i) {
    // Accelerations from just above 4.9 M steps/s^2 (Z just below 1) to 10^10 (2,000
    // levels per tick); now and then one ramp of the two is not steep.
    const auto steep = [&] {
      return pick(rng, kClockHz + 1, pick(rng, 0, 1) ? 50'000'000 : 10'000'000'000);
    };
    const int64_t accel = rng() % 8 == 0 ? pick(rng, 1'000, 4'000'000) : steep();
    const int64_t decel = rng() % 8 == 0 ? pick(rng, 1'000, 4'000'000) : steep();
    const int64_t velocity = pick(rng, 10, 1'000'000);
    const RampSpec r =
        profile_ramp(velocity, accel, decel, profile_levels_per_hz(std::max(accel, decel)));
    const int64_t distance = rng() % 4 == 0 ? 0 : pick(rng, 1, 20'000);
    const int changes = static_cast<int>(rng() % 4);
    const Rational quick = slope_ticks_per_level(steep(), r.phase_per_step / kClockHz);
    const std::mt19937_64 script(rng());
    const std::vector<Tick> walked = run(r, distance, Taking::Walked, script, changes, quick);
    ASSERT_EQ(run(r, distance, Taking::Peeked, script, changes, quick), walked)
        << "move " << i << ": v " << velocity << " a " << accel << " d " << decel << " distance "
        << distance;
    ASSERT_EQ(run(r, distance, Taking::Next, script, changes, quick), walked) << "move " << i;
    steps += static_cast<int64_t>(walked.size());
  }
  EXPECT_GT(steps, 100'000);
}

}  // namespace
}  // namespace stepnode::motion
