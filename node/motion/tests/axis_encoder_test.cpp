// Encoder feedback (SPM30 chapter 5, 3.3.2; STP100 chapter 6, 4.2.2.2): encoder position from
// the counts and MLT/DIV for each encoder type, position validation against the tolerance,
// and stall detection, in virtual time on the simulated machine's encoder.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <vector>

#include "node/motion/axis.hpp"
#include "node/sim/machine.hpp"

namespace stepnode::motion {
namespace {

constexpr Tick ms(double v) { return static_cast<Tick>(v * kClockHz / 1000.0); }

class AxisEncoder : public ::testing::Test {
 protected:
  // 2000 steps/rev, a 500-line quadrature encoder decoded x4: 2000 counts/rev, MLT/DIV 1/1.
  static sim::AxisMachineConfig machine() {
    sim::AxisMachineConfig m;
    m.steps_per_rev = 2000;
    m.encoder_lines = 500;
    m.encoder = sim::EncoderKind::Quadrature;
    return m;
  }
  static AxisConfig config(int64_t mlt = 1, int64_t div = 1, int64_t tolerance = 0, bool stall = false) {
    AxisConfig c;
    c.encoder = sim::EncoderKind::Quadrature;
    c.encoder_multiplier = mlt;
    c.encoder_divisor = div;
    c.encoder_tolerance = tolerance;
    c.stall_detection = stall;
    return c;
  }
  void build(AxisConfig c = config(), sim::AxisMachineConfig m = machine()) {
    motors.assign(1, sim::AxisMachine(m));
    axis = std::make_unique<Axis>(c, std::vector<MotorPort*>{&motors[0]}, &estop);
    axis->on_event = [this](const AxisEvent& e) { events.push_back(e); };
    now = 0;
    held = 0;
    events.clear();
    axis->write_commands(command::kClearErrors, now);
    axis->write_commands(0, now);
  }
  void SetUp() override { build(); }
  void write(uint16_t bits) { axis->write_commands(bits, now); }
  void issue(uint16_t bits) {
    write(static_cast<uint16_t>(held | bits));
    write(held);
  }
  void hold(uint16_t bits) {
    held = bits;
    write(held);
  }
  void at(Tick t) {
    now = std::max(now, t);
    axis->advance_to(now);
  }
  void wait(double milliseconds) { at(now + ms(milliseconds)); }
  void set_position(int32_t p) {
    axis->words().destination = p;
    issue(command::kSetPosition);
  }
  void move_rel(int32_t d) {
    axis->words().destination = d;
    issue(command::kMoveRelative);
  }
  bool has(uint16_t bits) const { return (axis->status() & bits) == bits; }
  bool any(uint16_t bits) const { return (axis->status() & bits) != 0; }
  uint16_t errors() const { return axis->status() & status::kErrors; }
  int64_t mech() const { return motors[0].position(); }
  // Step by step to standstill; `check` after every step.
  template <class F>
  void walk(F check, double limit = 600000) {
    Tick end = now + ms(limit);
    while (now < end && any(status::kMoving)) {
      auto next = axis->next_step_time();
      at(next ? std::min(*next, end) : std::min(now + ms(0.1), end));
      check();
    }
  }
  void walk() {
    walk([] {});
  }
  // The largest |motor - encoder| over a walk.
  int64_t walk_max_error() {
    int64_t worst = 0;
    walk([&] { worst = std::max<int64_t>(worst, std::llabs(int64_t{axis->motor_position()} - axis->encoder_position())); });
    return worst;
  }

  std::vector<sim::AxisMachine> motors;
  bool estop = false;
  std::unique_ptr<Axis> axis;
  std::vector<AxisEvent> events;
  Tick now = 0;
  uint16_t held = 0;
};

// ---- SPM30 5.2/5.3, STP100 6.3.1: the step-to-feedback ratio -------------------------------

TEST_F(AxisEncoder, Spm30_5_2_QuadratureX4RatioOneTracksEveryStepBothWays) {
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

TEST_F(AxisEncoder, Stp100_6_3_1_Quadrature250Lines200StepsIsAlsoMlt1Div5) {
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
  AxisConfig c = config(1, 1, 5, true);
  c.encoder = sim::EncoderKind::None;
  build(c, m);
  set_position(10);
  move_rel(1400);
  EXPECT_EQ(walk_max_error(), 0);
  EXPECT_EQ(axis->encoder_position(), 1410);
  EXPECT_EQ(mech(), 1200);
  EXPECT_TRUE(has(status::kPositionValid));  // nothing to validate against
  EXPECT_EQ(errors(), 0);                     // %I5 never goes on (5.1)
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
  EXPECT_EQ(errors(), 0);                      // not an error bit
  // Set Current Position re-validates (encoder loaded too).
  set_position(0);
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_EQ(axis->encoder_position(), 0);
}

TEST_F(AxisEncoder, Stp100_6_3_2_MissedStepsInvalidateOnTheStepThatReachesTheToleranceButDoNotStop) {
  sim::AxisMachineConfig m = machine();
  m.miss_every = 50;  // item 4: the motor misses every 50th pulse
  build(config(1, 1, 10), m);
  set_position(0);
  move_rel(1000);
  int32_t invalid_at = -1;
  walk([&] {
    if (invalid_at < 0 && !has(status::kPositionValid)) invalid_at = axis->motor_position();
  });
  EXPECT_EQ(invalid_at, 500);  // the 10th missed pulse is the 500th
  // "An invalid position during a move does not automatically stop the move."
  EXPECT_EQ(axis->motor_position(), 1000);
  EXPECT_EQ(mech(), 980);
  EXPECT_EQ(axis->encoder_position(), 980);
  EXPECT_EQ(errors(), 0);
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

TEST_F(AxisEncoder, Stp100_6_3_3_JammedMotorLatchesMotorStalledAndStopsAtOnce) {
  sim::AxisMachineConfig m = machine();
  m.stall_above = 2000;
  build(config(1, 1, 10, true), m);
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
  for (const auto& e : events) reported = reported || (e.kind == AxisEvent::Error && e.error_bits == status::kMotorStalled);
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
    build(config(1, 1, 10, true), m);
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
  build(config(1, 1, 255, true), m);
  set_position(0);
  move_rel(3000);
  walk();
  EXPECT_EQ(errors(), 0);
  EXPECT_EQ(mech(), 1500);
  EXPECT_FALSE(has(status::kPositionValid));  // 1500 > 255
}

TEST_F(AxisEncoder, Stp100_6_3_3_StallDetectionOffOrNoEncoderNeverLatches) {
  sim::AxisMachineConfig m = machine();
  m.stall_above = 500;
  build(config(1, 1, 10, false), m);
  set_position(0);
  move_rel(2000);
  walk();
  EXPECT_EQ(errors(), 0);
  EXPECT_EQ(axis->motor_position(), 2000);  // the pulses all went out
  EXPECT_EQ(mech(), 500);
  EXPECT_FALSE(has(status::kPositionValid));
  m.encoder = sim::EncoderKind::None;
  AxisConfig c = config(1, 1, 10, true);
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
  build(config(1, 1, 10, true), m);
  axis->words().destination = 0;
  issue(command::kFindHomeUp);
  walk();
  EXPECT_EQ(errors(), status::kMotorStalled);
  EXPECT_FALSE(has(status::kPositionValid));
  EXPECT_EQ(mech(), 3000);
}

TEST_F(AxisEncoder, Stp100_4_2_3_1_FindHomeLoadsTheEncoderPosition) {
  sim::AxisMachineConfig m = machine();
  m.home = sim::Cam{700, 40};
  build(config(1, 1, 5, true), m);
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
