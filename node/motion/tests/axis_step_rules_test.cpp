// The Horner rules of a jog or a move act only at some steps, and the core calls after_step
// at those only (Axis::hooks): an active end limit (SPM30 3.3.1), the position a jog's end
// on the bound of the position words is set from (SPM30 3.3), an indexed move's window till
// its index (STP100 5.3.5), and, once a new configuration turns them on, the encoder's stall
// windows (SPM30 5.4); a move's step count is the generator's. Each must act at exactly its
// step however many steps one advance takes (the device advances once per tick, or less).
#include "node/motion/tests/axis_harness.hpp"

namespace stepnode::motion {
namespace {

class AxisStepRules : public harness::AxisHarness {
 protected:
  void build_with(AxisConfig c, sim::AxisMachineConfig m) {
    build(c, m);
    clear();
  }
  // Far enough for any of these jogs to have ended, in one advance.
  void one_long_advance() { wait(600'000); }
};

TEST_F(AxisStepRules, Spm30_3_3_1_AJogStopsAtTheStepThatReachesTheUpperLimit) {
  sim::AxisMachineConfig m = plain();
  m.upper_limit = 500;  // active at 500 and above
  build_with({}, m);
  hold(command::kJogUp);
  one_long_advance();
  EXPECT_EQ(mech(), 500);  // no step after the one that made the limit active
  EXPECT_TRUE(has(status::kUpperLimit));
  EXPECT_FALSE(any(status::kMoving));
}

TEST_F(AxisStepRules, Spm30_3_3_1_AJogOffTheLowerLimitGoesOnAndStopsAtTheUpperOne) {
  sim::AxisMachineConfig m = plain();
  m.lower_limit = 0;  // active at the start (position 0) and below
  m.upper_limit = 300;
  build_with({}, m);
  ASSERT_TRUE(motors[0].levels().lower_limit());
  hold(command::kJogUp);  // away from the active limit: allowed (SPM30 3.3.1)
  one_long_advance();
  EXPECT_EQ(mech(), 300);
  EXPECT_EQ(errors(), status::kUpperLimit);  // the lower one, left behind, latched nothing
}

TEST_F(AxisStepRules, Spm30_3_3_1_AJogDownStopsAtTheStepThatReachesTheLowerLimit) {
  sim::AxisMachineConfig m = plain();
  m.lower_limit = -250;  // active at -250 and below
  build_with({}, m);
  hold(command::kJogDown);
  one_long_advance();
  EXPECT_EQ(mech(), -250);
  EXPECT_TRUE(has(status::kLowerLimit));
}

TEST_F(AxisStepRules, Spm30_3_3_AJogEndsOnTheBoundInOneAdvance) {
  build_with({}, plain());
  set_position(8'380'000);  // far from the bound: the jog runs without an end at first
  hold(command::kJogUp);
  one_long_advance();
  EXPECT_EQ(axis->motor_position(), 8'388'607);  // neither short of it nor past it
  EXPECT_EQ(mech(), 8'607);
  EXPECT_EQ(errors(), 0);
  EXPECT_FALSE(any(status::kMoving));
}

TEST_F(AxisStepRules, Spm30_3_3_AJogDownEndsOnTheLowerBoundInOneAdvance) {
  build_with({}, plain());
  set_position(-8'380'000);
  hold(command::kJogDown);
  one_long_advance();
  EXPECT_EQ(axis->motor_position(), -8'388'608);
  EXPECT_EQ(mech(), -8'608);
  EXPECT_EQ(errors(), 0);
}

TEST_F(AxisStepRules, Spm30_5_4_StallDetectionTurnedOnWithinAJogLooksAtItsNextSteps) {
  // 2000 steps and 500 lines a revolution: a line every 4 steps, scaled back by MLT 4.
  sim::AxisMachineConfig m;
  m.stall_above = 300;  // the motor jams at 300
  AxisConfig c;
  c.encoder = EncoderKind::Quadrature;
  c.encoder_multiplier = 4;
  build_with(c, m);  // tolerance 0: no stall detection (SPM30 5.4)
  hold(command::kJogUp);
  while (axis->motor_position() < 100) at(*axis->next_step_time());
  c.encoder_tolerance = 5;  // stall detection on from the next step
  axis->set_config(c);
  one_long_advance();
  // Windows of 20 lines = 80 commanded steps from 100: 180, 260, 340 (the jam at 300 shows
  // 10 lines in it, over 10 %), 420 (no line at all: < 10 %, a stall).
  EXPECT_EQ(axis->motor_position(), 420);
  EXPECT_EQ(mech(), 300);
  EXPECT_TRUE(has(status::kMotorStalled));
  EXPECT_FALSE(any(status::kMoving));
}

TEST_F(AxisStepRules, Spm30_3_3_1_AMoveStopsAtTheStepThatReachesTheUpperLimit) {
  sim::AxisMachineConfig m = plain();
  m.upper_limit = 700;
  build_with({}, m);
  move_rel(5000);
  one_long_advance();
  EXPECT_EQ(mech(), 700);
  EXPECT_TRUE(has(status::kUpperLimit));
  EXPECT_FALSE(any(status::kResumable));  // an error ended it (SPM30 %Q15)
}

TEST_F(AxisStepRules, Spm30_4_AMoveStoppedShortAndResumedEndsOnItsTarget) {
  build_with({}, plain());
  move_rel(-3000);
  while (axis->motor_position() > -1000) at(*axis->next_step_time());
  issue(command::kDecelStop);
  one_long_advance();
  const int64_t stopped_at = mech();
  ASSERT_GT(stopped_at, -3000);  // short of the target: resumable
  ASSERT_TRUE(has(status::kResumable));
  issue(command::kResumeMove);  // the rest of the move: from the steps the first one took
  one_long_advance();
  EXPECT_EQ(mech(), -3000);
  EXPECT_EQ(axis->motor_position(), -3000);
  EXPECT_FALSE(any(status::kResumable));  // done: nothing left to resume
  EXPECT_EQ(errors(), 0);
}

TEST_F(AxisStepRules, Stp100_5_3_5_AnIndexedMoveEndsIndexDestinationPastTheIndexInOneAdvance) {
  sim::AxisMachineConfig m = plain();
  m.index = sim::Cam{2500, 10};  // active from the step to 2500
  build_with({}, m);
  CommandWords& w = axis->words();
  w.destination = 9000;
  w.index_destination = 400;
  w.index_window_open = 1000;
  w.index_window_close = 8000;
  issue(command::kMoveIndexed);
  one_long_advance();
  EXPECT_EQ(mech(), 2500 + 400);  // N more steps beyond the index point
  EXPECT_EQ(errors(), 0);
}

}  // namespace
}  // namespace stepnode::motion
