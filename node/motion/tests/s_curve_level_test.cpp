// The S-curve's level (StepGenerator::level(), velocity(), marks().peak_level) is computed
// when read, from the S-curve's state at the last step or change. Here it must equal the
// level worked out the eager way at every step and change (as the generator did before):
// a twin SCurve run beside the generator, its velocity converted at every step, over random
// moves and velocity motions with stops, velocity changes, new targets and regrids, read
// at random points.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "node/motion/ramp.hpp"
#include "node/motion/s_curve.hpp"
#include "node/motion/s_curve_scale.hpp"
#include "node/motion/step_generator.hpp"

namespace stepnode::motion {
namespace {

constexpr double kHz = static_cast<double>(kClockHz);

// The reference: round half up of x >= 0 (0 below), as the generator's level_of().
int64_t eager_level(double x) { return x > 0 ? std::llround(x) : 0; }

double slope_of(const RampSpec& r, Rational z) {
  return kHz * kHz * static_cast<double>(z.den) /
         (static_cast<double>(z.num) * static_cast<double>(r.phase_per_step));
}

JerkLimits limits_of(const RampSpec& r) {
  JerkLimits l;
  l.velocity = r.velocity_of(r.run_level);
  l.acceleration = slope_of(r, r.accel_ticks_per_level);
  l.deceleration = slope_of(r, r.decel_ticks_per_level);
  l.begin_accel_jerk = r.jerk[0];
  l.begin_decel_jerk = r.jerk[1];
  l.end_accel_jerk = r.jerk[2];
  l.end_decel_jerk = r.jerk[3];
  return l;
}

RampSpec random_ramp(std::mt19937_64& rng) {
  auto pick = [&](int64_t lo, int64_t hi) {
    return lo + static_cast<int64_t>(rng() % static_cast<uint64_t>(hi - lo + 1));
  };
  const int64_t accel = pick(100, 400'000), decel = pick(100, 400'000);
  RampSpec r =
      profile_ramp(pick(5, 40'000), accel, decel, profile_levels_per_hz(std::max(accel, decel)));
  r.s_curve = true;
  for (uint32_t& j : r.jerk)
    j = rng() % 8 == 0 ? 0 : static_cast<uint32_t>(pick(1'000, 100'000'000));
  return r;
}

// The twin and the level the generator showed before levels were computed when read.
struct Reference {
  SCurve s;
  RampSpec ramp;
  int64_t level = 0, peak = 0;
  void follow() {
    const double lph = static_cast<double>(ramp.phase_per_step) / kHz;
    const double v =
        s.at_target_velocity() ? s.target_velocity() : scurve::to_double(s.slope()) / scurve::kV;
    level = eager_level(v * lph);
    peak = std::max(peak, level);
  }
};

void expect_same(const StepGenerator& g, const Reference& r, int move, int64_t n) {
  ASSERT_EQ(g.level(), r.level) << "move " << move << " step " << n;
  ASSERT_EQ(g.velocity(), g.moving() ? r.ramp.velocity_of(r.level) : 0.0)
      << "move " << move << " step " << n;
  ASSERT_EQ(g.marks().peak_level, r.peak) << "move " << move << " step " << n;
}

// A change between the last step and the next; false: the move left the S-curve (regrid).
bool random_change(std::mt19937_64& rng, StepGenerator& g, Reference& r, Tick last,
                   bool& stopping) {
  const std::optional<Tick> next = g.peek();
  const Tick room = next ? std::max<Tick>(0, *next - 1 - last) : 1000;
  const Tick at = last + static_cast<Tick>(rng() % static_cast<uint64_t>(room + 1));
  switch (rng() % 5) {
    case 0:
      g.stop(at);
      r.s.stop(at);
      stopping = true;
      break;
    case 1: {
      const Rational z{r.ramp.decel_ticks_per_level.num, r.ramp.decel_ticks_per_level.den * 3};
      g.stop(at, z);
      r.s.stop(at, slope_of(r.ramp, z));
      stopping = true;
      break;
    }
    case 2: {
      if (stopping) return true;
      const auto level = static_cast<int64_t>(static_cast<double>(r.ramp.run_level) *
                                              std::uniform_real_distribution<double>(0.1, 2)(rng));
      g.change_velocity(at, level);
      r.s.change_velocity(
          at, static_cast<double>(level) * kHz / static_cast<double>(r.ramp.phase_per_step));
      break;
    }
    case 3: {
      if (g.remaining() || stopping) return true;
      const int64_t level = r.level;
      g.regrid(at, r.ramp);
      EXPECT_EQ(g.level(), std::max<int64_t>(level, 1));
      return false;
    }
    default: {
      const auto steps = 1 + static_cast<int64_t>(rng() % 3000);
      g.retarget(at, steps, r.ramp);
      r.s.retarget(at, g.steps_done() + steps);
      stopping = false;
      break;
    }
  }
  r.follow();
  return true;
}

TEST(SCurveLevel, ReadWhenAskedEqualsTheLevelKeptAtEveryStep) {
  std::mt19937_64 rng(20261203);
  StepGenerator g;  // one generator for all moves: nothing may carry over from the last
  int64_t reads = 0;
  for (int move = 0; move < 250; ++move) {
    Reference r;
    r.ramp = random_ramp(rng);
    const std::optional<int64_t> distance =
        rng() % 3 != 0 ? std::optional<int64_t>(1 + static_cast<int64_t>(rng() % 5000))
                       : std::nullopt;
    const Tick start = g.time() + static_cast<Tick>(rng() % 1000);
    g.start(r.ramp, start, rng() % 2 ? -1 : +1, distance);
    r.s.start(limits_of(r.ramp), start, distance);
    int64_t change_at[2] = {static_cast<int64_t>(rng() % 3000), static_cast<int64_t>(rng() % 6000)};
    const int every = 1 + static_cast<int>(rng() % 9);  // how often the level is read
    bool stopping = false;
    Tick last = start;
    for (int64_t n = 0; n < 12'000; ++n) {
      if (n == change_at[0] || n == change_at[1]) {
        if (!random_change(rng, g, r, last, stopping)) break;
        expect_same(g, r, move, n);
      }
      if (!distance && !stopping && n == 6000) g.stop(last), r.s.stop(last), r.follow();
      Step s;
      const bool was_moving = g.moving();
      const bool stepped = g.next(s);
      const std::optional<Tick> t = r.s.next_step();
      ASSERT_EQ(stepped, t.has_value()) << "move " << move << " step " << n + 1;
      if (!stepped) {
        if (was_moving) r.level = 0;  // the motion ends here (idle after its last step: kept)
        expect_same(g, r, move, n + 1);
        break;
      }
      ASSERT_EQ(s.time, *t) << "move " << move << " step " << n + 1;
      last = s.time;
      r.follow();
      if (rng() % static_cast<uint64_t>(every) == 0 || !g.moving()) {
        if (rng() % 2) g.peek();  // a peek between does not move the level
        expect_same(g, r, move, n + 1);
        ++reads;
      }
    }
  }
  EXPECT_GT(reads, 100'000) << reads;
}

}  // namespace
}  // namespace stepnode::motion
