// The axis's stops that are not commands: end limits, the emergency stop, limit-started moves
// and the master lost (heartbeat consumer timeout), in virtual time. Sections: SPM30 =
// HE693STP manual (3.1, 3.3.1, chapter 4), STP100 = HE800STP100 manual (4.2.1, 5.3.4).
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <vector>

#include "node/motion/stpcalc.hpp"
#include "node/motion/tests/axis_harness.hpp"

namespace stepnode::motion {
namespace {

using harness::ms;

class AxisSafety : public harness::AxisHarness {
 protected:
  static sim::AxisMachineConfig machine() {
    sim::AxisMachineConfig m;
    m.encoder = sim::EncoderKind::None;
    m.lower_limit = -3000;
    m.upper_limit = 3000;
    m.home = sim::Cam{10000, 40};  // out of reach of the limits: a home never found
    return m;
  }
  void build(AxisConfig c = {}, sim::AxisMachineConfig m = machine()) { AxisHarness::build(c, m); }
  void SetUp() override { build(); }
  // Runs to just after the next step (the e-stop or a fault can then come between steps).
  void next_step() {
    auto t = axis->next_step_time();
    ASSERT_TRUE(t.has_value());
    at(*t);
  }
  // Standing still and invalid, as after a sudden stop (SPM30 3.3.1).
  void expect_sudden_stop(uint16_t error) {
    EXPECT_EQ(errors(), error);
    EXPECT_FALSE(any(status::kMoving | status::kAccelerating | status::kDecelerating));
    EXPECT_FALSE(any(status::kPositionValid | status::kResumable));
    EXPECT_FALSE(axis->next_step_time().has_value());
  }
};

// ---- end limits: SPM30 3.1/3.3.1, STP100 4.2.1 ----------------------------------------------

TEST_F(AxisSafety, Spm30_3_3_1_LowerLimitHitMovingDownLatchesI2HaltsAndInvalidates) {
  clear();
  set_position(0);
  move_rel(-5000);
  wait(60000);
  expect_sudden_stop(status::kLowerLimit);
  EXPECT_EQ(mech(), -3000);  // stopped on the very step that made the input active
  EXPECT_EQ(axis->motor_position(), -3000);
  ASSERT_FALSE(events.empty());
  bool reported = false;
  for (const auto& e : events)
    if (e.kind == AxisEvent::Error && e.error_bits == status::kLowerLimit) reported = true;
  EXPECT_TRUE(reported);
  wait(1000);
  EXPECT_EQ(errors(), status::kLowerLimit);  // latched until Clear Errors
  clear();
  EXPECT_EQ(errors(), 0);
}

TEST_F(AxisSafety, Spm30_3_3_1_UpperLimitHitWhileRunningStopsAtOnce) {
  clear();
  set_position(0);
  move_rel(5000);  // at 1000 steps/s when it reaches 3000
  wait(2600);
  ASSERT_TRUE(has(status::kMoving));
  wait(2000);
  expect_sudden_stop(status::kUpperLimit);
  EXPECT_EQ(mech(), 3000);
}

TEST_F(AxisSafety, Spm30_3_3_1_LimitDuringJogLatchesEvenWithTheBitStillHeld) {
  clear();
  hold(command::kJogDown);
  wait(30000);
  expect_sudden_stop(status::kLowerLimit);
  EXPECT_EQ(mech(), -3000);
  hold(0);
}

TEST_F(AxisSafety, Spm30_3_3_1_ActiveLimitBlocksItsDirectionAndAllowsMovingAway) {
  clear();
  move_rel(-4000);
  wait(20000);
  ASSERT_EQ(errors(), status::kLowerLimit);
  clear();
  set_position(0);
  // Toward the active limit: refused with the limit error, not a single step.
  move_rel(-1);
  EXPECT_EQ(errors(), status::kLowerLimit);
  EXPECT_TRUE(has(status::kPositionValid));  // refused before any step: nothing moved
  clear();
  set_position(0);
  hold(command::kJogDown);
  EXPECT_EQ(errors(), status::kLowerLimit);
  hold(0);
  clear();
  set_position(0);
  move_abs(-10);
  EXPECT_EQ(errors(), status::kLowerLimit);
  clear();
  wait(1000);
  EXPECT_EQ(mech(), -3000);
  // Away from it: allowed, the first step leaves the switch.
  set_position(0);
  move_rel(1);
  wait(100);
  EXPECT_EQ(mech(), -2999);
  EXPECT_EQ(errors(), 0);
  move_rel(-1);  // back onto it: the input activates during the move (STP100 4.2.1)
  wait(100);
  EXPECT_EQ(mech(), -3000);
  EXPECT_EQ(errors(), status::kLowerLimit);
  clear();
  hold(command::kJogUp);
  wait(500);
  EXPECT_EQ(errors(), 0);
  EXPECT_GT(mech(), -3000);
  hold(0);
  wait(1000);
  EXPECT_FALSE(any(status::kMoving));
}

TEST_F(AxisSafety, Stp100_4_2_1_LimitActiveWhileStandingStillIsNoError) {
  clear();
  motors[0].displace(5000);  // pushed onto the upper limit
  wait(100);
  EXPECT_EQ(errors(), 0);
  move_rel(-10);  // away from it
  wait(500);
  EXPECT_EQ(mech(), 4990);
  EXPECT_EQ(errors(), 0);
}

TEST_F(AxisSafety, Spm30_4_FindHomeNotFoundEndsOnTheLimitWithItsError) {
  clear();
  set_position(0);
  axis->words().destination = 0;
  issue(command::kFindHomeDown);
  EXPECT_FALSE(has(status::kPositionValid));  // FIND HOME step 1
  wait(60000);
  expect_sudden_stop(status::kLowerLimit);
  EXPECT_EQ(mech(), -3000);
  EXPECT_FALSE(has(status::kAtHome));
}

TEST_F(AxisSafety, Spm30_4_FindHomeTowardAnActiveLimitTakesNoStep) {
  clear();
  motors[0].displace(-3000);  // on the lower limit
  issue(command::kFindHomeDown);
  wait(1000);
  EXPECT_EQ(errors(), status::kLowerLimit);
  EXPECT_EQ(mech(), -3000);
  EXPECT_EQ(motors[0].pulses_received(), 0u);
}

// ---- STP100 5.3.4: limit-switch-started moves -----------------------------------------------

TEST_F(AxisSafety, Stp100_5_3_4_MoveTowardActiveLimitWaitsForItsReleaseThenRuns) {
  AxisConfig c;
  c.limit_started_moves = true;
  build(c);
  clear();
  motors[0].displace(3000);  // on the high limit input
  set_position(0);
  move_rel(400);  // up: started by the high limit's release
  EXPECT_EQ(errors(), 0);
  EXPECT_TRUE(has(status::kMoving));  // the move is in progress
  EXPECT_TRUE(axis->dir_output_high());
  wait(2000);
  EXPECT_EQ(mech(), 3000);
  EXPECT_EQ(motors[0].pulses_received(), 0u);
  // Other commands are ignored meanwhile (Moving is on).
  axis->words().destination = 9;
  issue(command::kSetPosition);
  EXPECT_EQ(axis->motor_position(), 0);
  // The input goes inactive: the move starts then, at the base velocity.
  motors[0].config().upper_limit = 100000;
  wait(0);
  EXPECT_TRUE(has(status::kMoving | status::kAccelerating));
  wait(5000);
  EXPECT_EQ(mech(), 3400);
  EXPECT_EQ(axis->motor_position(), 400);
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_EQ(errors(), 0);
}

TEST_F(AxisSafety, Stp100_5_3_4_AbsoluteMoveDownStartedByTheLowLimit) {
  AxisConfig c;
  c.limit_started_moves = true;
  build(c);
  clear();
  motors[0].displace(-3000);
  set_position(1000);
  move_abs(700);  // 300 down
  wait(1000);
  EXPECT_EQ(mech(), -3000);
  EXPECT_FALSE(axis->dir_output_high());
  motors[0].displace(+500);  // carried off the switch
  wait(0);
  wait(5000);
  EXPECT_EQ(mech(), -2800);
  EXPECT_EQ(axis->motor_position(), 700);
}

TEST_F(AxisSafety, Stp100_5_3_4_WaitingMoveCanBeStoppedAndAwayMovesStartAtOnce) {
  AxisConfig c;
  c.limit_started_moves = true;
  build(c);
  clear();
  motors[0].displace(3000);
  move_rel(100);
  issue(command::kImmediateStop);
  EXPECT_FALSE(any(status::kMoving));
  motors[0].config().upper_limit = 100000;
  wait(3000);
  EXPECT_EQ(mech(), 3000);  // cancelled: never starts
  motors[0].config().upper_limit = 3000;
  move_rel(-100);  // away from the active limit: at once
  EXPECT_TRUE(has(status::kAccelerating));
  wait(3000);
  EXPECT_EQ(mech(), 2900);
  // Jogs are not limit-started: toward the active limit is still the limit error.
  motors[0].displace(100);
  hold(command::kJogUp);
  EXPECT_EQ(errors(), status::kUpperLimit);
  hold(0);
}

// STP100 5.3.10 IMMEDIATE STOP: "If the motor was moving, the Current Position Valid Status bit
// (%I9) is turned OFF". A limit-started move waiting for its limit's release shows %I16 (the
// move is in progress) but "does not start until the End Limit input is deactivated" (5.3.4):
// the motor is not moving, and %I9 stays on, as it does when the e-stop ends the same wait.
TEST_F(AxisSafety, Stp100_5_3_10_ImmediateStopOfAWaitingLimitStartedMoveKeepsI9) {
  AxisConfig c;
  c.limit_started_moves = true;
  build(c);
  clear();
  motors[0].displace(3000);  // on the upper limit
  wait(1);
  set_position(0);
  move_rel(100);
  ASSERT_TRUE(has(status::kMoving));
  issue(command::kImmediateStop);
  EXPECT_FALSE(any(status::kMoving));
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_EQ(errors(), 0);
  move_rel(100);
  ASSERT_TRUE(has(status::kMoving));
  estop = true;
  wait(0);
  EXPECT_EQ(errors(), status::kEmergencyStop);
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_EQ(motors[0].pulses_received(), 0u);  // no pulse ever went out
}

TEST_F(AxisSafety, Stp100_5_3_4_WithoutTheOptionTheSameMoveIsALimitError) {
  clear();
  motors[0].displace(3000);
  move_rel(400);
  EXPECT_EQ(errors(), status::kUpperLimit);
  EXPECT_FALSE(any(status::kMoving));
}

// ---- the emergency stop: SPM30 3.1/3.3.1, STP100 4.2.1 --------------------------------------

TEST_F(AxisSafety, Spm30_3_3_1_EmergencyStopDuringAMoveStopsBeforeTheNextStep) {
  clear();
  set_position(0);
  axis->words().running_velocity = 101;  // ~100 steps/s: 10 ms between steps
  axis->words().acceleration_ms = 3;
  move_rel(2000);
  wait(500);
  next_step();
  int64_t where = mech();
  uint64_t pulses = motors[0].pulses_received();
  wait(1);  // between two steps
  estop = true;
  wait(0);  // the node advances the axis whenever an input changes
  expect_sudden_stop(status::kEmergencyStop);
  wait(1000);
  EXPECT_EQ(mech(), where);  // no step after the input went active
  EXPECT_EQ(motors[0].pulses_received(), pulses);
  EXPECT_EQ(axis->motor_position(), where);
}

TEST_F(AxisSafety, Spm30_3_3_1_EmergencyStopWhileRunningFastHalts) {
  clear();
  set_position(0);
  move_rel(2500);
  wait(1000);
  estop = true;
  wait(0);
  expect_sudden_stop(status::kEmergencyStop);
  int64_t where = mech();
  wait(1000);
  EXPECT_EQ(mech(), where);
}

TEST_F(AxisSafety, Spm30_3_1_EmergencyStopActiveBeforeACommandRefusesEveryMotion) {
  clear();
  estop = true;
  wait(10);
  EXPECT_EQ(errors(), 0);  // STP100 4.2.1: "activated during move"
  for (uint16_t bit :
       {command::kMoveRelative, command::kJogUp, command::kFindHomeUp, command::kMoveIndexed}) {
    axis->words().destination = 100;
    issue(bit);
    EXPECT_EQ(errors(), status::kEmergencyStop) << bit;
    EXPECT_FALSE(any(status::kMoving)) << bit;
    hold(0);
    clear();  // the bit clears; the input is still active
    EXPECT_EQ(errors(), 0);
  }
  wait(1000);
  EXPECT_EQ(motors[0].pulses_received(), 0u);
  estop = false;
  move_rel(100);
  wait(2000);
  EXPECT_EQ(mech(), 100);
}

TEST_F(AxisSafety, Spm30_3_3_1_EmergencyStopWhileALimitStartedMoveWaits) {
  AxisConfig c;
  c.limit_started_moves = true;
  build(c);
  clear();
  motors[0].displace(3000);
  move_rel(100);
  ASSERT_TRUE(has(status::kMoving));
  estop = true;
  wait(0);
  EXPECT_EQ(errors(), status::kEmergencyStop);
  EXPECT_FALSE(any(status::kMoving));
  motors[0].config().upper_limit = 100000;
  wait(2000);
  EXPECT_EQ(motors[0].pulses_received(), 0u);
}

TEST_F(AxisSafety, Spm30_3_3_1_EmergencyStopDuringJogAndHome) {
  clear();
  hold(command::kJogUp);
  wait(300);
  estop = true;
  wait(0);
  expect_sudden_stop(status::kEmergencyStop);
  hold(0);
  estop = false;
  clear();
  axis->words().destination = 0;
  issue(command::kFindHomeUp);
  wait(300);
  estop = true;
  wait(0);
  expect_sudden_stop(status::kEmergencyStop);
}

// ---- master lost (heartbeat consumer timeout) -> %I8 ----------------------------------------

TEST_F(AxisSafety, MasterLost_MovingAxisDeceleratesNotHaltsAndLatchesWatchdog) {
  clear();
  set_position(0);
  move_rel(2900);
  wait(1000);
  ASSERT_TRUE(has(status::kMoving));
  ASSERT_FALSE(any(status::kAccelerating | status::kDecelerating));
  Tick lost = now;
  axis->master_lost(now);
  EXPECT_EQ(errors(), status::kPowerUp);
  EXPECT_TRUE(has(status::kMoving | status::kDecelerating));  // a ramp, not a halt
  EXPECT_EQ(events.back().kind, AxisEvent::Error);
  EXPECT_EQ(events.back().error_bits, status::kPowerUp);
  while (any(status::kMoving) && now < lost + ms(5000)) wait(0.1);
  StpcalcResult calc =
      stpcalc({.total = std::nullopt, .aq3 = 600, .aq4 = 100, .aq5 = 1000, .aq6 = 500, .aq7 = 0});
  EXPECT_NEAR(ticks_to_ms(now - lost), calc.deceleration_time_ms, 1.0);
  EXPECT_TRUE(has(status::kPositionValid));  // not a sudden stop
  EXPECT_FALSE(has(status::kResumable));
  EXPECT_LT(mech(), 2900);
  EXPECT_EQ(axis->motor_position(), mech());
  // Nothing is obeyed until Clear Errors.
  move_rel(10);
  hold(command::kJogUp);
  wait(500);
  EXPECT_FALSE(any(status::kMoving));
  hold(0);
  clear();
  move_rel(10);
  EXPECT_TRUE(has(status::kMoving));
}

// SPM30 4 IMMEDIATE STOP / DECELERATE AND STOP: "Status Bits Required: None", so they act
// while an error is latched, e.g. during the ramp after a lost master.
TEST_F(AxisSafety, Spm30_4_ImmediateStopIsObeyedWhileAnErrorIsLatched) {
  clear();
  set_position(0);
  move_rel(2900);
  wait(1000);
  axis->master_lost(now);
  ASSERT_EQ(errors(), status::kPowerUp);
  ASSERT_TRUE(has(status::kMoving | status::kDecelerating));
  wait(20);
  issue(command::kImmediateStop);
  EXPECT_FALSE(any(status::kMoving | status::kDecelerating));  // at once, not after the ramp
  EXPECT_FALSE(has(status::kPositionValid));                   // "If the axis was moving"
  EXPECT_EQ(errors(), status::kPowerUp);                       // still latched
  const int64_t stopped = mech();
  wait(2000);
  EXPECT_EQ(mech(), stopped);
}

TEST_F(AxisSafety, Spm30_4_DecelerateAndStopIsObeyedWhileAnErrorIsLatched) {
  clear();
  set_position(0);
  move_rel(2900);
  wait(1000);
  axis->master_lost(now);
  issue(command::kDecelStop);  // the ramp goes on to base velocity and stops
  EXPECT_TRUE(has(status::kMoving | status::kDecelerating));
  wait(5000);
  EXPECT_FALSE(any(status::kMoving));
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_FALSE(has(status::kResumable));  // "unless an error occurred"
  // The other commands still wait for Clear Errors.
  move_rel(10);
  EXPECT_FALSE(any(status::kMoving));
}

TEST_F(AxisSafety, MasterLost_JogStopsWithTheBitStillOnAndRepeatDoesNotRepeat) {
  clear();
  hold(command::kJogDown);
  wait(1000);
  axis->master_lost(now);
  EXPECT_TRUE(has(status::kDecelerating));
  wait(1000);
  EXPECT_FALSE(any(status::kMoving));
  hold(0);
  clear();
  set_position(0);
  hold(command::kRepeatMove);
  move_rel(300);
  wait(100);
  axis->master_lost(now);
  wait(5000);
  EXPECT_FALSE(any(status::kMoving));
  EXPECT_LE(mech(), 300);
  hold(0);
}

TEST_F(AxisSafety, MasterLost_DuringFindHomeStopsTheSearch) {
  sim::AxisMachineConfig m = machine();
  m.home = sim::Cam{900, 40};
  build({}, m);
  clear();
  axis->words().destination = 0;
  issue(command::kFindHomeUp);
  // At 1000 steps/s the ramp down takes ~275 steps: lost at ~800, it passes the cam.
  while (mech() < 800) wait(0.5);
  axis->master_lost(now);
  wait(10000);
  EXPECT_FALSE(any(status::kMoving));
  EXPECT_FALSE(has(status::kPositionValid));  // the search did not go on to completion
  EXPECT_GT(mech(), 940);
  EXPECT_EQ(errors(), status::kPowerUp);
}

TEST_F(AxisSafety, MasterLost_WhileStandingStillLatchesWatchdogOnly) {
  clear();
  set_position(5);
  axis->master_lost(now);
  EXPECT_EQ(axis->status(), status::kPowerUp | status::kPositionValid);
  wait(1000);
  EXPECT_EQ(mech(), 0);
}

}  // namespace
}  // namespace stepnode::motion
