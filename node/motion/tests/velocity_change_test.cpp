// Velocity changes while running (what HP SUSTAIN and velocity modes need) and the
// continuous-slope frequency ramp.
#include <gtest/gtest.h>

#include "node/motion/step_generator.hpp"

namespace stepnode::motion {
namespace {

Tick run_until(StepGenerator& g, Tick until, Step& last) {
  Step s;
  while (auto t = g.peek()) {
    if (*t > until) break;
    g.next(s);
    last = s;
  }
  return last.time;
}

TEST(VelocityChange, RampsUpAndDownToANewVelocityAndHoldsIt) {
  RampSpec ramp = frequency_ramp(100, 1000, 500'000);  // 100..1000 Hz at 500 Hz/s
  StepGenerator g;
  g.start(ramp, 0, +1, std::nullopt);
  Step last;
  run_until(g, 3 * kClockHz, last);  // (1000-100)/500 = 1.8 s to reach max
  EXPECT_EQ(g.phase(), MotionPhase::Running);
  EXPECT_NEAR(g.velocity(), 1000.0, 1e-9);
  // Down to 400 Hz: 1.2 s at 500 Hz/s, then holds.
  g.change_velocity(last.time, 400 * kLevelsPerHz);
  EXPECT_EQ(g.phase(), MotionPhase::Decelerating);
  Tick from = last.time;
  run_until(g, from + kClockHz * 11 / 10, last);
  EXPECT_EQ(g.phase(), MotionPhase::Decelerating);
  run_until(g, from + kClockHz * 13 / 10, last);
  EXPECT_EQ(g.phase(), MotionPhase::Running);
  EXPECT_NEAR(g.velocity(), 400.0, 1e-9);
  // Held: 400 steps in one second, to a step.
  int64_t before = g.steps_done();
  Tick t0 = last.time;
  run_until(g, t0 + kClockHz, last);
  EXPECT_NEAR(static_cast<double>(g.steps_done() - before), 400.0, 1.0);
  // Up again to 800 Hz, then a stop ramps to the minimum and ends.
  g.change_velocity(last.time, 800 * kLevelsPerHz);
  EXPECT_EQ(g.phase(), MotionPhase::Accelerating);
  run_until(g, last.time + 2 * kClockHz, last);
  EXPECT_NEAR(g.velocity(), 800.0, 1e-9);
  g.stop(last.time);
  Step s;
  while (g.next(s)) {
  }
  EXPECT_FALSE(g.moving());
}

TEST(VelocityChange, ZeroHertzMinimumStillMovesAndEnds) {
  RampSpec ramp = frequency_ramp(0, 250, 500'000);  // the HP power-on profile
  StepGenerator g;
  g.start(ramp, 0, -1, 100);
  Step s;
  int64_t n = 0;
  while (g.next(s)) ++n;
  EXPECT_EQ(n, 100);
}

}  // namespace
}  // namespace stepnode::motion
