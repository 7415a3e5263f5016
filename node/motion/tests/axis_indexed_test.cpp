// MOVE INDEXED (%Q11) and REPEAT MOVE (%Q12): STP113 = SPM30 appendix C (C1.3.2, C1.3.4),
// STP100 = HE800STP100 manual (4.2.3.7-4.2.3.10, 5.3.5, 5.3.6), in virtual time. The index
// window opens only at the running velocity and closes at the deceleration point; an index
// inside it ends the move %AQ8 steps past the index with the %AQ10 deceleration; DIR is taken
// low at the end of every indexed move.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <vector>

#include "node/motion/stpcalc.hpp"
#include "node/motion/tests/axis_harness.hpp"

namespace stepnode::motion {
namespace {

using harness::ms;

class AxisIndexed : public harness::AxisHarness {
 protected:
  static sim::AxisMachineConfig machine(int64_t index_at = 3000, int64_t width = 10) {
    sim::AxisMachineConfig m;
    m.encoder = sim::EncoderKind::None;
    m.index = sim::Cam{index_at, width};
    return m;
  }
  // A new axis, its errors cleared.
  void build(AxisConfig c = {}, sim::AxisMachineConfig m = machine()) {
    AxisHarness::build(c, m);
    clear();
  }
  void SetUp() override { build(); }
  void indexed(int32_t destination, uint32_t index_destination, uint32_t open, uint32_t close,
               uint16_t index_decel = 0) {
    CommandWords& w = axis->words();
    w.destination = destination;
    w.index_destination = index_destination;
    w.index_window_open = open;
    w.index_window_close = close;
    w.index_deceleration_ms = index_decel;
    issue(command::kMoveIndexed);
  }
  struct Sample {
    Tick t;
    int64_t mech;
    uint16_t status;
    bool dir;
  };
  std::vector<Sample> walk(double limit = 120000) {
    std::vector<Sample> out;
    Tick end = now + ms(limit);
    while (now < end && any(status::kMoving)) {
      auto next = axis->next_step_time();
      at(next ? std::min(*next, end) : std::min(now + ms(0.1), end));
      out.push_back({now, mech(), axis->status(), axis->dir_output_high()});
    }
    return out;
  }
  static Tick first(const std::vector<Sample>& s, uint16_t bit) {
    for (const auto& x : s)
      if (x.status & bit) return x.t;
    return -1;
  }
};

TEST_F(AxisIndexed, Stp100_5_3_5_IndexInsideTheWindowEndsIndexDestinationPastIt) {
  axis->words().deceleration_ms = 400;
  indexed(10000, 700, 1000, 8000, /*index_decel=*/250);
  EXPECT_TRUE(axis->dir_output_high());  // DIR set by the direction at the start
  auto s = walk();
  EXPECT_EQ(mech(), 3000 + 700);  // N more steps beyond the index point
  EXPECT_EQ(axis->motor_position(), 3700);
  EXPECT_EQ(errors(), 0);
  EXPECT_FALSE(axis->dir_output_high());  // taken low at the end of an indexed move
  for (size_t i = 0; i + 1 < s.size(); ++i) EXPECT_TRUE(s[i].dir) << i;  // high while moving
  // The alternate deceleration (%AQ10, 4.2.3.8) from the running velocity.
  StpcalcResult calc =
      stpcalc({.total = std::nullopt, .aq3 = 600, .aq4 = 100, .aq5 = 1000, .aq6 = 500, .aq7 = 250});
  Tick decel = first(s, status::kDecelerating);
  ASSERT_GT(decel, 0);
  EXPECT_NEAR(ticks_to_ms(s.back().t - decel), calc.deceleration_time_ms, 1.5);
  int64_t decel_from = 0;
  for (const auto& x : s)
    if (x.status & status::kDecelerating) {
      decel_from = x.mech;
      break;
    }
  EXPECT_NEAR(static_cast<double>(3700 - decel_from + 1), calc.deceleration_pulses, 1.5);
}

// STP100 5.3.5: the new end point "is defined to be N more steps (in the same direction)
// beyond the point at which the Index Input became active". An N shorter than the %AQ10 ramp
// (250 ms from 1000 to 100 steps/s: about 137 pulses) still ends there, and the motor still
// slows to the base velocity before it stops (a stepper stops safely only from its base
// velocity): the deceleration takes the time that fits. Before: the ramp was cut at 984 steps/s.
TEST_F(AxisIndexed, Stp100_5_3_5_IndexDestinationCloserThanTheRampEndsThereAtTheBaseVelocity) {
  for (uint32_t n : {40u, 100u, 136u}) {
    build();
    indexed(10000, n, 1000, 8000, /*index_decel=*/250);
    std::vector<Tick> steps;
    Tick index_time = -1;
    int64_t last = mech();
    Tick end = now + ms(20000);
    while (now < end && any(status::kMoving)) {
      auto next = axis->next_step_time();
      at(next ? std::min(*next, end) : end);
      if (mech() != last) {
        last = mech();
        if (mech() >= 3000) steps.push_back(now);
        if (mech() == 3000) index_time = now;
      }
    }
    EXPECT_EQ(mech(), 3000 + n) << n;  // exactly N past the index
    EXPECT_EQ(errors(), 0) << n;
    ASSERT_GT(index_time, 0);
    ASSERT_GE(steps.size(), 3u);
    // The last step comes at about the base velocity (100 steps/s: 10 ms; the step spans the
    // ramp's last levels, so its mean rate is a little above base): under twice the base.
    double last_interval_ms = ticks_to_ms(steps.back() - steps[steps.size() - 2]);
    EXPECT_GT(last_interval_ms, 1000.0 / 200) << n;
    // And the intervals only grow from the index on: a deceleration, no jump.
    for (size_t i = 2; i < steps.size(); ++i)
      EXPECT_GE(steps[i] - steps[i - 1] + 1, steps[i - 1] - steps[i - 2]) << n << " step " << i;
  }
}

TEST_F(AxisIndexed, Stp100_4_2_3_8_ZeroIndexDecelerationMeansTheNormalOne) {
  axis->words().deceleration_ms = 300;
  indexed(10000, 900, 1000, 8000, 0);
  auto s = walk();
  EXPECT_EQ(mech(), 3900);
  StpcalcResult calc =
      stpcalc({.total = std::nullopt, .aq3 = 600, .aq4 = 100, .aq5 = 1000, .aq6 = 500, .aq7 = 300});
  EXPECT_NEAR(ticks_to_ms(s.back().t - first(s, status::kDecelerating)), calc.deceleration_time_ms,
              1.5);
}

TEST_F(AxisIndexed, C1_3_4_AlternateDestinationMayBeLongerThanTheMove) {
  indexed(4000, 5000, 1000, 3500);
  walk();
  EXPECT_EQ(mech(), 8000);  // longer than the default relative move (STP100 5.3.5)
}

TEST_F(AxisIndexed, C1_3_4_IndexBeforeTheWindowOpensIsAPlainRelativeMove) {
  indexed(6000, 700, 3500, 5000);
  walk();
  EXPECT_EQ(mech(), 6000);
  EXPECT_FALSE(axis->dir_output_high());  // still an indexed move: DIR low at its end
}

TEST_F(AxisIndexed, C1_3_4_IndexAfterTheWindowClosesIsAPlainRelativeMove) {
  indexed(6000, 700, 1000, 2999);
  walk();
  EXPECT_EQ(mech(), 6000);
}

TEST_F(AxisIndexed, Stp100_5_3_5_WindowOpensOnlyAtTheRunningVelocity) {
  build({}, machine(200));  // the index during the acceleration (about 275 steps)
  indexed(6000, 700, 100, 5000);
  walk();
  EXPECT_EQ(mech(), 6000);
  // A move too short to reach the running velocity never opens the window.
  build({}, machine(200));
  indexed(450, 10, 1, 440);
  walk();
  EXPECT_EQ(mech(), 450);
}

TEST_F(AxisIndexed, Stp100_5_3_5_WindowClosesAtTheDecelerationPoint) {
  build({}, machine(3850));  // decelerating from about 3725 on
  indexed(4000, 50, 1000, 1'000'000);
  walk();
  EXPECT_EQ(mech(), 4000);
}

TEST_F(AxisIndexed, C1_3_4_IndexAlreadyActiveWhenTheWindowOpensIsNotAccepted) {
  build({}, machine(2990, 30));    // active on [2990, 3019]
  indexed(6000, 700, 3000, 5000);  // opens while the input is already on
  walk();
  EXPECT_EQ(mech(), 6000);  // received before the window: ignored
}

TEST_F(AxisIndexed, Stp100_5_3_5_IndexedMoveDownEndsBelowTheIndex) {
  build({}, machine(-3010, 10));  // active on [-3010, -3001]
  indexed(-6000, 700, 1000, 5000);
  EXPECT_FALSE(axis->dir_output_high());
  walk();
  EXPECT_EQ(mech(), -3001 - 700);
  EXPECT_FALSE(axis->dir_output_high());
}

// STP100 5.3.5 NOTE: "at the end of an Indexed Move, DIR+ and DIR- are always taken Low and
// High", whatever ended it.
TEST_F(AxisIndexed, Stp100_5_3_5_DirGoesLowAtTheEndOfAnIndexedMoveWhateverEndedIt) {
  enum class End { DecelStop, ImmediateStop, Limit, EmergencyStop };
  for (End how : {End::DecelStop, End::ImmediateStop, End::Limit, End::EmergencyStop}) {
    sim::AxisMachineConfig m = machine(50'000);
    m.upper_limit = 2000;
    build({}, m);
    indexed(10000, 700, 1000, 8000);
    ASSERT_TRUE(axis->dir_output_high());
    if (how != End::Limit) wait(300);
    switch (how) {
      case End::DecelStop: issue(command::kDecelStop); break;
      case End::ImmediateStop: issue(command::kImmediateStop); break;
      case End::EmergencyStop: estop = true; break;
      case End::Limit: break;
    }
    walk();
    EXPECT_FALSE(any(status::kMoving)) << static_cast<int>(how);
    EXPECT_LT(mech(), 10000) << static_cast<int>(how);
    EXPECT_FALSE(axis->dir_output_high()) << static_cast<int>(how);
    estop = false;
  }
}

// STP100 5.3.9 DECELERATE AND STOP: "If this command pre-empts a Move Relative or Move Absolute
// command, the Pre-empted Move Resumable Status bit (%I10) is turned ON"; Move Indexed's
// "Status Bits Affected" (5.3.5) have no %I10, and RESUME MOVE (5.3.7) resumes "a previously
// pre-empted Relative Move or Absolute Move". A stopped indexed move is not resumable, also
// one stopped while it waits for a limit's release (5.3.4).
TEST_F(AxisIndexed, Stp100_5_3_9_DecelerateAndStopOfAnIndexedMoveIsNotResumable) {
  indexed(10000, 700, 1000, 8000);
  wait(1500);
  ASSERT_TRUE(has(status::kMoving));
  issue(command::kDecelStop);
  walk();
  ASSERT_FALSE(any(status::kMoving));
  ASSERT_LT(mech(), 3000);  // short of the index and of the target
  EXPECT_FALSE(has(status::kResumable));
  issue(command::kResumeMove);
  EXPECT_EQ(errors(), status::kIllegalMove);

  AxisConfig c;
  c.limit_started_moves = true;
  sim::AxisMachineConfig m = machine();
  m.upper_limit = 2000;
  build(c, m);
  motors[0].displace(2000);  // on the upper limit
  wait(1);
  indexed(10000, 700, 1000, 8000);
  ASSERT_TRUE(has(status::kMoving));  // waiting for the limit's release
  issue(command::kDecelStop);
  EXPECT_FALSE(has(status::kResumable));
  wait(1);
  EXPECT_FALSE(any(status::kMoving | status::kResumable));
  EXPECT_EQ(motors[0].pulses_received(), 0u);
}

TEST_F(AxisIndexed, Stp100_5_3_5_RelativeAndAbsoluteMovesLeaveDirAsItWas) {
  axis->words().destination = 100;
  issue(command::kMoveRelative);
  walk();
  EXPECT_TRUE(axis->dir_output_high());
  axis->words().destination = 0;
  issue(command::kSetPosition);
  axis->words().destination = -50;
  issue(command::kMoveAbsolute);
  walk();
  EXPECT_FALSE(axis->dir_output_high());
  axis->words().destination = 50;
  issue(command::kMoveAbsolute);
  walk();
  EXPECT_TRUE(axis->dir_output_high());
}

TEST_F(AxisIndexed, Spm30_3_4_IndexWordsMayChangeOnceTheMoveStarted) {
  indexed(10000, 700, 1000, 8000, 250);
  CommandWords& w = axis->words();  // prepared for the next move at once
  w.index_destination = 50;
  w.index_window_open = 9000;
  w.index_window_close = 9500;
  w.index_deceleration_ms = 27300;  // not even legal with these velocities
  w.destination = 1;
  walk();
  EXPECT_EQ(errors(), 0);
  EXPECT_EQ(mech(), 3700);
}

TEST_F(AxisIndexed, C1_3_2_Q11IsFutureUseWithoutIndexedMoves) {
  AxisConfig c;
  c.indexed_moves = false;  // SPM30 3.2 (%Q11 future use) / STP100 3.2.3 box unchecked
  build(c);
  indexed(1000, 10, 1, 900);
  EXPECT_FALSE(any(status::kMoving));
  EXPECT_EQ(errors(), 0);
  wait(3000);
  EXPECT_EQ(mech(), 0);
}

// ---- STP100 5.3.6 REPEAT MOVE with indexed moves -------------------------------------------

TEST_F(AxisIndexed, Stp100_5_3_6_RepeatedIndexedMovesRegisterOnEachIndex) {
  // A registration mark every 3000 steps, seen by the index input as the material passes.
  hold(command::kRepeatMove);
  indexed(10000, 700, 1000, 8000);
  std::vector<int64_t> ends;
  for (int k = 0; k < 3; ++k) {
    int64_t mark = 3000 + 3700 * k;
    motors[0].config().index = sim::Cam{mark, 10};
    // Run until this move ends: the next one starts at once and raises DIR again.
    while (mech() < mark + 700) {
      auto next = axis->next_step_time();
      ASSERT_TRUE(next.has_value());
      at(*next);
    }
    ASSERT_EQ(mech(), mark + 700) << k;
    ends.push_back(mech());
    EXPECT_TRUE(has(status::kMoving)) << k;  // repeated immediately
    EXPECT_TRUE(axis->dir_output_high()) << k;
  }
  EXPECT_EQ(ends, (std::vector<int64_t>{3700, 7400, 11100}));
  // Released during the 4th move: no mark in its window, it completes as a relative move.
  motors[0].config().index.reset();
  hold(0);
  walk();
  EXPECT_EQ(mech(), 11100 + 10000);
  EXPECT_FALSE(axis->dir_output_high());
  EXPECT_FALSE(any(status::kMoving));
}

TEST_F(AxisIndexed, Stp100_5_3_6_RepeatedIndexedMoveWithoutIndexRepeatsTheRelativeDistance) {
  motors[0].config().index.reset();
  hold(command::kRepeatMove);
  indexed(-1500, 700, 1000, 8000);
  while (mech() > -3200) wait(1);
  hold(0);  // during the third move: it completes, no fourth
  walk();
  EXPECT_EQ(mech(), -4500);
  EXPECT_EQ(axis->motor_position(), -4500);
}

}  // namespace
}  // namespace stepnode::motion
