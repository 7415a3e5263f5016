// The positions the module can hold (SPM30 3.3 / 3.4, C1.3.4; STP100 table 4.1), in virtual
// time: MOTOR POSITION and DESTINATION POSITION are -8,388,608..+8,388,607, "the maximum
// relative move would be 8,388,608 pulses, while the maximum absolute move would be
// 16,777,215 pulses" (B1.2.1). A move that would end outside is not possible (Illegal Move),
// a jog stops on the bound, and the index words are in the module model's ranges.
#include "node/motion/tests/axis_harness.hpp"

namespace stepnode::motion {
namespace {

using harness::ms;

class AxisPositionRange : public harness::AxisHarness {
 protected:
  void SetUp() override {
    build();
    clear();
  }
  void fast_profile() {
    CommandWords& w = axis->words();
    w.velocity_divisor = 20;  // the smallest divisor: the fastest steps (SPM30 3.4.2)
    w.running_velocity = 8000;
    w.base_velocity = 4000;
    w.acceleration_ms = 100;
  }
};

TEST_F(AxisPositionRange, Spm30_3_3_RelativeMovePastThePositionRangeIsIllegal) {
  set_position(8'388'000);
  move_rel(607);  // ends on +8,388,607: legal
  walk_steps();
  EXPECT_EQ(axis->motor_position(), 8'388'607);
  EXPECT_EQ(errors(), 0);
  move_rel(1);  // would end on 8,388,608
  EXPECT_TRUE(has(status::kIllegalMove));
  EXPECT_FALSE(any(status::kMoving));
  EXPECT_EQ(axis->motor_position(), 8'388'607);
  clear();
  set_position(-8'388'000);
  move_rel(-609);  // would end on -8,388,609
  EXPECT_TRUE(has(status::kIllegalMove));
  EXPECT_EQ(mech(), 607);  // nothing moved
}

TEST_F(AxisPositionRange, SpmB1_2_1_TheLongestAbsoluteMoveIs16777215Pulses) {
  fast_profile();
  set_position(-8'388'608);
  move_abs(8'388'607);
  for (int second = 0; second < 3600 && any(status::kMoving); ++second) wait(1000);
  EXPECT_EQ(errors(), 0);
  EXPECT_EQ(mech(), 16'777'215);  // pulses sent
  EXPECT_EQ(axis->motor_position(), 8'388'607);
}

TEST_F(AxisPositionRange, Spm30_3_3_JogStopsOnTheBoundOfThePositionWords) {
  set_position(8'387'000);
  hold(command::kJogUp);  // held: a jog runs until released, here until the bound
  walk_steps();
  EXPECT_EQ(axis->motor_position(), 8'388'607);
  EXPECT_EQ(errors(), 0);
  EXPECT_FALSE(any(status::kMoving));
  // At the bound, no jog further up (not possible: Illegal Move); down is free.
  hold(0);
  hold(command::kJogUp);
  EXPECT_TRUE(has(status::kIllegalMove));
  hold(0);
  clear();
  hold(command::kJogDown);
  wait(200);
  EXPECT_TRUE(any(status::kMoving));
  EXPECT_LT(axis->motor_position(), 8'388'607);
}

TEST_F(AxisPositionRange, Spm30_3_3_JogDownStopsOnTheLowerBound) {
  set_position(-8'387'900);
  hold(command::kJogDown);
  walk_steps();
  EXPECT_EQ(axis->motor_position(), -8'388'608);
  EXPECT_EQ(errors(), 0);
}

TEST_F(AxisPositionRange, Spm30_C1_3_4_IndexWordsAre0To8388607) {
  CommandWords& w = axis->words();
  w.destination = 1000;
  w.index_window_open = 0;
  w.index_window_close = 8'388'607;
  w.index_destination = 8'388'608;  // one above the STP113's range
  issue(command::kMoveIndexed);
  EXPECT_TRUE(has(status::kIllegalMove));
  clear();
  w.index_destination = 0;
  w.index_window_close = 8'388'608;
  issue(command::kMoveIndexed);
  EXPECT_TRUE(has(status::kIllegalMove));
  clear();
  w.index_window_close = 8'388'607;
  issue(command::kMoveIndexed);  // every word at a bound of its range: legal
  EXPECT_EQ(errors(), 0);
  walk_steps();
  EXPECT_EQ(mech(), 1000);
}

TEST_F(AxisPositionRange, Stp100_Table4_1_IndexWordsAre1To16777215) {
  AxisConfig c;
  c.module = AxisConfig::Module::Stp100;
  build(c);
  clear();
  CommandWords& w = axis->words();
  w.destination = 1000;
  w.index_window_open = 1;
  w.index_window_close = 16'777'215;  // legal on the STP100 (not on the STP113)
  set_position(-8'388'608);
  w.destination = 1000;
  // An index at step 999 at the latest, the end that far past it: +8,388,607 at most.
  w.index_destination = 16'777'215 - 999;
  issue(command::kMoveIndexed);
  EXPECT_EQ(errors(), 0);
  issue(command::kImmediateStop);
  clear();
  w.index_window_open = 0;  // below the STP100's range
  issue(command::kMoveIndexed);
  EXPECT_TRUE(has(status::kIllegalMove));
}

TEST_F(AxisPositionRange, Spm30_3_3_IndexedMoveWhoseIndexCouldEndOutsideIsIllegal) {
  CommandWords& w = axis->words();
  set_position(8'380'000);
  w.destination = 5000;  // the relative move ends on 8,385,000: inside
  w.index_window_open = 100;
  w.index_window_close = 4000;  // an index up to step 3999 ...
  w.index_destination = 3608;   // ... ends 3608 past it: 8,387,607 at most, inside
  issue(command::kMoveIndexed);
  EXPECT_EQ(errors(), 0);
  issue(command::kImmediateStop);
  clear();
  set_position(8'380'000);
  w.destination = 5000;
  w.index_destination = 4608;  // 8,388,607 at most: still inside
  issue(command::kMoveIndexed);
  EXPECT_EQ(errors(), 0);
  issue(command::kImmediateStop);
  clear();
  set_position(8'380'000);
  w.destination = 5000;
  w.index_destination = 4609;  // an index at step 3999 would end on 8,388,608
  issue(command::kMoveIndexed);
  EXPECT_TRUE(has(status::kIllegalMove));
}

TEST_F(AxisPositionRange, Stp100_5_3_6_RepeatedMoveStopsBeforeLeavingThePositions) {
  set_position(8'388'000);
  axis->words().destination = 300;
  hold(command::kRepeatMove);
  issue(command::kMoveRelative);
  walk_steps();
  wait(1);
  walk_steps();  // 8,388,600 after two; a third would end on 8,388,900
  wait(1);
  walk_steps();
  EXPECT_EQ(axis->motor_position(), 8'388'600);
  EXPECT_TRUE(has(status::kIllegalMove));
}

}  // namespace
}  // namespace stepnode::motion
