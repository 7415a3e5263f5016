// Profile position mode, controlword bit 9 "change on set-point" (CiA 402-2, the definition
// of bits 4, 5 and 9): with bit 9 = 1 and bit 5 = 0 the drive proceeds with the current
// profile velocity up to the current set-point and then applies the next one: it does not
// stop at the first target. The set-point handshake as the standard has it: bit 12 (set-
// point acknowledge) stays 1 while the buffer holds the next set-point and drops when the
// drive takes it over at the first target; bit 10 (target reached) only at the last one.
// Velocities from the step times the engine makes, against the closed form of the motion.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "node/profiles/cia402/tests/drive_harness.hpp"

namespace stepnode::cia402 {
namespace {

constexpr uint16_t kNewSetPoint = 0x1F, kEnabled = 0x0F, kChangeOnSetPoint = 1u << 9;

class ChangeOnSetPoint : public DriveAxis {
 protected:
  void SetUp() override {
    enable();
    drive.parameters().acceleration = drive.parameters().deceleration = kAccel;
  }
  // A set-point (target, 6081h) with the handshake: bit 4 up, then down.
  void set_point(int32_t target, uint32_t velocity, uint16_t extra = 0) {
    drive.parameters().profile_velocity = velocity;
    drive.set_target_position(target);
    cw(kNewSetPoint | extra);
    cw(kEnabled | extra);
  }
  // The velocity of the step that took the motor (from 0, upward) to `position`: steps/s
  // from its interval to the step before.
  double velocity_at(int64_t position) const {
    const auto k = static_cast<size_t>(position - 1);
    return static_cast<double>(kClockHz) /
           static_cast<double>(motor.steps.at(k).time - motor.steps.at(k - 1).time);
  }
  // The slowest step between two positions (upward from 0).
  double slowest_between(int64_t from, int64_t to) const {
    double v = 1e12;
    for (int64_t p = from; p <= to; ++p) v = std::min(v, velocity_at(p));
    return v;
  }
  double seconds(Tick t) const { return static_cast<double>(t) / kClockHz; }
  static constexpr uint32_t kAccel = 10'000;  // steps/s^2, both ways
};

// The time of a motion from standstill through x1 at v1 (reached before x1) on to standstill
// at x2, at v2 from x1 on: the trapezoid's pieces at acceleration a.
double through_time(double x1, double v1, double x2, double v2, double a) {
  const double up = v1 / a, up_steps = v1 * v1 / (2 * a);
  const double change = std::fabs(v2 - v1) / a,
               change_steps = std::fabs(v2 * v2 - v1 * v1) / (2 * a);
  const double down = v2 / a, down_steps = v2 * v2 / (2 * a);
  return up + (x1 - up_steps) / v1 + change + (x2 - x1 - change_steps - down_steps) / v2 + down;
}

TEST_F(ChangeOnSetPoint, TheAxisRunsThroughTheFirstTargetAtItsVelocityThenAtTheNextOnes) {
  set_point(1000, 1000);
  EXPECT_FALSE(drive.statusword() & kBit12);  // taken; the buffer is free
  set_point(3000, 2000, kChangeOnSetPoint);
  EXPECT_TRUE(drive.statusword() & kBit12);  // buffered: no further set-point now
  run(ms(1000));                             // before the first target (1.05 s)
  EXPECT_TRUE(drive.statusword() & kBit12);
  EXPECT_LT(motor.position(), 1000);
  run(ms(200));
  EXPECT_GT(motor.position(), 1000);
  EXPECT_FALSE(drive.statusword() & kBit12);          // the next set-point is the running one
  EXPECT_FALSE(drive.statusword() & kTargetReached);  // the first target is no target reached
  run(ms(1500));
  EXPECT_EQ(motor.position(), 3000);
  EXPECT_TRUE(drive.statusword() & kTargetReached);
  // No slowing down at the first target: 1000 steps/s up to it, then up to 2000.
  EXPECT_NEAR(velocity_at(1000), 1000, 1);
  EXPECT_GE(slowest_between(100, 1000), 999);
  EXPECT_NEAR(velocity_at(2000), 2000, 2);
  EXPECT_NEAR(seconds(motor.steps.back().time), through_time(1000, 1000, 3000, 2000, kAccel),
              0.002);
}

TEST_F(ChangeOnSetPoint, SetPointsChainWhileTheBufferFreesAtEachTarget) {
  // The master sends the next set-point whenever bit 12 drops (the buffer has room): three
  // targets, one motion, no stop before the last.
  set_point(1000, 1000);
  set_point(2000, 1000, kChangeOnSetPoint);
  for (int i = 0; i < 3000 && (drive.statusword() & kBit12); ++i) run(ms(1));
  EXPECT_GE(motor.position(), 1000);
  EXPECT_LT(motor.position(), 1010);  // freed at the first target
  set_point(3000, 1000, kChangeOnSetPoint);
  run(ms(3000));
  EXPECT_EQ(motor.position(), 3000);
  EXPECT_GE(slowest_between(100, 2900), 999);
  // One trapezoid over 3000 steps: 0.1 s and 50 steps up, 2900 steps at 1000, 0.1 s down.
  EXPECT_NEAR(seconds(motor.steps.back().time), 0.1 + (3000 - 100) / 1000.0 + 0.1, 0.002);
}

TEST_F(ChangeOnSetPoint, ALowerNextVelocityIsTakenFromTheFirstTargetOn) {
  set_point(1000, 2000);
  set_point(3000, 500, kChangeOnSetPoint);
  run(ms(5000));
  EXPECT_EQ(motor.position(), 3000);
  EXPECT_NEAR(velocity_at(1000), 2000, 2);  // the first set-point's velocity at its target
  EXPECT_NEAR(velocity_at(2000), 500, 1);
  EXPECT_NEAR(seconds(motor.steps.back().time), through_time(1000, 2000, 3000, 500, kAccel), 0.003);
}

TEST_F(ChangeOnSetPoint, WithoutBit9TheAxisStopsAtTheFirstTarget) {
  set_point(1000, 1000);
  set_point(3000, 2000);  // buffered, bit 9 = 0: target reached first
  run(ms(4000));
  EXPECT_EQ(motor.position(), 3000);
  EXPECT_LT(velocity_at(1000), 200);  // the last step of a ramp to standstill
  // The first motion ends at 1.1 s; the second starts from standstill there (its first step
  // sqrt(2 / a) = 14 ms later).
  EXPECT_NEAR(seconds(motor.steps.at(999).time), 1.1, 0.002);
  EXPECT_GT(seconds(motor.steps.at(1000).time - motor.steps.at(999).time), 0.014);
}

TEST_F(ChangeOnSetPoint, ANextTargetBehindTheFirstIsReachedFromAStandstillThere) {
  set_point(2000, 1000);
  set_point(500, 1000, kChangeOnSetPoint);  // the other way: it cannot run through
  run(ms(6000));
  EXPECT_EQ(motor.position(), 500);
  int64_t at = 0, highest = 0;
  for (const sim::TracedStep& s : motor.steps) highest = std::max(highest, at += s.direction);
  EXPECT_EQ(highest, 2000);  // the first target, exactly
}

TEST_F(ChangeOnSetPoint, GivenDuringTheRampDownToTheFirstTargetTheAxisSpeedsUpAgain) {
  set_point(1000, 1000);
  run(ms(1020));  // the ramp down began at 950 steps (1.0 s)
  ASSERT_LT(motor.position(), 1000);
  set_point(3000, 1000, kChangeOnSetPoint);
  run(ms(3000));
  EXPECT_EQ(motor.position(), 3000);
  EXPECT_GT(slowest_between(900, 2900), 700);  // back to 1000 steps/s, no standstill
  EXPECT_NEAR(velocity_at(2000), 1000, 1);
}

TEST_F(ChangeOnSetPoint, ChangeSetImmediatelyWins) {
  // Bits 5 and 9 together: bit 5 (the table's "x" for bit 9): the new target at once.
  set_point(1000, 1000);
  run(ms(300));
  set_point(400, 1000, kChangeOnSetPoint | (1u << 5));
  run(ms(2000));
  int64_t at = 0, highest = 0;
  for (const sim::TracedStep& s : motor.steps) highest = std::max(highest, at += s.direction);
  EXPECT_EQ(motor.position(), 400);
  EXPECT_LE(highest, 400);  // the first target was never gone to
}

// A fresh axis at a horizon, playing a change-on-set-point pair: the pulses the machine got.
struct HorizonAxis : DriveAxis {
  void TestBody() override {}
  std::vector<sim::TracedStep> play(Tick horizon) {
    std::vector<sim::TracedStep> train;  // as the machine receives them, queued or not
    motor.trace_into(&train);
    motor.set_horizon(horizon);
    enable();
    drive.parameters().acceleration = drive.parameters().deceleration = 10'000;
    drive.parameters().profile_velocity = 1000;
    drive.set_target_position(1000);
    cw(kNewSetPoint);
    cw(kEnabled);
    run(ms(300));
    drive.parameters().profile_velocity = 2000;
    drive.set_target_position(3000);
    cw(kNewSetPoint | kChangeOnSetPoint);
    cw(kEnabled | kChangeOnSetPoint);
    run(ms(3000));
    motor.trace_into(nullptr);
    EXPECT_EQ(motor.position(), 3000) << "horizon " << horizon;
    return train;
  }
};

// The core queues steps up to the port's horizon ahead of their time; the run-through
// changes the course from a step's rule (the velocity at the first target), so the queued
// steps are taken back and planned again: the train is the same at any horizon.
TEST(ChangeOnSetPointHorizon, TheStepsAreTheSameAtAnyHorizon) {
  const std::vector<sim::TracedStep> at_0 = HorizonAxis{}.play(0);
  ASSERT_EQ(at_0.size(), 3000u);
  EXPECT_EQ(HorizonAxis{}.play(ms(1)), at_0);
  EXPECT_EQ(HorizonAxis{}.play(ms(100)), at_0);
}

}  // namespace
}  // namespace stepnode::cia402
