// 6086h = 3 (jerk-limited ramp) in profile position and profile velocity mode: the moves
// of CiA 402-2's handshake with the S-curve's step times, change set immediately, halt,
// quick stop, and PV's velocity reached.
#include <gtest/gtest.h>

#include "node/profiles/cia402/tests/drive_harness.hpp"

namespace stepnode::cia402 {
namespace {

class SCurveDrive : public DriveAxis {
 protected:
  void SetUp() override {
    Parameters& p = drive.parameters();
    p.motion_profile_type = kJerkLimitedRamp;
    p.profile_velocity = 1000;
    p.acceleration = p.deceleration = 10'000;
    for (uint32_t& j : p.jerk) j = 1'000'000;
    drive.set_mode(Mode::ProfilePosition, now);
    enable();
  }
  void move_to(int32_t target, uint16_t extra = 0) {
    drive.set_target_position(target);
    cw(0x1F | extra);
    cw(0x0F | (extra & ~0x10));
  }
};

TEST_F(SCurveDrive, ProfilePositionTakesTheClosedFormTime) {
  // 200 steps at 1000 steps/s, 10 000 steps/s^2, 1e6 steps/s^3: 310 ms exactly
  // (2 x (a/j + v/a) + 90 steps / v). The jerk phase (10 ms) covers j t^3/6 = 1/6 step;
  // the first step then falls where 1/6 + 50 u + 5000 u^2 = 1: u = 8.84437 ms, at 18.84437 ms.
  move_to(200);
  run(ms(400));
  ASSERT_EQ(motor.steps.size(), 200u);
  // (The core may start the motion later for the direction output's setup time: the
  // times are measured from the first step.)
  EXPECT_NEAR(motor.steps.back().time - motor.steps.front().time, ms(310) - 0.01884437 * kClockHz,
              2);
  EXPECT_EQ(drive.position_actual(), 200);
  EXPECT_TRUE(drive.statusword() & kTargetReached);
}

TEST_F(SCurveDrive, ChangeSetImmediatelyMovesTheEndPoint) {
  move_to(2000);
  run(ms(500));
  move_to(1000, 0x20);  // bit 5: the new target replaces the running one
  run_s(2);
  EXPECT_EQ(drive.position_actual(), 1000);
  EXPECT_EQ(motor.steps.size(), 1000u);  // no overshoot, no way back
  EXPECT_TRUE(drive.statusword() & kTargetReached);
}

TEST_F(SCurveDrive, HaltAndQuickStopRampDown) {
  move_to(100'000);
  run(ms(300));
  cw(0x10F);  // halt (605Dh 1: the profile's deceleration)
  const size_t at_halt = motor.steps.size();
  run_s(1);
  const size_t after = motor.steps.size();
  EXPECT_GT(after, at_halt);  // it ramped, it did not stop dead
  EXPECT_EQ(drive.velocity_actual(), 0);
  run_s(1);
  EXPECT_EQ(motor.steps.size(), after);
  cw(0x0F);
  move_to(100'000);
  run(ms(300));
  cw(0x0B);  // quick stop (605Ah 2: 6085h ramp, then switch on disabled)
  run_s(1);
  EXPECT_EQ(state(), kSwitchOnDisabled);
  EXPECT_EQ(drive.velocity_actual(), 0);
}

TEST_F(SCurveDrive, ProfileVelocityReachesAndHoldsTheTarget) {
  drive.set_mode(Mode::ProfileVelocity, now);
  drive.set_target_velocity(1500, now);
  run(ms(50));
  EXPECT_FALSE(drive.statusword() & kTargetReached);
  run(ms(400));  // 1500/10 000 + 10 ms of jerk: 160 ms
  EXPECT_TRUE(drive.statusword() & kTargetReached);
  EXPECT_EQ(drive.velocity_actual(), 1500);
  drive.set_target_velocity(-500, now);  // a reversal: stop, then the other way
  run_s(1);
  EXPECT_EQ(drive.velocity_actual(), -500);
  EXPECT_TRUE(drive.statusword() & kTargetReached);
  drive.set_target_velocity(0, now);
  run_s(1);
  EXPECT_TRUE(drive.statusword() & kBit12);  // speed = 0
}

}  // namespace
}  // namespace stepnode::cia402
