// Encoder feedback (SPM30 chapter 5, 3.3.2; STP100 chapter 6, 4.2.2.2): encoder position from
// the counts and MLT/DIV for each encoder type, position validation against the tolerance,
// and stall detection, in virtual time on the simulated machine's encoder.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>

#include "node/motion/tests/axis_harness.hpp"

namespace stepnode::motion {
namespace {

using harness::ms;

class AxisEncoder : public harness::AxisHarness {
 protected:
  // 2000 steps/rev, a 500-line quadrature encoder decoded x4 (SPM30 5.1 "quadrupled"):
  // 2000 counts/rev, MLT/DIV 1/1.
  static sim::AxisMachineConfig machine() {
    sim::AxisMachineConfig m;
    m.steps_per_rev = 2000;
    m.encoder_lines = 500;
    m.encoder = sim::EncoderKind::Quadrature;
    return m;
  }
  // 50,000 steps/rev and a 1000-line quadrature encoder counted once per line (STP100 Table
  // 6.1: MLT 50, DIV 1), the load unable to move up past `stall_above`.
  static sim::AxisMachineConfig fine_steps(int64_t stall_above) {
    sim::AxisMachineConfig m;
    m.steps_per_rev = 50000;
    m.encoder_lines = 1000;
    m.encoder = sim::EncoderKind::Quadrature;
    m.stall_above = stall_above;
    return m;
  }
  // An SPM30 axis 1 (stall detection follows the tolerance, SPM30 5.4).
  static AxisConfig config(int64_t mlt = 1, int64_t div = 1, int64_t tolerance = 0) {
    AxisConfig c;
    c.encoder = sim::EncoderKind::Quadrature;
    c.quadrature_decoding = 4;
    c.encoder_multiplier = mlt;
    c.encoder_divisor = div;
    c.encoder_tolerance = tolerance;
    return c;
  }
  // An STP100: stall detection is its own checkbox (6.3.3).
  static AxisConfig stp100(int64_t mlt, int64_t div, int64_t tolerance, bool stall) {
    AxisConfig c = config(mlt, div, tolerance);
    c.module = AxisConfig::Module::Stp100;
    c.stall_detection = stall;
    return c;
  }
  // The axis with its errors cleared, ready for a command.
  void build(AxisConfig c = config(), sim::AxisMachineConfig m = machine()) {
    AxisHarness::build(c, m);
    clear();
  }
  void SetUp() override { build(); }
  using AxisHarness::walk;
  void walk() {
    walk([] {});
  }
  // The largest |motor - encoder| over a walk.
  int64_t walk_max_error() {
    int64_t worst = 0;
    walk([&] {
      worst = std::max<int64_t>(
          worst, std::llabs(int64_t{axis->motor_position()} - axis->encoder_position()));
    });
    return worst;
  }
};

// ---- SPM30 5.2/5.3, STP100 6.3.1: the step-to-feedback ratio -------------------------------

TEST_F(AxisEncoder, Spm30_5_1_QuadratureDecodedX4RatioOneTracksEveryStepBothWays) {
  set_position(0);
  move_rel(2345);
  EXPECT_EQ(walk_max_error(), 0);
  EXPECT_EQ(axis->encoder_position(), 2345);
  move_rel(-7000);  // through zero into negative positions
  EXPECT_EQ(walk_max_error(), 0);
  EXPECT_EQ(axis->encoder_position(), -4655);
  EXPECT_EQ(axis->motor_position(), -4655);
  EXPECT_EQ(mech(), -4655);
}

TEST_F(AxisEncoder, Spm30_5_3_UpDownEncoder1000Lines200StepsIsMlt1Div5) {
  sim::AxisMachineConfig m = machine();
  m.steps_per_rev = 200;
  m.encoder_lines = 1000;
  m.encoder = sim::EncoderKind::UpDown;  // one count per line: 1000 counts/rev
  AxisConfig c = config(1, 5);
  c.encoder = sim::EncoderKind::UpDown;
  build(c, m);
  set_position(100);
  move_rel(-1234);
  EXPECT_EQ(walk_max_error(), 0);
  EXPECT_EQ(axis->encoder_position(), -1134);
  move_rel(3000);
  EXPECT_EQ(walk_max_error(), 0);
  EXPECT_EQ(axis->encoder_position(), 1866);
}

TEST_F(AxisEncoder, Stp100_6_2_1_Quadrature250LinesDecodedX4On200StepsIsAlsoMlt1Div5) {
  sim::AxisMachineConfig m = machine();
  m.steps_per_rev = 200;
  m.encoder_lines = 250;  // x4: 1000 counts/rev
  build(config(1, 5), m);
  set_position(0);
  move_rel(-777);
  EXPECT_EQ(walk_max_error(), 0);
  EXPECT_EQ(axis->encoder_position(), -777);
}

TEST_F(AxisEncoder, Spm30_5_4_CoarseEncoderTracksWithinItsResolution) {
  // 12,800 steps/rev against 1000 U/D lines: MLT 64 / DIV 5 (SPM30 5.3 table); one count is
  // 12.8 steps, so the encoder position lags by under 13.8 steps ("resolution error", 5.4).
  sim::AxisMachineConfig m = machine();
  m.steps_per_rev = 12800;
  m.encoder_lines = 1000;
  m.encoder = sim::EncoderKind::UpDown;
  AxisConfig c = config(64, 5);
  c.encoder = sim::EncoderKind::UpDown;
  build(c, m);
  set_position(0);
  move_rel(5000);
  int64_t worst = walk_max_error();
  EXPECT_LE(worst, 13);
  EXPECT_GE(worst, 12);
  EXPECT_EQ(axis->encoder_position(), 4992);  // 390 whole counts (of 390.625) * 12.8
}

TEST_F(AxisEncoder, Spm30_5_1_NoEncoderReportsAxis1MotorPosition) {
  sim::AxisMachineConfig m = machine();
  m.encoder = sim::EncoderKind::None;
  m.miss_every = 7;  // even when the motor loses steps
  AxisConfig c = config(1, 1, 5);
  c.encoder = sim::EncoderKind::None;
  build(c, m);
  set_position(10);
  move_rel(1400);
  EXPECT_EQ(walk_max_error(), 0);
  EXPECT_EQ(axis->encoder_position(), 1410);
  EXPECT_EQ(mech(), 1200);
  EXPECT_TRUE(has(status::kPositionValid));  // nothing to validate against
  EXPECT_EQ(errors(), 0);                    // %I5 never goes on (5.1)
}

TEST_F(AxisEncoder, Spm30_3_3_2_EncoderPositionZeroAtPowerUpAndLoadedBySetPosition) {
  motors[0].displace(12345);  // wherever the machine is
  axis->power_up(now);
  EXPECT_EQ(axis->encoder_position(), 0);
  EXPECT_EQ(axis->motor_position(), 0);
  write(command::kClearErrors);
  write(0);
  set_position(-400);
  EXPECT_EQ(axis->encoder_position(), -400);  // STP100 5.3.8: into both
  move_rel(1000);
  EXPECT_EQ(walk_max_error(), 0);
  EXPECT_EQ(axis->encoder_position(), 600);
  EXPECT_EQ(mech(), 13345);
}

// SPM30 5.3 and STP100 Table 6.1 (the same 16 rows): a 1000-line quadrature encoder on the
// motor shaft, MLT/DIV for each STEP RESOLUTION. The module counts lines (its default
// decoding): a row copied from the manual tracks the motor to within one count.
struct RatioRow {
  int64_t step_resolution, mlt, div;
};
constexpr RatioRow kRatioTable[] = {
    {200, 1, 5},     {400, 2, 5},     {1000, 1, 1},   {2000, 2, 1},
    {5000, 5, 1},    {10000, 10, 1},  {12800, 64, 5}, {18000, 18, 1},
    {20000, 20, 1},  {21600, 108, 5}, {25000, 25, 1}, {25400, 127, 5},
    {25600, 128, 5}, {36000, 36, 1},  {50000, 50, 1}, {50800, 254, 5},
};

TEST_F(AxisEncoder,
       Spm30_5_3_Stp100_6_3_1_EveryRowOfTheRatioTableTracksA1000LineQuadratureEncoder) {
  for (auto module : {AxisConfig::Module::Spm30, AxisConfig::Module::Stp100}) {
    for (const RatioRow& row : kRatioTable) {
      SCOPED_TRACE(testing::Message()
                   << "step resolution " << row.step_resolution
                   << (module == AxisConfig::Module::Spm30 ? " SPM30" : " STP100"));
      sim::AxisMachineConfig m = machine();
      m.steps_per_rev = row.step_resolution;
      m.encoder_lines = 1000;
      // One count is MLT/DIV steps: the resolution error (5.4 item 2) stays under one count,
      // so a tolerance of one count more keeps %I9 on and no stall is seen.
      int64_t count_steps = (row.mlt + row.div - 1) / row.div;
      AxisConfig c = config(row.mlt, row.div, count_steps + 1);
      c.quadrature_decoding = 1;
      c.module = module;
      c.stall_detection = true;
      build(c, m);
      set_position(0);
      for (int32_t distance : {static_cast<int32_t>(row.step_resolution * 3 / 2 + 7),
                               static_cast<int32_t>(-row.step_resolution * 2 - 3)}) {
        move_rel(distance);
        EXPECT_LE(walk_max_error(), count_steps);
        EXPECT_EQ(errors(), 0);
        EXPECT_TRUE(has(status::kPositionValid));
        int64_t lines = mech() * 1000;
        int64_t counts = lines >= 0 ? lines / row.step_resolution
                                    : -((-lines + row.step_resolution - 1) / row.step_resolution);
        int64_t scaled = counts * row.mlt;
        int64_t expected = scaled >= 0 ? scaled / row.div : -((-scaled + row.div - 1) / row.div);
        EXPECT_EQ(axis->encoder_position(), expected);
      }
      EXPECT_EQ(axis->motor_position(), mech());
    }
  }
}

TEST_F(AxisEncoder, Spm30_5_1_DecodingX2AndX4CountEachLineTwiceAndFourTimes) {
  // "a quadrature encoder's resolution can be effectively doubled or quadrupled": 1000 lines
  // on 1000 steps/rev is MLT/DIV 1/1 counted once, 1/2 doubled and 1/4 quadrupled.
  for (int64_t decoding : {1, 2, 4}) {
    sim::AxisMachineConfig m = machine();
    m.steps_per_rev = 1000;
    m.encoder_lines = 1000;
    AxisConfig c = config(1, decoding, 1);
    c.quadrature_decoding = decoding;
    build(c, m);
    set_position(0);
    move_rel(1234);
    EXPECT_EQ(walk_max_error(), 0) << decoding;
    EXPECT_EQ(axis->encoder_position(), 1234) << decoding;
    EXPECT_TRUE(has(status::kPositionValid)) << decoding;
  }
  // The table's row with the encoder decoded x4 reads four times the motor position: a
  // configuration error, shown as %I9 off on the first move.
  sim::AxisMachineConfig m = machine();
  m.steps_per_rev = 1000;
  m.encoder_lines = 1000;
  AxisConfig c = config(1, 1, 5);
  c.quadrature_decoding = 4;
  c.encoder_tolerance = 0;
  build(c, m);
  set_position(0);
  move_rel(100);
  walk();
  EXPECT_EQ(axis->encoder_position(), 400);
}

// ---- SPM30 5.4, STP100 6.3.2: the encoder tolerance ----------------------------------------

TEST_F(AxisEncoder, Spm30_5_4_PositionInvalidWhenTheDifferenceReachesTheTolerance) {
  build(config(1, 1, 10));
  set_position(0);
  motors[0].displace(-9);  // an external force while standing still (item 6)
  wait(10);
  EXPECT_TRUE(has(status::kPositionValid));  // 9 < 10
  motors[0].displace(-1);
  wait(10);  // compared continuously (STP100 6.3.2), not only while stepping
  EXPECT_FALSE(has(status::kPositionValid));  // |0 - (-10)| reaches 10
  EXPECT_EQ(errors(), 0);                     // not an error bit
  // Set Current Position re-validates (encoder loaded too).
  set_position(0);
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_EQ(axis->encoder_position(), 0);
}

TEST_F(AxisEncoder, Spm30_5_4_MissedStepsInvalidateOnTheStepThatReachesTheToleranceButDoNotStop) {
  sim::AxisMachineConfig m = machine();
  m.miss_every = 50;  // item 4: the motor misses every 50th pulse
  build(config(1, 1, 10), m);
  set_position(0);
  move_rel(1000);
  int32_t invalid_at = -1;
  walk([&] {
    if (invalid_at < 0 && !has(status::kPositionValid)) invalid_at = axis->motor_position();
  });
  EXPECT_EQ(invalid_at, 500);  // the 10th missed pulse is the 500th: 10 reaches 10
  // "An invalid position during a move does not automatically stop the move."
  EXPECT_EQ(axis->motor_position(), 1000);
  EXPECT_EQ(mech(), 980);
  EXPECT_EQ(axis->encoder_position(), 980);
  EXPECT_EQ(errors(), 0);
}

TEST_F(AxisEncoder, Stp100_6_3_2_PositionInvalidOnlyWhenTheDifferenceExceedsTheTolerance) {
  build(stp100(1, 1, 10, false));
  set_position(0);
  motors[0].displace(-10);
  wait(10);
  EXPECT_TRUE(has(status::kPositionValid));  // 10 does not exceed 10
  motors[0].displace(-1);
  wait(10);
  EXPECT_FALSE(has(status::kPositionValid));  // 11 does
}

TEST_F(AxisEncoder, Spm30_5_4_ZeroToleranceDisablesValidation) {
  sim::AxisMachineConfig m = machine();
  m.miss_every = 3;
  build(config(1, 1, 0), m);
  set_position(0);
  move_rel(900);
  walk();
  motors[0].displace(-500);
  wait(10);
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_EQ(axis->encoder_position(), 100);
}

TEST_F(AxisEncoder, Spm30_5_4_BacklashStyleOffsetBelowToleranceKeepsTheMoveValid) {
  sim::AxisMachineConfig m = machine();
  m.steps_per_rev = 2000;
  m.encoder_lines = 250;  // 1000 counts: 2 steps per count, MLT 2 / DIV 1
  build(config(2, 1, 2), m);
  set_position(0);
  move_rel(1501);
  bool always_valid = true;
  walk([&] { always_valid = always_valid && has(status::kPositionValid); });
  EXPECT_TRUE(always_valid);  // a 1-step resolution error stays under the tolerance of 2
  EXPECT_EQ(axis->encoder_position(), 1500);
}

// ---- SPM30 5.4, STP100 6.3.3: stall detection ------------------------------------------------

TEST_F(AxisEncoder, Spm30_5_4_ANonZeroToleranceDetectsAJammedLoadWithNoOtherSetting) {
  // "when ENCODER TOL is non-zero, the SPM30 uses the encoder feedback pulses to verify motor
  // velocity during motion": a 2000-step move with the load stuck at 200 does not complete.
  sim::AxisMachineConfig m = machine();
  m.stall_above = 200;
  build(config(1, 1, 10), m);
  set_position(0);
  move_rel(2000);
  walk();
  EXPECT_EQ(errors(), status::kMotorStalled);
  EXPECT_FALSE(any(status::kMoving | status::kDecelerating));
  EXPECT_EQ(mech(), 200);
  EXPECT_LE(axis->motor_position(), 200 + 40);  // within two windows of 20 counts
}

TEST_F(AxisEncoder, Spm30_5_4_ZeroToleranceNeverDetectsAStallWhateverTheStp100Checkbox) {
  // "If encoder tolerance is zero ... the MOTOR STALLED ERROR will never go ON."
  sim::AxisMachineConfig m = machine();
  m.stall_above = 200;
  AxisConfig c = config(1, 1, 0);
  c.stall_detection = true;  // the STP100's setting: not the SPM30's rule
  build(c, m);
  set_position(0);
  move_rel(2000);
  walk();
  EXPECT_EQ(errors(), 0);
  EXPECT_EQ(axis->motor_position(), 2000);
  EXPECT_EQ(mech(), 200);
}

TEST_F(AxisEncoder, Stp100_6_3_3_StallDetectionIsTheCheckboxNotTheTolerance) {
  sim::AxisMachineConfig m = machine();
  m.stall_above = 200;
  build(stp100(1, 1, 0, true), m);
  set_position(0);
  move_rel(2000);
  walk();
  EXPECT_EQ(errors(), status::kMotorStalled);
  EXPECT_EQ(mech(), 200);
}

TEST_F(AxisEncoder, Stp100_6_3_3_TheThresholdIsTenPercentOfTheTheoreticalVelocity) {
  // A slipping motor that follows one step in n: 11.1 % and exactly 10 % are not a stall
  // ("less than 10 %"), 9.1 % is, whatever the encoder's rounding.
  for (uint32_t n : {9u, 10u, 11u}) {
    for (int64_t mlt_div : {1, 4}) {  // 1 count per step, and 4 steps per count (500 lines x1)
      sim::AxisMachineConfig m = machine();
      m.move_every = n;
      AxisConfig c = stp100(mlt_div, 1, 0, true);
      c.quadrature_decoding = mlt_div == 1 ? 4 : 1;
      build(c, m);
      set_position(0);
      move_rel(60000);
      walk();
      SCOPED_TRACE(testing::Message()
                   << "1 step in " << n << ", " << mlt_div << " steps per count");
      if (n == 11) {
        EXPECT_EQ(errors(), status::kMotorStalled);
        EXPECT_LE(axis->motor_position(), 2 * 1000 * mlt_div);  // within two long windows
      } else {
        EXPECT_EQ(errors(), 0);
        EXPECT_EQ(axis->motor_position(), 60000);
        EXPECT_EQ(mech(), 60000 / n);
      }
    }
  }
}

TEST_F(AxisEncoder, Stp100_6_3_3_JammedMotorLatchesMotorStalledAndStopsAtOnce) {
  sim::AxisMachineConfig m = machine();
  m.stall_above = 2000;
  build(stp100(1, 1, 10, true), m);
  set_position(0);
  move_rel(5000);
  walk();
  EXPECT_EQ(errors(), status::kMotorStalled);
  EXPECT_FALSE(any(status::kMoving | status::kDecelerating));  // stopped at once, no ramp
  EXPECT_FALSE(has(status::kPositionValid));                   // SPM30 3.3.1
  EXPECT_FALSE(has(status::kResumable));
  EXPECT_EQ(mech(), 2000);
  EXPECT_GT(axis->motor_position(), 2000);
  EXPECT_LE(axis->motor_position(), 2000 + 64);  // within two detection windows
  bool reported = false;
  for (const auto& e : events)
    reported = reported || (e.kind == AxisEvent::Error && e.error_bits == status::kMotorStalled);
  EXPECT_TRUE(reported);
  uint64_t pulses = motors[0].pulses_received();
  wait(5000);
  EXPECT_EQ(motors[0].pulses_received(), pulses);
  // Only Clear Errors is obeyed; then moving away works.
  move_rel(-100);
  EXPECT_FALSE(any(status::kMoving));
  issue(command::kClearErrors);
  move_rel(-100);
  walk();
  EXPECT_EQ(mech(), 1900);
}

TEST_F(AxisEncoder, Stp100_6_3_3_StallDetectedAtAnyCommandedVelocity) {
  // SPM30 5.4: "regardless of how fast the motor is supposed to be moving".
  for (uint16_t running : {2, 8191}) {
    sim::AxisMachineConfig m = machine();
    m.stall_below = -300;
    build(stp100(1, 1, 10, true), m);
    CommandWords& w = axis->words();
    w.velocity_divisor = running == 2 ? 600 : 20;  // 1..2 steps/s, or up to 245,730 steps/s
    w.base_velocity = 1;
    w.running_velocity = running;
    w.acceleration_ms = running == 2 ? 3 : 100;
    hold(command::kJogDown);
    walk();
    EXPECT_EQ(errors(), status::kMotorStalled) << running;
    EXPECT_EQ(mech(), -300) << running;
    EXPECT_GE(axis->motor_position(), -300 - 64) << running;
    hold(0);
  }
}

TEST_F(AxisEncoder, Stp100_6_3_3_SlowerButMovingIsNotAStall) {
  sim::AxisMachineConfig m = machine();
  m.miss_every = 2;  // half the steps lost: 50% of the commanded velocity
  build(stp100(1, 1, 255, true), m);
  set_position(0);
  move_rel(3000);
  walk();
  EXPECT_EQ(errors(), 0);
  EXPECT_EQ(mech(), 1500);
  EXPECT_FALSE(has(status::kPositionValid));  // 1500 > 255
}

// ---- A move shorter than a stall window: judged at its end ----------------------------------

// STP100 3.2.3: "the STP100 verifies that encoder feedback pulses are being received after a
// move is requested. If encoder pulses are not received, the STP100 assumes that the motor is
// not turning, and sets the Motor Stalled error bit". A 900-step move at MLT 50 / DIV 1
// (Table 6.1: 50,000 steps, 1000 lines) should give 18 lines, less than a 20-count window;
// the load is jammed and none come: %I5 at the move's end.
TEST_F(AxisEncoder, Stp100_3_2_3_JammedMoveShorterThanAWindowIsAStallAtItsEnd) {
  AxisConfig c = stp100(50, 1, 0, true);
  c.quadrature_decoding = 1;
  build(c, fine_steps(/*stall_above=*/0));
  set_position(0);
  move_rel(900);
  walk();
  EXPECT_EQ(mech(), 0);
  EXPECT_EQ(axis->encoder_position(), 0);
  EXPECT_EQ(axis->motor_position(), 900);  // the move ran out: nothing left to stop
  EXPECT_EQ(errors(), status::kMotorStalled);
  EXPECT_FALSE(any(status::kMoving));
}

// The same at one count per step: a jammed 15-step move (15 counts expected, none came).
TEST_F(AxisEncoder, Stp100_3_2_3_JammedFifteenStepMoveIsAStall) {
  sim::AxisMachineConfig m = machine();
  m.stall_above = 0;
  build(stp100(1, 1, 0, true), m);
  set_position(0);
  move_rel(15);
  walk();
  EXPECT_EQ(mech(), 0);
  EXPECT_EQ(errors(), status::kMotorStalled);
}

// SPM30 5.4: "when ENCODER TOL is non-zero ... the SPM30 uses the encoder feedback pulses to
// verify motor velocity during motion": the jammed 900-step move at MLT 50 / DIV 1 (5.3).
TEST_F(AxisEncoder, Spm30_5_4_JammedMoveShorterThanAWindowIsAStallAtItsEnd) {
  AxisConfig c = config(50, 1, 255);
  c.quadrature_decoding = 1;
  build(c, fine_steps(/*stall_above=*/0));
  set_position(0);
  move_rel(900);
  walk();
  EXPECT_EQ(mech(), 0);
  EXPECT_FALSE(has(status::kPositionValid));  // |900 - 0| reached 255
  EXPECT_EQ(errors(), status::kMotorStalled);
}

// STP100 6.3.3 "less than 10% of the theoretical move velocity" over a move shorter than the
// long window: one step in 15 (6.7 %) over 900 steps at one count per step is a stall; one
// in 10 (10 %) is not.
TEST_F(AxisEncoder, Stp100_6_3_3_ShortMoveIsJudgedByTheTenPercentRuleAtItsEnd) {
  for (uint32_t n : {15u, 10u}) {
    sim::AxisMachineConfig m = machine();
    m.move_every = n;
    build(stp100(1, 1, 0, true), m);
    set_position(0);
    move_rel(900);
    walk();
    SCOPED_TRACE(testing::Message() << "1 step in " << n);
    EXPECT_EQ(mech(), 900 / n);
    EXPECT_EQ(axis->motor_position(), 900);
    EXPECT_EQ(errors(), n == 15 ? status::kMotorStalled : 0);
  }
}

// A jammed jog shorter than a window: judged when the jog has ramped down and stopped.
TEST_F(AxisEncoder, Stp100_3_2_3_JammedShortJogIsAStallWhenItStops) {
  AxisConfig c = stp100(50, 1, 0, true);
  c.quadrature_decoding = 1;
  build(c, fine_steps(/*stall_above=*/0));
  hold(command::kJogUp);
  wait(500);
  ASSERT_EQ(errors(), 0);  // under 1000 steps: no full window yet
  hold(0);
  walk();
  EXPECT_GT(axis->motor_position(), 10);
  EXPECT_LT(axis->motor_position(), 1000);
  EXPECT_EQ(mech(), 0);
  EXPECT_EQ(errors(), status::kMotorStalled);
}

// Under 10 expected counts, 10 % is less than the one count an encoder reading can be short:
// a jammed 10-step move at one count per step is too short to judge.
TEST_F(AxisEncoder, Stp100_6_3_3_MoveTooShortToJudgeIsNeverAStall) {
  sim::AxisMachineConfig m = machine();
  m.stall_above = 0;
  build(stp100(1, 1, 0, true), m);
  set_position(0);
  move_rel(10);
  walk();
  EXPECT_EQ(mech(), 0);
  EXPECT_EQ(errors(), 0);
  EXPECT_EQ(axis->motor_position(), 10);
}

TEST_F(AxisEncoder, Stp100_6_3_3_StallDetectionOffOrNoEncoderNeverLatches) {
  sim::AxisMachineConfig m = machine();
  m.stall_above = 500;
  build(stp100(1, 1, 10, false), m);
  set_position(0);
  move_rel(2000);
  walk();
  EXPECT_EQ(errors(), 0);
  EXPECT_EQ(axis->motor_position(), 2000);  // the pulses all went out
  EXPECT_EQ(mech(), 500);
  EXPECT_FALSE(has(status::kPositionValid));
  m.encoder = sim::EncoderKind::None;
  AxisConfig c = stp100(1, 1, 10, true);
  c.encoder = sim::EncoderKind::None;
  build(c, m);
  move_rel(2000);
  walk();
  EXPECT_EQ(errors(), 0);  // SPM30 5.1
  EXPECT_EQ(mech(), 500);
}

TEST_F(AxisEncoder, Stp100_6_3_3_StallDuringFindHomeEndsIt) {
  sim::AxisMachineConfig m = machine();
  m.home = sim::Cam{5000, 40};
  m.stall_above = 3000;
  build(stp100(1, 1, 10, true), m);
  axis->words().destination = 0;
  issue(command::kFindHomeUp);
  walk();
  EXPECT_EQ(errors(), status::kMotorStalled);
  EXPECT_FALSE(has(status::kPositionValid));
  EXPECT_EQ(mech(), 3000);
}

// A FIND HOME run shorter than the long window is judged when it stops: the search reaches
// the cam 60 steps up at one step in 15 (6.7 %), after 900 commanded steps.
TEST_F(AxisEncoder, Stp100_6_3_3_SlippingFindHomeSearchIsAStallWhenItStopsOnTheCam) {
  sim::AxisMachineConfig m = machine();
  m.home = sim::Cam{60, 40};
  m.move_every = 15;
  build(stp100(1, 1, 0, true), m);
  axis->words().destination = 0;
  issue(command::kFindHomeUp);
  walk();
  EXPECT_EQ(mech(), 60);
  EXPECT_EQ(axis->motor_position(), 900);
  EXPECT_EQ(errors(), status::kMotorStalled);
  EXPECT_FALSE(has(status::kPositionValid));
}

TEST_F(AxisEncoder, Stp100_4_2_3_1_FindHomeLoadsTheEncoderPosition) {
  sim::AxisMachineConfig m = machine();
  m.home = sim::Cam{700, 40};
  build(stp100(1, 1, 5, true), m);
  axis->words().destination = 10'000;
  issue(command::kFindHomeUp);
  walk();
  EXPECT_EQ(errors(), 0);
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_EQ(mech(), 700);
  EXPECT_EQ(axis->motor_position(), 10'000);
  EXPECT_EQ(axis->encoder_position(), 10'000);
  move_rel(-1700);
  EXPECT_EQ(walk_max_error(), 0);
  EXPECT_EQ(axis->encoder_position(), 8300);
}

}  // namespace
}  // namespace stepnode::motion
