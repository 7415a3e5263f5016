// The CiA 402 drive on the motion core, in virtual time: the controlword sequences a master
// sends (CiA 402-2 "device control": 06h shutdown, 07h switch on, 0Fh enable operation,
// 0Bh quick stop, 00h disable voltage) and the profile position / profile velocity modes'
// bits (6040h bits 4, 5, 6, 8; 6041h bits 10, 11, 12), with the step times the engine makes.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "node/profiles/cia402/tests/drive_harness.hpp"

namespace stepnode::cia402 {
namespace {

class DriveTest : public DriveAxis {};

TEST_F(DriveTest, TheMastersStartSequenceReachesOperationEnabled) {
  EXPECT_EQ(state(), kSwitchOnDisabled);  // transitions 0 and 1 at power-up
  cw(0x06);
  EXPECT_EQ(state(), kReadyToSwitchOn);
  cw(0x07);
  EXPECT_EQ(state(), kSwitchedOn);
  cw(0x0F);
  EXPECT_EQ(state(), kOperationEnabled);
  EXPECT_TRUE(drive.statusword() & (1u << 9));  // remote
}

TEST_F(DriveTest, NoMotionUnlessOperationIsEnabled) {
  drive.set_target_position(500);
  cw(0x06);
  cw(0x07);
  cw(0x1F & ~0x08);  // switched on with bit 4: not enabled, nothing moves
  run(ms(500));
  EXPECT_EQ(motor.position(), 0);
}

// A trapezoid of 1000 steps at 1000 steps/s with 10,000 steps/s^2 both ways: 50 steps and
// 0.1 s up, 900 steps at 1000 steps/s, 50 steps and 0.1 s down: 1.1 s.
TEST_F(DriveTest, ProfilePositionRunsTheTrapezoidWithTheSetPointHandshake) {
  enable();
  set_profile(1000, 10'000, 10'000);
  EXPECT_TRUE(drive.statusword() & kTargetReached);
  drive.set_target_position(1000);
  cw(0x1F);                                  // new set-point, absolute
  EXPECT_TRUE(drive.statusword() & kBit12);  // set-point acknowledge
  EXPECT_FALSE(drive.statusword() & kTargetReached);
  cw(0x0F);
  EXPECT_FALSE(drive.statusword() & kBit12);  // ready for the next one
  run(ms(1200));
  EXPECT_EQ(motor.position(), 1000);
  EXPECT_EQ(drive.position_actual(), 1000);
  EXPECT_TRUE(drive.statusword() & kTargetReached);
  ASSERT_EQ(motor.steps.size(), 1000u);
  const double last = static_cast<double>(motor.steps.back().time) / kClockHz;
  EXPECT_NEAR(last, 1.1, 0.005);
  // Cruise: 1 ms between steps, exactly (1000 steps/s on the 4.9152 MHz timebase).
  EXPECT_EQ(motor.steps[500].time - motor.steps[499].time, kClockHz / 1000);
  // The first step of a ramp from standstill: at sqrt(2/a) = 14.1 ms.
  EXPECT_NEAR(static_cast<double>(motor.steps[0].time) / kClockHz, std::sqrt(2.0 / 10'000), 0.001);
}

TEST_F(DriveTest, RelativeSetPointsAddToThePrecedingTarget) {
  enable();
  set_profile(2000, 20'000, 20'000);
  drive.set_target_position(300);
  cw(0x5F);  // new set-point, relative
  cw(0x4F);
  run(ms(600));
  EXPECT_EQ(motor.position(), 300);
  cw(0x5F);
  cw(0x4F);
  run(ms(600));
  EXPECT_EQ(motor.position(), 600);
}

TEST_F(DriveTest, ABufferedSetPointRunsAfterTheFirstAndFillsTheBuffer) {
  enable();
  set_profile(1000, 10'000, 10'000);
  drive.set_target_position(500);
  cw(0x1F);
  cw(0x0F);
  run(ms(100));
  drive.set_target_position(-200);
  cw(0x1F);  // bit 5 = 0: after the first
  cw(0x0F);
  EXPECT_TRUE(drive.statusword() & kBit12);  // the buffer is full: no third one now
  run(ms(505));  // the first ends at 0.6 s; the second's first step comes 14 ms later
  EXPECT_EQ(motor.position(), 500);  // the first target is reached...
  run(ms(1500));
  EXPECT_EQ(motor.position(), -200);  // ...then the second
  EXPECT_FALSE(drive.statusword() & kBit12);
  EXPECT_TRUE(drive.statusword() & kTargetReached);
}

TEST_F(DriveTest, ChangeSetImmediatelyMovesTheEndPointWithoutStopping) {
  enable();
  set_profile(1000, 10'000, 10'000);
  drive.set_target_position(400);
  cw(0x1F);
  cw(0x0F);
  run(ms(200));
  drive.set_target_position(1500);
  cw(0x3F);  // new set-point, change immediately
  cw(0x0F);
  run(ms(2500));
  EXPECT_EQ(motor.position(), 1500);
  // No stop at 400: the step interval there is the cruise interval.
  EXPECT_EQ(motor.steps[400].time - motor.steps[399].time, kClockHz / 1000);
}

TEST_F(DriveTest, ChangeSetImmediatelyBackwardsStopsThenGoesThere) {
  enable();
  set_profile(1000, 10'000, 10'000);
  drive.set_target_position(2000);
  cw(0x1F);
  cw(0x0F);
  run(ms(500));
  const int64_t at = motor.position();
  drive.set_target_position(100);
  cw(0x3F);
  cw(0x0F);
  run(ms(3000));
  EXPECT_EQ(motor.position(), 100);
  EXPECT_GT(at, 100);
}

TEST_F(DriveTest, HaltStopsWithTheProfileDecelerationAndShowsTargetReached) {
  enable();
  set_profile(1000, 10'000, 10'000);
  drive.set_target_position(5000);
  cw(0x1F);
  cw(0x0F);
  run(ms(500));
  const int64_t at = motor.position();
  cw(0x010F);  // halt
  run(ms(300));
  EXPECT_EQ(state(), kOperationEnabled);                           // a halt is no state change
  EXPECT_NEAR(static_cast<double>(motor.position() - at), 50, 2);  // v^2 / 2d
  EXPECT_TRUE(drive.statusword() & kTargetReached);
  const int64_t halted_at = motor.position();
  cw(0x0F);
  run(ms(300));
  EXPECT_GT(motor.position(), halted_at);  // on to 5000 (drive_wording_test.cpp)
}

TEST_F(DriveTest, QuickStopRampsAt6085AndEndsInSwitchOnDisabled) {
  enable();
  set_profile(1000, 10'000, 10'000);
  drive.parameters().quick_stop_deceleration = 100'000;
  drive.set_target_position(5000);
  cw(0x1F);
  cw(0x0F);
  run(ms(500));
  const int64_t at = motor.position();
  cw(0x0B);  // quick stop, 605Ah = 2: quick stop ramp, then Switch on disabled
  EXPECT_EQ(state(), kQuickStopActive);
  run(ms(100));
  EXPECT_EQ(state(), kSwitchOnDisabled);
  EXPECT_NEAR(static_cast<double>(motor.position() - at), 5, 2);  // 1000^2 / (2 * 100,000)
}

TEST_F(DriveTest, QuickStopOptionSixStaysActiveAndTransition16EnablesAgain) {
  Options o;
  o.quick_stop = 6;
  drive.set_options(o);
  enable();
  set_profile(1000, 10'000, 10'000);
  drive.set_target_position(5000);
  cw(0x1F);
  cw(0x0F);
  run(ms(300));
  cw(0x0B);
  run(ms(300));
  EXPECT_EQ(state(), kQuickStopActive);
  cw(0x0F);  // enable operation: transition 16
  EXPECT_EQ(state(), kOperationEnabled);
  drive.set_target_position(0);
  cw(0x1F);
  cw(0x0F);
  run(ms(3000));
  EXPECT_EQ(motor.position(), 0);
}

TEST_F(DriveTest, DisableVoltageStopsThePulsesAtOnce) {
  enable();
  set_profile(1000, 10'000, 10'000);
  drive.set_target_position(5000);
  cw(0x1F);
  cw(0x0F);
  run(ms(500));
  const int64_t at = motor.position();
  cw(0x00);
  run(ms(200));
  EXPECT_EQ(motor.position(), at);
  EXPECT_EQ(state(), kSwitchOnDisabled);
}

TEST_F(DriveTest, ATargetBeyondTheSoftwareLimitStopsAtTheLimitWithBit11) {
  enable();
  set_profile(2000, 20'000, 20'000);
  drive.parameters().max_position_limit = 300;
  drive.parameters().min_position_limit = -300;
  drive.set_target_position(1000);
  cw(0x1F);
  cw(0x0F);
  EXPECT_TRUE(drive.statusword() & kInternalLimit);
  run(ms(1000));
  EXPECT_EQ(motor.position(), 300);
}

TEST_F(DriveTest, ALimitSwitchIsAFaultAndNoStepGoesPastIt) {
  sim::AxisMachineConfig c;
  c.upper_limit = 120;
  motor.config() = c;
  enable();
  set_profile(1000, 10'000, 10'000);
  drive.set_target_position(1000);
  cw(0x1F);
  cw(0x0F);
  run(ms(1500));
  EXPECT_EQ(motor.position(), 120);
  EXPECT_EQ(state() & 0x4F, kFault);
  EXPECT_EQ(drive.error_code(), 0x8612);
  cw(0x80);  // fault reset
  EXPECT_EQ(state(), kSwitchOnDisabled);
  enable();
  drive.set_target_position(0);  // away from the limit
  cw(0x1F);
  cw(0x0F);
  run(ms(1500));
  EXPECT_EQ(motor.position(), 0);
}

TEST_F(DriveTest, ProfileVelocityFollowsTheTargetAndReverses) {
  drive.set_mode(Mode::ProfileVelocity, now);
  enable();
  set_profile(1000, 10'000, 10'000);
  EXPECT_TRUE(drive.statusword() & kBit12);  // speed = 0
  drive.set_target_velocity(2000, now);
  EXPECT_FALSE(drive.statusword() & kTargetReached);
  run(ms(300));  // 0.2 s to 2000 steps/s
  EXPECT_EQ(drive.velocity_actual(), 2000);
  EXPECT_TRUE(drive.statusword() & kTargetReached);  // velocity reached
  EXPECT_FALSE(drive.statusword() & kBit12);
  drive.set_target_velocity(-1000, now);
  run(ms(400));  // 0.2 s down, 0.1 s up the other way
  EXPECT_EQ(drive.velocity_actual(), -1000);
  drive.set_target_velocity(0, now);
  run(ms(200));
  EXPECT_EQ(drive.velocity_actual(), 0);
  EXPECT_TRUE(drive.statusword() & kBit12);
  const int64_t at = motor.position();
  run(ms(200));
  EXPECT_EQ(motor.position(), at);
}

TEST_F(DriveTest, AModeChangeWhileMovingRampsDownThenShowsTheNewMode) {
  drive.set_mode(Mode::ProfileVelocity, now);
  enable();
  set_profile(1000, 10'000, 10'000);
  drive.set_target_velocity(1000, now);
  run(ms(300));
  drive.set_mode(Mode::ProfilePosition, now);
  EXPECT_EQ(drive.mode_display(), Mode::ProfileVelocity);  // still moving
  run(ms(200));
  EXPECT_EQ(drive.velocity_actual(), 0);
  EXPECT_EQ(drive.mode_display(), Mode::ProfilePosition);
  const int64_t at = motor.position();
  drive.set_target_position(static_cast<int32_t>(at + 100));
  cw(0x1F);
  cw(0x0F);
  run(ms(500));
  EXPECT_EQ(motor.position(), at + 100);
}

TEST_F(DriveTest, AnotherFrontEndsJobKeepsTheSetPointUnacknowledged) {
  struct Other final : motion::FrontEnd {
    void after_step(const motion::Step&) override {}
    void motion_ended(Tick) override {}
  } other;
  enable();
  ASSERT_TRUE(core.start(other, motion::profile_ramp(500, 5000, 5000, 1), +1, 100, now));
  drive.set_target_position(1000);
  cw(0x1F);
  EXPECT_FALSE(drive.statusword() & kBit12);
  run(ms(1000));
  EXPECT_EQ(motor.position(), 100);
}

}  // namespace
}  // namespace stepnode::cia402
