// SPM30 multiplexed mode (SPM30 chapter 4 SELECT AXIS, 3.1 %I11/%I12, 3.3.2): one register set
// drives one of three motors; selection saves and restores MOTOR POSITION, CURRENT POSITION
// VALID and AT HOME, and an AT HOME change while deselected invalidates the position. The
// encoder belongs to axis 1 whatever is selected. Single-motor axes ignore %Q2/%Q3.
#include <gtest/gtest.h>

#include "node/motion/tests/axis_harness.hpp"

namespace stepnode::motion {
namespace {

class AxisMultiplexed : public harness::AxisHarness {
 protected:
  static sim::AxisMachineConfig machine() {
    sim::AxisMachineConfig m;
    m.encoder = sim::EncoderKind::None;
    m.home = sim::Cam{1000, 40};
    m.lower_limit = -20000;
    m.upper_limit = 20000;
    return m;
  }
  // Three motors on the bench; the axis drives `count` of them (1: a single-motor axis).
  void build(AxisConfig c = {}, sim::AxisMachineConfig m = machine(), unsigned count = 3) {
    AxisHarness::build(c, m, count, 3);
    clear();
  }
  void SetUp() override { build(); }
  void select(unsigned n) {
    issue(n == 1 ? command::kSelectAxis1 : n == 2 ? command::kSelectAxis2 : command::kSelectAxis3);
  }
  void finish() {
    for (int i = 0; i < 600 && any(status::kMoving); ++i) wait(100);
  }
};

TEST_F(AxisMultiplexed, Spm30_3_1_SelectionBitsShowTheSelectedAxis) {
  EXPECT_EQ(axis->selected_motor(), 0u);  // axis 1 after power-up
  EXPECT_FALSE(any(status::kAxis2Selected | status::kAxis3Selected));
  select(2);
  EXPECT_EQ(axis->status() & (status::kAxis2Selected | status::kAxis3Selected),
            status::kAxis2Selected);
  select(3);
  EXPECT_EQ(axis->status() & (status::kAxis2Selected | status::kAxis3Selected),
            status::kAxis3Selected);
  select(1);
  EXPECT_FALSE(any(status::kAxis2Selected | status::kAxis3Selected));
  EXPECT_EQ(errors(), 0);
}

TEST_F(AxisMultiplexed, Spm30_4_SelectAxis_EachMotorKeepsItsPositionAndValidity) {
  set_position(100);
  move_rel(50);
  finish();
  select(2);
  EXPECT_EQ(axis->motor_position(), 0);  // never set: zero, invalid
  EXPECT_FALSE(has(status::kPositionValid));
  move_rel(-70);
  finish();
  select(3);
  set_position(3000);
  move_rel(20);
  finish();
  EXPECT_EQ(motors[0].position(), 50);  // each motor got only its own steps
  EXPECT_EQ(motors[1].position(), -70);
  EXPECT_EQ(motors[2].position(), 20);
  select(1);
  EXPECT_EQ(axis->motor_position(), 150);
  EXPECT_TRUE(has(status::kPositionValid));
  select(2);
  EXPECT_EQ(axis->motor_position(), -70);
  EXPECT_FALSE(has(status::kPositionValid));
  select(3);
  EXPECT_EQ(axis->motor_position(), 3020);
  EXPECT_TRUE(has(status::kPositionValid));
  select(3);  // step (1): the same axis again does nothing
  EXPECT_EQ(axis->motor_position(), 3020);
  EXPECT_TRUE(has(status::kPositionValid));
}

TEST_F(AxisMultiplexed, Spm30_4_SelectAxis_AtHomeChangedWhileDeselectedInvalidates) {
  select(2);
  set_position(5);
  select(1);
  motors[1].displace(1010);  // axis 2 carried onto its home switch while not selected
  select(2);
  EXPECT_TRUE(has(status::kAtHome));
  EXPECT_EQ(axis->motor_position(), 5);       // restored...
  EXPECT_FALSE(has(status::kPositionValid));  // ...but no longer trusted (step 5)
  // On the switch when deselected, off it when selected again: changed too.
  set_position(1010);
  select(1);
  motors[1].displace(100);
  select(2);
  EXPECT_FALSE(has(status::kAtHome));
  EXPECT_FALSE(has(status::kPositionValid));
  // Moved while deselected but the AT HOME status is the same: still valid.
  set_position(1110);
  select(3);
  motors[1].displace(300);
  select(2);
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_EQ(axis->motor_position(), 1110);
}

TEST_F(AxisMultiplexed, Spm30_4_SelectAxis_IgnoredWhileMovingOrWithAnError) {
  move_rel(3000);
  wait(200);
  select(2);
  EXPECT_EQ(axis->selected_motor(), 0u);
  finish();
  EXPECT_EQ(motors[0].position(), 3000);
  EXPECT_EQ(motors[1].position(), 0);
  axis->words().destination = 0;
  issue(command::kMoveAbsolute);  // invalid position: Illegal Move
  ASSERT_EQ(errors(), status::kIllegalMove);
  select(3);
  EXPECT_EQ(axis->selected_motor(), 0u);
}

TEST_F(AxisMultiplexed, Spm30_4_FindHomeAndJogActOnTheSelectedMotorsInputs) {
  motors[1].config().home = sim::Cam{-400, 10};  // axis 2's own home switch
  select(2);
  axis->words().destination = 9;
  issue(command::kFindHomeDown);
  finish();
  EXPECT_EQ(errors(), 0);
  EXPECT_TRUE(has(status::kPositionValid | status::kAtHome));
  EXPECT_EQ(motors[1].position(), -391);
  EXPECT_EQ(motors[0].position(), 0);
  EXPECT_EQ(axis->motor_position(), 9);
  select(1);
  EXPECT_FALSE(has(status::kAtHome));  // axis 1 is not on its switch
  hold(command::kJogUp);
  wait(500);
  hold(0);
  finish();
  EXPECT_GT(motors[0].position(), 0);
  EXPECT_EQ(motors[1].position(), -391);
}

TEST_F(AxisMultiplexed, Spm30_3_3_2_EncoderPositionIsAxis1sWhateverIsSelected) {
  // Without an encoder: axis 1's MOTOR POSITION (SPM30 5.1).
  set_position(77);
  select(2);
  set_position(500);
  move_rel(30);
  finish();
  EXPECT_EQ(axis->encoder_position(), 77);
  // With one: axis 1's encoder, loaded only when axis 1 is selected (SET CURRENT POSITION,
  // FIND HOME step 7: "and into ENCODER POSITION if axis 1 is selected").
  AxisConfig c;
  c.encoder = sim::EncoderKind::Quadrature;
  c.quadrature_decoding = 4;
  c.encoder_tolerance = 5;
  sim::AxisMachineConfig m = machine();
  m.encoder = sim::EncoderKind::Quadrature;  // 2000 steps, 500 lines decoded x4: 1:1
  build(c, m);
  set_position(40);
  move_rel(60);
  finish();
  ASSERT_EQ(axis->encoder_position(), 100);
  select(2);
  set_position(-5000);
  EXPECT_EQ(axis->encoder_position(), 100);
  axis->words().destination = -123;
  issue(command::kFindHomeUp);
  finish();
  EXPECT_EQ(axis->motor_position(), -123);
  EXPECT_EQ(axis->encoder_position(), 100);
  motors[0].displace(3);  // axis 1 moved by hand: its encoder still counts
  wait(1);
  EXPECT_EQ(axis->encoder_position(), 103);
  EXPECT_TRUE(has(status::kPositionValid));  // axis 2's validity is not checked against it
  select(1);
  EXPECT_EQ(axis->motor_position(), 100);
  EXPECT_TRUE(has(status::kPositionValid));  // 3 < tolerance 5
  motors[0].displace(2);
  wait(1);
  EXPECT_FALSE(has(status::kPositionValid));  // 5 reaches it
}

TEST_F(AxisMultiplexed, Spm30_4_SelectAxis_IsACommandThatEndsResumability) {
  set_position(0);
  move_rel(5000);
  wait(800);
  issue(command::kDecelStop);
  finish();
  ASSERT_TRUE(has(status::kResumable));
  select(2);
  select(1);
  EXPECT_FALSE(has(status::kResumable));
}

// SPM30 4 SELECT AXIS: "(1) If requested new axis is the same as the old axis or is illegal,
// do nothing." Nothing was done, so a pre-empted move stays resumable (RESUME MOVE (3) ends it
// on "some command other than %Q10"), on a multiplexed axis and on one motor alike.
TEST_F(AxisMultiplexed, Spm30_4_SelectAxis_TheSelectedAxisAgainDoesNothingAndKeepsI10) {
  select(2);
  move_rel(5000);
  wait(800);
  issue(command::kDecelStop);
  finish();
  ASSERT_TRUE(has(status::kResumable));
  select(2);  // the same axis
  EXPECT_TRUE(has(status::kResumable));
  issue(command::kResumeMove);
  finish();
  EXPECT_EQ(errors(), 0);
  EXPECT_EQ(motors[1].position(), 5000);

  build({}, machine(), 1);
  move_rel(5000);
  wait(800);
  issue(command::kDecelStop);
  finish();
  ASSERT_TRUE(has(status::kResumable));
  select(2);  // illegal on one motor
  select(1);  // the same axis
  EXPECT_TRUE(has(status::kResumable));
  issue(command::kResumeMove);
  finish();
  EXPECT_EQ(errors(), 0);
  EXPECT_EQ(motors[0].position(), 5000);
}

TEST_F(AxisMultiplexed, Spm30_3_1_PowerUpSelectsAxis1AndForgetsTheOthers) {
  select(2);
  set_position(222);
  axis->power_up(now);
  EXPECT_EQ(axis->selected_motor(), 0u);
  EXPECT_EQ(axis->status() & ~status::kAtHome, status::kPowerUp);
  write(command::kClearErrors);
  write(0);
  select(2);
  EXPECT_EQ(axis->motor_position(), 0);
  EXPECT_FALSE(has(status::kPositionValid));
}

TEST_F(AxisMultiplexed, Spm30_4_SelectAxis2And3AreIllegalOnASingleMotorAxis) {
  build({}, machine(), 1);
  set_position(10);
  select(2);
  select(3);
  issue(command::kSelectAxis2 | command::kSelectAxis3);
  EXPECT_EQ(axis->selected_motor(), 0u);
  EXPECT_FALSE(any(status::kAxis2Selected | status::kAxis3Selected));
  EXPECT_EQ(errors(), 0);  // step (1): illegal, do nothing
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_EQ(axis->motor_position(), 10);
  // An illegal selection rising with a legal command does not hide it.
  axis->words().destination = 25;
  issue(command::kSelectAxis3 | command::kMoveRelative);
  finish();
  EXPECT_EQ(motors[0].position(), 25);
}

}  // namespace
}  // namespace stepnode::motion
