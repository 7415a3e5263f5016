// The S-curve's quick step search against its full search (SCurve::use_full_search: the
// Newton estimate and exact check of a fresh cubic evaluation per step, as every step was
// found before the quick search): over random moves and velocity motions, with stops,
// velocity changes and new targets in the middle, every step must fall on the same tick.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>

#include "node/motion/s_curve.hpp"

namespace stepnode::motion {
namespace {

struct Pair {
  SCurve quick, full;
};

JerkLimits random_limits(std::mt19937_64& rng) {
  auto log_uniform = [&](double lo, double hi) {
    return lo * std::pow(hi / lo, std::uniform_real_distribution<double>(0, 1)(rng));
  };
  auto jerk = [&]() -> uint32_t {
    if (rng() % 8 == 0) return 0;  // not limited
    return static_cast<uint32_t>(log_uniform(1e3, 4e9));
  };
  JerkLimits l;
  l.velocity = log_uniform(1, 60'000);
  l.acceleration = log_uniform(10, 2e6);
  l.deceleration = log_uniform(10, 2e6);
  l.begin_accel_jerk = jerk();
  l.end_accel_jerk = jerk();
  l.begin_decel_jerk = jerk();
  l.end_decel_jerk = jerk();
  return l;
}

// A change at a tick between the last step and the next (as a drive gives it).
void random_change(std::mt19937_64& rng, Pair& p, Tick last, const JerkLimits& l) {
  const std::optional<Tick> next = p.full.peek();
  const Tick room = next ? std::max<Tick>(0, *next - 1 - last) : 1000;
  const Tick at = last + static_cast<Tick>(rng() % static_cast<uint64_t>(room + 1));
  switch (rng() % 4) {
    case 0: {
      const std::optional<double> decel =
          rng() % 2 ? std::optional<double>(l.deceleration * 3) : std::nullopt;
      p.quick.stop(at, decel);
      p.full.stop(at, decel);
      break;
    }
    case 1: {
      const double v = l.velocity * std::uniform_real_distribution<double>(0.1, 2)(rng);
      p.quick.change_velocity(at, v);
      p.full.change_velocity(at, v);
      break;
    }
    default: {
      const int64_t to = p.full.steps() + 1 + static_cast<int64_t>(rng() % 3000);
      p.quick.retarget(at, to);
      p.full.retarget(at, to);
      break;
    }
  }
}

TEST(SCurveProperty, QuickSearchEqualsTheFullSearchOnEveryStep) {
  std::mt19937_64 rng(20240613);
  int64_t steps = 0, quick = 0, even = 0;
  for (int move = 0; move < 300; ++move) {
    const JerkLimits l = random_limits(rng);
    const bool to_target = rng() % 3 != 0;
    const std::optional<int64_t> distance =
        to_target ? std::optional<int64_t>(1 + static_cast<int64_t>(rng() % 6000)) : std::nullopt;
    Pair p;
    p.full.use_full_search();
    const Tick start = static_cast<Tick>(rng() % 100'000);
    p.quick.start(l, start, distance);
    p.full.start(l, start, distance);
    // Up to two changes, each at a random step; a velocity motion is stopped by 8000 steps.
    int64_t change_at[2] = {static_cast<int64_t>(rng() % 4000), static_cast<int64_t>(rng() % 8000)};
    if (rng() % 3 == 0) change_at[0] = change_at[1] = -1;
    Tick last = start;
    for (int64_t n = 0; n < 20'000; ++n) {
      if (n == change_at[0] || n == change_at[1]) random_change(rng, p, last, l);
      if (!distance && n == 8000) p.full.stop(last), p.quick.stop(last);
      const std::optional<Tick> a = p.quick.next_step(), b = p.full.next_step();
      ASSERT_EQ(a, b) << "move " << move << " step " << n + 1;
      ASSERT_EQ(p.quick.velocity(), p.full.velocity()) << "move " << move << " step " << n + 1;
      if (!a) break;
      ASSERT_GT(*a, last - (n == 0 ? 1 : 0)) << "move " << move << " step " << n + 1;
      last = *a;
      ++steps;
    }
    EXPECT_EQ(p.quick.end(), p.full.end()) << "move " << move;
    quick += p.quick.quick_steps();
    even += p.quick.even_steps();
  }
  // The comparison means something only if the quick search found most steps.
  EXPECT_GT(steps, 300'000);
  EXPECT_GT(quick, steps * 9 / 10) << quick << " of " << steps;
  // ... and its constant-velocity path (cruises, holds, creeps) a good part of them.
  EXPECT_GT(even, steps / 4) << even << " of " << steps;
  std::printf("%lld steps, %lld by the quick search, %lld of those at a constant velocity\n",
              static_cast<long long>(steps), static_cast<long long>(quick),
              static_cast<long long>(even));
}

// The batch (SCurve::batch: steps found in doubles, each proven by an error bound) from
// random steps of the same moves: every step it gives on the full search's tick, and the
// motion after a part of it taken (take_batch) going on with the full search's steps.
TEST(SCurveProperty, ABatchHoldsTheFullSearchsNextSteps) {
  std::mt19937_64 rng(20261206);
  int64_t steps = 0, batched = 0, taken = 0;
  for (int move = 0; move < 300; ++move) {
    JerkLimits l = random_limits(rng);
    if (move % 5 == 0) {  // up to nearly a step per tick, with fast ramps
      l.velocity *= 80;
      l.acceleration *= 400, l.deceleration *= 400;
    }
    const std::optional<int64_t> distance =
        rng() % 3 != 0 ? std::optional<int64_t>(1 + static_cast<int64_t>(rng() % 6000))
                       : std::nullopt;
    Pair p;
    p.full.use_full_search();
    p.quick.start(l, 0, distance);
    p.full.start(l, 0, distance);
    const int64_t change_at = static_cast<int64_t>(rng() % 4000);
    Tick last = 0;
    for (int64_t n = 0; n < 12'000; ++n) {
      if (n == change_at) random_change(rng, p, last, l);
      if (!distance && n == 6000) p.full.stop(last), p.quick.stop(last);
      std::array<Tick, 32> out{};
      const int k = rng() % 4 == 0 ? p.quick.batch(out.data(), 32) : 0;
      if (k > 0) {
        SCurve ahead = p.full;
        for (int i = 0; i < k; ++i) {
          ASSERT_EQ(out[i], ahead.next_step()) << "move " << move << " step " << n << "+" << i;
          ASSERT_FALSE(ahead.ended()) << "a batch holds no motion's last step";
        }
        batched += k;
        const int take = 1 + static_cast<int>(rng() % static_cast<uint64_t>(k));
        p.quick.take_batch(out.data(), take);
        for (int i = 0; i < take; ++i) p.full.next_step();
        ASSERT_EQ(p.quick.steps(), p.full.steps());
        ASSERT_EQ(p.quick.velocity(), p.full.velocity()) << "move " << move << " step " << n;
        taken += take;
        last = out[take - 1];
        continue;
      }
      const std::optional<Tick> a = p.quick.next_step(), b = p.full.next_step();
      ASSERT_EQ(a, b) << "move " << move << " step " << n + 1;
      if (!a) break;
      last = *a;
      ++steps;
    }
    EXPECT_EQ(p.quick.end(), p.full.end()) << "move " << move;
  }
  EXPECT_GT(steps, 100'000);
  EXPECT_GT(batched, 1'000'000) << batched;
  EXPECT_GT(taken, 100'000) << taken;
}

// The constant-velocity path (s_curve_even.cpp) across the whole range of velocities: from
// steps 40 minutes apart to nearly a step per tick, where its q and r are at their ends,
// held open or cruising to a target, stopped or changed in the middle of a cruise (its
// step then re-found by the searches): every step on the full search's tick.
TEST(SCurveProperty, ConstantVelocityStepsEqualTheFullSearch) {
  std::mt19937_64 rng(20261205);
  int64_t steps = 0, even = 0;
  for (int move = 0; move < 240; ++move) {
    JerkLimits l;
    const double lo = std::log(4e-4), hi = std::log(4.9e6);  // up to 0.997 steps per tick
    l.velocity = std::exp(std::uniform_real_distribution<double>(lo, hi)(rng));
    l.acceleration = l.deceleration = std::max(1.0, l.velocity) * 40;  // a short ramp
    const uint32_t j = static_cast<uint32_t>(std::min(4e9, l.acceleration * 200));
    l.begin_accel_jerk = l.end_accel_jerk = l.begin_decel_jerk = l.end_decel_jerk = j;
    const std::optional<int64_t> distance =
        move % 2 ? std::optional<int64_t>(2000 + static_cast<int64_t>(rng() % 4000)) : std::nullopt;
    Pair p;
    p.full.use_full_search();
    p.quick.start(l, 0, distance);
    p.full.start(l, 0, distance);
    const int64_t change_at = move % 3 == 0 ? 1000 + static_cast<int64_t>(rng() % 1000) : -1;
    Tick last = 0;
    for (int64_t n = 0; n < 3000; ++n) {
      if (n == change_at) random_change(rng, p, last, l);
      const std::optional<Tick> a = p.quick.next_step(), b = p.full.next_step();
      ASSERT_EQ(a, b) << "move " << move << " v " << l.velocity << " step " << n + 1;
      ASSERT_EQ(p.quick.velocity(), p.full.velocity()) << "move " << move << " step " << n + 1;
      if (!a) break;
      last = *a;
      ++steps;
    }
    even += p.quick.even_steps();
  }
  EXPECT_GT(steps, 500'000);
  EXPECT_GT(even, steps * 3 / 4) << even << " of " << steps;
}

}  // namespace
}  // namespace stepnode::motion
