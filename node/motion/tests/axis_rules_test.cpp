// The axis against the module's rules, each test naming the manual section it checks
// (SPM30 = HE693STP manual, STP100 = HE800STP100 manual, C = SPM30 appendix C).
#include <gtest/gtest.h>

#include "node/motion/stpcalc.hpp"
#include "node/motion/tests/axis_harness.hpp"

namespace stepnode::motion {
namespace {

// These tests let 100 ticks pass between a command bit's edges (as a PLC scan does) and
// clear the power-up error themselves: `pulse` and `hold` below, not the harness' `issue`.
class AxisRules : public harness::AxisHarness {
 protected:
  void SetUp() override { build({}); }
  // Three motors on the bench; a multiplexed axis drives all three, any other the first.
  void build(AxisConfig config, sim::AxisMachineConfig machine = default_machine()) {
    AxisHarness::build(config, machine, config_multiplexed ? 3 : 1, 3);
  }
  static sim::AxisMachineConfig default_machine() {
    sim::AxisMachineConfig m;
    m.home = sim::Cam{5000, 40};
    m.lower_limit = -20000;
    m.upper_limit = 20000;
    return m;
  }
  // Commands are edges: the bit goes on, then off again.
  void pulse(uint16_t bits) {
    axis->write_commands(static_cast<uint16_t>(held | bits), now);
    axis->write_commands(held, now += 100);
  }
  void hold(uint16_t bits) {
    held = bits;
    axis->write_commands(held, now += 100);
  }
  void run_ms(int64_t ms) { axis->advance_to(now += ms * kClockHz / 1000); }
  void clear() { pulse(command::kClearErrors); }
  void set_position(int32_t p) {
    axis->words().destination = p;
    pulse(command::kSetPosition);
  }
  void move_rel(int32_t d) {
    axis->words().destination = d;
    pulse(command::kMoveRelative);
  }
  // Any of the bits (the harness' `has` wants all of them).
  bool has(uint16_t bits) const { return any(bits); }

  bool config_multiplexed = false;
};

TEST_F(AxisRules, Spm30_3_1_PowerUpOnlyWatchdogErrorAndOnlyClearObeyed) {
  EXPECT_EQ(axis->status() & ~status::kAtHome, status::kPowerUp);
  move_rel(100);
  run_ms(500);
  EXPECT_EQ(motors[0].position(), 0);
  pulse(command::kJogUp);
  EXPECT_FALSE(has(status::kMoving));
  clear();
  EXPECT_FALSE(has(status::kPowerUp));
  move_rel(100);
  run_ms(2000);
  EXPECT_EQ(motors[0].position(), 100);
}

TEST_F(AxisRules, Spm30_3_2_HighestBitWinsAndOnlyStopsWhileMoving) {
  clear();
  axis->words().destination = 777;
  pulse(command::kMoveRelative | command::kSetPosition);  // %Q13 > %Q8
  EXPECT_FALSE(has(status::kMoving));
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_EQ(axis->motor_position(), 777);
  move_rel(3000);
  run_ms(50);
  ASSERT_TRUE(has(status::kMoving));
  axis->words().destination = 1;
  pulse(command::kSetPosition);  // ignored while moving
  pulse(command::kMoveRelative);
  run_ms(20);
  EXPECT_NE(axis->motor_position(), 1);
  pulse(command::kDecelStop);
  EXPECT_TRUE(has(status::kDecelerating));
}

TEST_F(AxisRules, Spm30_3_4_OutOfRangeWordsAreIllegalMoves) {
  clear();
  axis->words().destination = 8'388'608;
  pulse(command::kMoveRelative);
  EXPECT_TRUE(has(status::kIllegalMove));
  clear();
  axis->words().destination = 100;
  axis->words().running_velocity = axis->words().base_velocity;  // must exceed base (3.4.4)
  pulse(command::kMoveRelative);
  EXPECT_TRUE(has(status::kIllegalMove));
  EXPECT_EQ(motors[0].position(), 0);
}

TEST_F(AxisRules, Spm30_Jog_LevelSensitiveAndTriangularWhenReleasedEarly) {
  clear();
  hold(command::kJogUp);
  run_ms(200);  // accelerating for 500 ms: released before running velocity
  EXPECT_TRUE(has(status::kAccelerating));
  double v = axis->velocity();
  hold(0);
  EXPECT_TRUE(has(status::kDecelerating));
  EXPECT_LT(v, 1000.0);
  run_ms(1000);
  EXPECT_FALSE(has(status::kMoving));
  EXPECT_GT(motors[0].position(), 0);
}

TEST_F(AxisRules, Spm30_ResumeMove_AnyNumberOfTimesUntilTheTarget) {
  clear();
  set_position(0);
  axis->words().destination = 6000;
  pulse(command::kMoveAbsolute);
  for (int i = 0; i < 2; ++i) {
    run_ms(1200);
    pulse(command::kDecelStop);
    run_ms(1000);
    ASSERT_FALSE(has(status::kMoving));
    ASSERT_TRUE(has(status::kResumable)) << i;  // %I10 (SPM30 DECELERATE AND STOP)
    EXPECT_LT(motors[0].position(), 6000);
    pulse(command::kResumeMove);
    EXPECT_FALSE(has(status::kResumable));
  }
  run_ms(10000);
  EXPECT_EQ(axis->motor_position(), 6000);
  EXPECT_FALSE(has(status::kResumable));
  // Another command after the pre-emption ends resumability; Resume is then illegal.
  axis->words().destination = 9000;
  pulse(command::kMoveAbsolute);
  run_ms(500);
  pulse(command::kDecelStop);
  run_ms(1000);
  ASSERT_TRUE(has(status::kResumable));
  set_position(0);
  EXPECT_FALSE(has(status::kResumable));
  pulse(command::kResumeMove);
  EXPECT_TRUE(has(status::kIllegalMove));
}

TEST_F(AxisRules, Stp100_5_3_6_RepeatMoveWhileQ12IsOn) {
  clear();
  hold(command::kRepeatMove);
  move_rel(200);
  run_ms(3000);
  int64_t after = motors[0].position();
  EXPECT_GT(after, 400);  // repeated
  hold(0);
  run_ms(2000);
  int64_t final_position = motors[0].position();
  EXPECT_FALSE(has(status::kMoving));
  EXPECT_EQ(final_position % 200, 0);
  EXPECT_LE(final_position, after + 200);  // the move in progress completes, no more
}

TEST_F(AxisRules, C1_Stp100_5_3_5_IndexedMoveInsideAndOutsideTheWindow) {
  sim::AxisMachineConfig m = default_machine();
  m.index = sim::Cam{3000, 10};
  build({}, m);
  clear();
  CommandWords& w = axis->words();
  w.index_destination = 700;
  w.index_window_open = 1000;
  w.index_window_close = 8000;
  w.destination = 10000;
  pulse(command::kMoveIndexed);
  EXPECT_TRUE(axis->dir_output_high());
  run_ms(20000);
  EXPECT_EQ(motors[0].position(), 3000 + 700);  // N steps after the index input
  EXPECT_FALSE(axis->dir_output_high());        // DIR as move-in-progress
  // Window opening after the index: a plain relative move.
  build({}, m);
  clear();
  axis->words().index_destination = 700;
  axis->words().index_window_open = 3500;
  axis->words().index_window_close = 8000;
  axis->words().destination = 6000;
  pulse(command::kMoveIndexed);
  run_ms(20000);
  EXPECT_EQ(motors[0].position(), 6000);
}

TEST_F(AxisRules, Spm30_3_3_1_LimitStopsLatchesInvalidatesAndAllowsMovingAway) {
  clear();
  set_position(0);
  move_rel(-30000);
  run_ms(60000);
  EXPECT_TRUE(has(status::kLowerLimit));
  EXPECT_FALSE(has(status::kPositionValid));
  EXPECT_FALSE(has(status::kMoving));
  EXPECT_EQ(motors[0].position(), -20000);  // stopped on the step that hit the switch
  clear();
  move_rel(-10);  // toward the active limit: refused
  EXPECT_TRUE(has(status::kLowerLimit));
  EXPECT_EQ(motors[0].position(), -20000);
  clear();
  move_rel(500);  // away from it
  run_ms(5000);
  EXPECT_EQ(motors[0].position(), -19500);
  EXPECT_EQ(axis->status() & status::kErrors, 0);
}

TEST_F(AxisRules, Stp100_5_3_4_LimitStartedMoveWaitsForTheLimitToRelease) {
  AxisConfig c;
  c.limit_started_moves = true;
  sim::AxisMachineConfig m = default_machine();
  m.upper_limit = 0;  // active where the motor is
  build(c, m);
  clear();
  move_rel(300);
  run_ms(1000);
  EXPECT_EQ(motors[0].position(), 0);
  motors[0].config().upper_limit = 100000;  // the limit input deactivates
  run_ms(0);                                // (the node advances on every input change)
  EXPECT_TRUE(has(status::kMoving));
  run_ms(3000);
  EXPECT_EQ(motors[0].position(), 300);
}

TEST_F(AxisRules, Spm30_3_1_EmergencyStopDuringAndBeforeAMove) {
  clear();
  set_position(0);
  move_rel(5000);
  run_ms(300);
  estop = true;
  run_ms(10);
  EXPECT_TRUE(has(status::kEmergencyStop));
  EXPECT_FALSE(has(status::kPositionValid));
  EXPECT_FALSE(has(status::kMoving));
  clear();
  move_rel(10);
  EXPECT_TRUE(has(status::kEmergencyStop));
}

TEST_F(AxisRules, Spm30_ImmediateStopInvalidatesOnlyWhenMoving) {
  clear();
  set_position(0);
  pulse(command::kImmediateStop);
  EXPECT_TRUE(has(status::kPositionValid));
  move_rel(5000);
  run_ms(300);
  pulse(command::kImmediateStop);
  EXPECT_FALSE(has(status::kMoving));
  EXPECT_FALSE(has(status::kPositionValid));
}

TEST_F(AxisRules, Spm30_4_FindHomeNormalFromAboveAndSimpleOvershoots) {
  clear();
  set_position(9000);
  motors[0].displace(9000);
  axis->words().destination = 0;
  pulse(command::kFindHomeDown);
  run_ms(60000);
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_TRUE(has(status::kAtHome));
  // Step 7 approaches in the search direction again: from above, the cam's top step.
  EXPECT_EQ(motors[0].position(), 5039);
  EXPECT_EQ(axis->motor_position(), 0);
  // Simple method: stops at the first step on the cam (steps 4-7 skipped).
  AxisConfig simple;
  simple.home_method = AxisConfig::HomeMethod::Simple;
  build(simple);
  clear();
  motors[0].displace(9000);
  axis->words().destination = 123;
  pulse(command::kFindHomeDown);
  run_ms(60000);
  EXPECT_EQ(motors[0].position(), 5039);
  EXPECT_EQ(axis->motor_position(), 123);
}

TEST_F(AxisRules, Stp100_5_3_2_MarkerOriginWithLimitQualification) {
  AxisConfig c;
  c.origin_source = AxisConfig::OriginSource::Marker;
  c.limit_qualified_home = true;
  c.encoder = sim::EncoderKind::Quadrature;
  sim::AxisMachineConfig m = default_machine();
  m.home.reset();
  m.encoder = sim::EncoderKind::Quadrature;
  m.steps_per_rev = 2000;
  m.marker_offset = 300;  // markers at ...,-19700,-17700,...
  m.marker_width = 4;
  build(c, m);
  clear();
  axis->words().destination = 0;
  pulse(command::kFindHomeDown);
  run_ms(120000);
  EXPECT_EQ(axis->status() & status::kErrors, 0);
  EXPECT_TRUE(has(status::kPositionValid));
  // The marker nearest the lower limit (-20000) is [-19700, -19697]; the last approach runs
  // in the search direction (down), so it ends on the marker's top step.
  EXPECT_EQ(motors[0].position(), -19697);
}

TEST_F(AxisRules, Spm30_5_4_ToleranceAndStall) {
  AxisConfig c;
  c.encoder = sim::EncoderKind::Quadrature;
  c.encoder_tolerance = 10;
  c.stall_detection = true;
  sim::AxisMachineConfig m = default_machine();
  m.encoder = sim::EncoderKind::Quadrature;  // 2000 steps, 500 lines x4: ratio 1/1
  m.miss_every = 50;
  build(c, m);
  clear();
  set_position(0);
  move_rel(1000);
  run_ms(5000);
  EXPECT_FALSE(has(status::kPositionValid));  // 20 missed steps > tolerance 10
  EXPECT_EQ(axis->status() & status::kMotorStalled, 0);
  m.miss_every = 0;
  m.stall_above = 2000;
  build(c, m);
  clear();
  move_rel(5000);
  run_ms(20000);
  EXPECT_TRUE(has(status::kMotorStalled));
  EXPECT_FALSE(has(status::kMoving));
  EXPECT_LT(axis->motor_position(), 2100);  // stopped soon after the jam
}

TEST_F(AxisRules, MasterLostDeceleratesAndLatchesWatchdog) {
  clear();
  move_rel(20000);
  run_ms(1000);
  ASSERT_FALSE(has(status::kAccelerating));
  axis->master_lost(now);
  EXPECT_TRUE(has(status::kPowerUp));
  EXPECT_TRUE(has(status::kDecelerating));  // a ramp, not a halt
  run_ms(2000);
  EXPECT_FALSE(has(status::kMoving));
  EXPECT_FALSE(has(status::kResumable));
  move_rel(10);
  run_ms(100);
  EXPECT_FALSE(has(status::kMoving));  // nothing moves until cleared
}

TEST_F(AxisRules, Spm30_SelectAxis_SavesRestoresAndAtHomeChangeInvalidates) {
  config_multiplexed = true;
  build({});
  clear();
  set_position(111);
  pulse(command::kSelectAxis2);
  EXPECT_TRUE(has(status::kAxis2Selected));
  EXPECT_FALSE(has(status::kPositionValid));
  set_position(222);
  move_rel(10);
  run_ms(500);
  EXPECT_EQ(motors[1].position(), 10);
  EXPECT_EQ(motors[0].position(), 0);
  pulse(command::kSelectAxis1);
  EXPECT_EQ(axis->motor_position(), 111);
  EXPECT_TRUE(has(status::kPositionValid));
  // Motor 2 moved onto its home cam while deselected: its position is no longer trusted.
  motors[1].displace(5000 - 10);
  pulse(command::kSelectAxis2);
  EXPECT_EQ(axis->motor_position(), 232);
  EXPECT_FALSE(has(status::kPositionValid));
}

TEST_F(AxisRules, SingleMotorIgnoresSelectAxis2And3) {
  clear();
  pulse(command::kSelectAxis2);
  pulse(command::kSelectAxis3);
  EXPECT_FALSE(has(status::kAxis2Selected | status::kAxis3Selected));
  EXPECT_EQ(axis->status() & status::kErrors, 0);
}

}  // namespace
}  // namespace stepnode::motion
