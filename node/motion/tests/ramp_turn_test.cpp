// Where a move too short for its running velocity turns (RampSpec::ShortMove::Meet, the
// profile ramps: HP PROFILE FREQ, CiA 402 profile position): after the first step of the
// ramp up at which the phase still to come, (distance - steps)·D, is no more than the ramp
// down from the current level adds (Z_D·sum(base + 1 .. level)) plus the accumulator's
// phase; a move that reaches its run level ramps down from the tick where the phase to come
// equals that of the ramp down. The reference below is the phase-accumulator model written
// from those rules and the ramp's definition alone: interval k of a ramp lasts
// floor((k+1)·Z) - floor(k·Z) ticks, every step the first tick at which the accumulator
// reaches D. The generator, which asks its turn test only near the end of the ramp up
// (issue 13), must give every step of it, also after a change of velocity or of the end on
// the way (and one that comes after the ramp down's first tick finds it ramping down).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "node/motion/hp_profile.hpp"
#include "node/motion/step_generator.hpp"

namespace stepnode::motion {
namespace {

Tick interval_ticks(Rational z, int64_t k) {
  const __int128 num = z.num;
  return static_cast<Tick>((k + 1) * num / z.den - k * num / z.den);
}

// The phase the generator counts for the ramp down from `level` (RampSpec::decel_phase's
// definition, ramp.hpp): Z_D·sum(base + 1 .. level), rounded down. The ramp's intervals add
// within a tick per level of it.
__int128 ramp_down_phase(const RampSpec& r, int64_t level) {
  const __int128 levels =
      static_cast<__int128>(level - r.base_level) * (level + r.base_level + 1) / 2;
  return levels * r.decel_ticks_per_level.num / r.decel_ticks_per_level.den;
}

// A change at tick `at`, no step at it. A velocity (StepGenerator::change_velocity): a higher
// level ramps up to it from there, its intervals counted from `at`, and the move keeps its
// target, so it may have to turn on the way. Or, with `steps`, a nearer end
// (StepGenerator::retarget): the move ends `steps` steps from there, its ramp down at
// `decel` ticks per level from then on.
struct Change {
  Tick at = -1;
  int64_t level = 0;
  int64_t steps = 0;
  Rational decel;
  // The model's answers: the change came in the run; the tick the ramp down to the target
  // began (-1: none, or not from the run).
  bool in_run = false;
  Tick ramp_down_began = -1;
};

// The step times of a move of `distance` steps from tick 0, run_level > base_level.
std::vector<Tick> model_steps(RampSpec r, int64_t distance, Change& change) {
  enum { Up, Run, Down, Creep } phase = Up;
  const int64_t d = r.phase_per_step;
  std::vector<Tick> steps;
  Tick t = 0, decel_at = -1;
  int64_t acc = 0, level = r.base_level + 1, k = 0, peak = r.run_level;
  Tick end = interval_ticks(r.accel_ticks_per_level, 0);
  Tick change_at = change.at;  // -1 once made
  const auto turn = [&] {
    phase = Down, k = 0;
    end = t + interval_ticks(r.decel_ticks_per_level, 0);
  };
  const auto plan_ramp_down = [&] {  // in the run: where the phase to come equals its phase
    const __int128 target = static_cast<__int128>(distance) * d - ramp_down_phase(r, level);
    const __int128 now = static_cast<__int128>(steps.size()) * d + acc;
    decel_at = now >= target ? t : t + static_cast<Tick>((target - now + level - 1) / level);
  };
  while (static_cast<int64_t>(steps.size()) < distance) {
    const Tick need = (d - acc + level - 1) / level;  // ticks to the accumulator's step
    const bool ends = phase == Up || phase == Down;
    // The change comes first, unless an interval ends or the ramp down begins by its tick.
    if (change_at >= 0 && t + need > change_at && (!ends || end > change_at) &&
        (phase != Run || decel_at > change_at)) {
      acc += level * (change_at - t), t = change_at;
      change.in_run = phase == Run;
      change_at = -1;
      if (change.steps > 0) {
        distance = static_cast<int64_t>(steps.size()) + change.steps;
        r.decel_ticks_per_level = change.decel;
        if (phase == Run) plan_ramp_down();
      } else if (change.level > level) {
        phase = Up, peak = change.level, k = 0, ++level;
        end = t + interval_ticks(r.accel_ticks_per_level, 0);
      }
      continue;
    }
    if (phase == Run && t + need > decel_at) {  // the ramp down's first tick comes first
      change.ramp_down_began = decel_at;
      acc += level * (decel_at - t), t = decel_at;
      turn();
      continue;
    }
    if (ends && t + need > end) {  // the interval ends first
      acc += level * (end - t), t = end;
      if (phase == Up && level == peak) {
        phase = Run;
        plan_ramp_down();
      } else if (phase == Down && level == r.base_level + 1) {
        phase = Creep, level = std::max(r.base_level, r.min_creep_level);
      } else {
        level += phase == Up ? 1 : -1;
        end = t +
              interval_ticks(phase == Up ? r.accel_ticks_per_level : r.decel_ticks_per_level, ++k);
      }
      continue;
    }
    t += need, acc += level * need - d;
    steps.push_back(t);
    const int64_t left = distance - static_cast<int64_t>(steps.size());
    if (phase == Up && left > 0 &&
        static_cast<__int128>(left) * d <= ramp_down_phase(r, level) + acc)
      turn();
  }
  return steps;
}

std::vector<Tick> model_steps(const RampSpec& r, int64_t distance) {
  Change none;
  return model_steps(r, distance, none);
}

std::vector<Tick> generator_steps(const RampSpec& r, int64_t distance, Change change = {}) {
  StepGenerator g;
  g.start(r, 0, +1, distance);
  std::vector<Tick> steps;
  for (Step s; g.peek();) {
    if (change.at >= 0 && *g.peek() > change.at) {
      RampSpec nearer = r;
      nearer.decel_ticks_per_level = change.decel;
      if (change.steps > 0) g.retarget(change.at, change.steps, nearer);
      else g.change_velocity(change.at, change.level);
      change.at = -1;
    } else if (g.next(s)) {
      steps.push_back(s.time);
      if (steps.size() > static_cast<size_t>(distance)) break;  // never: it ends at the target
    }
  }
  return steps;
}

std::string describe(const RampSpec& r) {
  std::ostringstream o;
  o << "D " << r.phase_per_step << ", levels " << r.base_level << ".." << r.run_level << ", Z_A "
    << r.accel_ticks_per_level.num << "/" << r.accel_ticks_per_level.den << ", Z_D "
    << r.decel_ticks_per_level.num << "/" << r.decel_ticks_per_level.den;
  return o.str();
}

// Distances around each turn: from a few steps to past the whole ramp up and down.
void expect_every_distance(const RampSpec& r, int64_t most, const char* what) {
  for (int64_t distance = 1; distance <= most; ++distance) {
    const std::vector<Tick> want = model_steps(r, distance);
    ASSERT_EQ(generator_steps(r, distance), want)
        << what << ": " << describe(r) << ", " << distance << " steps";
  }
}

class RandomRamps {
 public:
  RandomRamps() : rng_(13) {}
  int64_t pick(int64_t lo, int64_t hi) {
    return std::uniform_int_distribution<int64_t>(lo, hi)(rng_);
  }
  // With `steep`, ramps of several levels at one tick too (Z < 1).
  RampSpec next(bool steep = true) {
    RampSpec r;
    r.base_level = pick(0, 40);
    r.run_level = r.base_level + pick(2, 600);
    r.phase_per_step = r.run_level * pick(1, 30) + pick(0, r.run_level);
    // From several levels a tick (Z < 1) to tens of ticks a level; the ramp down steeper or
    // gentler than the ramp up.
    r.accel_ticks_per_level = {pick(1, 4000), pick(1, 200)};
    r.decel_ticks_per_level = {pick(1, 4000), pick(1, 200)};
    for (Rational* z : {&r.accel_ticks_per_level, &r.decel_ticks_per_level})
      if (!steep) z->num = std::max(z->num, z->den);
    r.min_creep_level = std::max<int64_t>(1, r.base_level);
    return r;
  }
  // The steps of the ramp up and down at the run level.
  static int64_t whole(const RampSpec& r) {
    return static_cast<int64_t>((r.accel_phase(r.run_level) + r.decel_phase(r.run_level)) /
                                r.phase_per_step);
  }

 private:
  std::mt19937_64 rng_;
};

TEST(RampTurn, ShortMovesTurnAtTheFirstStepTheRampDownNeeds) {
  RandomRamps ramps;
  for (int i = 0; i < 300; ++i) {
    const RampSpec r = ramps.next();
    expect_every_distance(r, std::min<int64_t>(RandomRamps::whole(r) + 3, 400), "random ramp");
  }
}

// How many changes were compared, and how many of those came in the run.
struct Compared {
  int all = 0, in_run = 0;
};

// The change made one tick after the move's step j (j + 2 <= distance), or at its own tick
// (between steps j and j + 1), compared, unless there is a step at that tick.
void expect_change(const RampSpec& r, int64_t distance, size_t j, Change change,
                   Compared& compared) {
  const std::vector<Tick> before = model_steps(r, distance);
  if (change.at < 0) change.at = before[j] + 1;
  if (before[j + 1] == change.at) return;
  const std::vector<Tick> want = model_steps(r, distance, change);
  ++compared.all;
  compared.in_run += change.in_run ? 1 : 0;
  EXPECT_EQ(generator_steps(r, distance, change), want)
      << describe(r) << ", " << distance << " steps, at tick " << change.at << ": level "
      << change.level << " or the end " << change.steps << " steps on, Z_D " << change.decel.num
      << "/" << change.decel.den;
}

TEST(RampTurn, AHigherVelocityOnTheWayKeepsTheTurn) {
  // change_velocity() above the run level, in the ramp up, the run or the ramp down: the
  // peak the turn is reckoned from rises. (Z >= 1
  // here: at Z < 1 a change at a tick where several levels change leaves the last 0-long
  // interval at that tick to the new ramp, a convention this model does not write out.)
  RandomRamps ramps;
  Compared compared;
  for (int i = 0; i < 3000 && !HasFailure(); ++i) {
    const RampSpec r = ramps.next(false);
    const int64_t distance = ramps.pick(2, std::min<int64_t>(2 * RandomRamps::whole(r) + 3, 400));
    Change change;
    change.level = r.run_level + ramps.pick(1, 2000);
    const auto j = static_cast<size_t>(ramps.pick(0, distance - 2));
    expect_change(r, distance, j, change, compared);
  }
  EXPECT_GT(compared.all, 2500);
  EXPECT_GT(compared.in_run, 100);
}

TEST(RampTurn, ANearerEndOnTheWayTurnsForIt) {
  // retarget() (an indexed move's index) brings the end nearer and changes the ramp down,
  // in the ramp up, the run or the ramp down.
  RandomRamps ramps;
  Compared compared;
  for (int i = 0; i < 3000 && !HasFailure(); ++i) {
    const RampSpec r = ramps.next(false);  // Z >= 1: see AHigherVelocityOnTheWayKeepsTheTurn
    const int64_t distance = ramps.pick(3, std::min<int64_t>(2 * RandomRamps::whole(r) + 3, 400));
    const int64_t j = ramps.pick(0, distance - 3);
    const int64_t z = ramps.pick(200, 4000);
    Change change;
    change.steps = ramps.pick(1, distance - j - 2);
    change.decel = {z, ramps.pick(1, z / 2)};
    expect_change(r, distance, static_cast<size_t>(j), change, compared);
  }
  EXPECT_GT(compared.all, 2500);
  EXPECT_GT(compared.in_run, 100);
}

TEST(RampTurn, AChangeAfterTheRampDownBeganFindsItRampingDown) {
  // A change between the ramp down's first tick and the step after it (a run to a target,
  // its ramp down begun on the tick where the phase to come equals the ramp's): the motion
  // is ramping down from that tick, not still running.
  RandomRamps ramps;
  Compared compared;
  for (int i = 0; i < 3000 && !HasFailure(); ++i) {
    const RampSpec r = ramps.next(false);  // Z >= 1: see AHigherVelocityOnTheWayKeepsTheTurn
    const int64_t whole = RandomRamps::whole(r);
    if (whole + 5 > 400) continue;
    const int64_t distance = ramps.pick(whole + 5, 400);
    Change none;
    const std::vector<Tick> before = model_steps(r, distance, none);
    const Tick began = none.ramp_down_began;
    if (began <= before.front()) continue;  // none (-1), or before the first step
    const auto j = static_cast<size_t>(std::upper_bound(before.begin(), before.end(), began) -
                                       before.begin() - 1);
    if (j + 3 > before.size() || before[j + 1] - began < 2) continue;  // a step left after it
    Change change;
    change.at = ramps.pick(began + 1, before[j + 1] - 1);
    if (i % 2 == 0) {
      change.level = r.run_level + ramps.pick(1, 2000);
    } else {
      change.steps = ramps.pick(1, distance - static_cast<int64_t>(j) - 2);
      const int64_t z = ramps.pick(200, 4000);
      change.decel = {z, ramps.pick(1, z / 2)};
    }
    expect_change(r, distance, j, change, compared);
  }
  EXPECT_GT(compared.all, 500);
}

TEST(RampTurn, ProfileRampsTurnAtTheFirstStepTheRampDownNeeds) {
  // The grids the front ends make: HP PROFILE FREQ (Hz, Hz/s) and CiA 402 (steps/s, /s²).
  hp::Profile p;
  p.min = 20, p.max = 2'000, p.slope = 150'000, p.last = 50e-6;
  expect_every_distance(hp::freq_ramp(p, p.max), 60, "HP PROFILE FREQ 20 2000 150000");
  expect_every_distance(profile_ramp(3'000, 400'000, 900'000, profile_levels_per_hz(400'000)), 60,
                        "CiA 402 3000 steps/s, 400,000 up, 900,000 down");
  expect_every_distance(profile_ramp(3'000, 900'000, 400'000, profile_levels_per_hz(400'000)), 60,
                        "CiA 402 3000 steps/s, 900,000 up, 400,000 down");
}

}  // namespace
}  // namespace stepnode::motion
