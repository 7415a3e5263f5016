// A velocity change in a move to a target (CiA 402 PP "change on set-point": the next
// set-point's velocity from the first target on): the move keeps its end, runs at the new
// velocity and ramps down to the end from it; a target too near to hold a lower velocity
// is reached by ramping on down. Times against the closed form of a trapezoid.
#include <gtest/gtest.h>

#include <cmath>

#include "node/motion/step_generator.hpp"

namespace stepnode::motion {
namespace {

constexpr int64_t kLevels = 1;  // levels per step/s

// Steps `g` until `steps_done` reaches `n`; the time of that step.
Tick run_to(StepGenerator& g, int64_t n) {
  Step s;
  while (g.steps_done() < n && g.next(s)) {
  }
  return s.time;
}

double seconds(Tick t) { return static_cast<double>(t) / kClockHz; }

TEST(VelocityChangeToTarget, UpToTheNewVelocityThenDownToTheSameEnd) {
  // 1000 steps/s, 10,000 steps/s^2 both ways; 3000 steps. At step 1000 (t = 0.1 + 0.95 s at
  // 1000 steps/s) up to 2000 steps/s: 0.1 s and 150 steps, 1650 steps at 2000 (0.825 s),
  // down in 0.2 s and 200 steps: the end at 2.175 s.
  StepGenerator g;
  g.start(profile_ramp(1000, 10'000, 10'000, kLevels), 0, +1, 3000);
  const Tick at = run_to(g, 1000);
  EXPECT_NEAR(seconds(at), 1.05, 0.001);
  g.change_velocity(at, 2000 * kLevels);
  EXPECT_EQ(g.phase(), MotionPhase::Accelerating);
  run_to(g, 1500);
  EXPECT_EQ(g.phase(), MotionPhase::Running);
  EXPECT_NEAR(g.velocity(), 2000.0, 1e-9);
  const Tick end = run_to(g, 3000);
  EXPECT_FALSE(g.moving());
  EXPECT_EQ(g.steps_done(), 3000);
  EXPECT_NEAR(seconds(end), 2.175, 0.002);
}

TEST(VelocityChangeToTarget, DownToALowerVelocityHoldsItThenEndsThere) {
  // 2000 steps/s; at step 1000 down to 500 steps/s (0.15 s, 187.5 steps), held, then down to
  // the end at 3000 as a move at 500 steps/s ends: from a step at 500 steps/s with the same
  // steps to go, in the same time.
  StepGenerator g, at_500;
  g.start(profile_ramp(2000, 10'000, 10'000, kLevels), 0, +1, 3000);
  at_500.start(profile_ramp(500, 10'000, 10'000, kLevels), 0, +1, 3000);
  const Tick at = run_to(g, 1000);
  g.change_velocity(at, 500 * kLevels);
  EXPECT_EQ(g.phase(), MotionPhase::Decelerating);
  const Tick held = run_to(g, 2000);
  EXPECT_NEAR(seconds(held - at), 0.15 + (1000 - 187.5) / 500, 0.002);
  EXPECT_EQ(g.phase(), MotionPhase::Running);
  EXPECT_NEAR(g.velocity(), 500.0, 1e-9);
  const Tick reference = run_to(at_500, 2000);
  EXPECT_NEAR(seconds(run_to(g, 3000) - held), seconds(run_to(at_500, 3000) - reference), 0.001);
  EXPECT_EQ(g.steps_done(), 3000);
  EXPECT_FALSE(g.moving());
}

TEST(VelocityChangeToTarget, InTheRampDownToTheTargetALowerVelocityIsNotHeld) {
  // Down to a lower velocity and then to standstill takes as long as straight down (the
  // same deceleration): from inside the final ramp (it begins 200 steps before the end at
  // 2000 steps/s) the ramp runs on to the end, step for step as if nothing had been asked.
  StepGenerator changed, plain;
  for (StepGenerator* g : {&changed, &plain})
    g->start(profile_ramp(2000, 10'000, 10'000, kLevels), 0, +1, 3000);
  const Tick at = run_to(changed, 2850);
  run_to(plain, 2850);
  changed.change_velocity(at, 1000 * kLevels);
  int64_t held = 0;
  Step s;
  while (changed.next(s))
    if (changed.phase() == MotionPhase::Running) ++held;
  EXPECT_EQ(changed.steps_done(), 3000);
  EXPECT_EQ(held, 0);
  EXPECT_EQ(s.time, run_to(plain, 3000));
}

}  // namespace
}  // namespace stepnode::motion
