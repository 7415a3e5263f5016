// FIND HOME UP / FIND HOME DOWN (SPM30 chapter 4, STP100 5.3.2 "Find Origin", STP113 C1.2.1):
// the normal 7-step method with its 50 ms dwell, the simple method, the encoder marker as
// origin, the limit-switch-qualified variant, overshoot, stops and failures, in virtual time.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "node/motion/tests/axis_harness.hpp"

namespace stepnode::motion {
namespace {

using harness::ms;

class AxisHoming : public harness::AxisHarness {
 protected:
  static sim::AxisMachineConfig machine() {
    sim::AxisMachineConfig m;
    m.encoder = sim::EncoderKind::None;
    m.home = sim::Cam{5000, 40};  // active on [5000, 5039]
    m.lower_limit = -20000;
    m.upper_limit = 20000;
    return m;
  }
  // The axis with its errors cleared, ready for a command.
  void build(AxisConfig c = {}, sim::AxisMachineConfig m = machine()) {
    AxisHarness::build(c, m);
    clear();
  }
  void SetUp() override { build(); }
  void home(uint16_t bit, int32_t destination) {
    axis->words().destination = destination;
    issue(bit);
  }

  // Every step until the axis stands still: position, velocity and status after it.
  struct Sample {
    Tick t;
    int64_t mech;
    double velocity;
    uint16_t status;
  };
  std::vector<Sample> walk(double limit = 600000) {
    std::vector<Sample> out;
    Tick end = now + ms(limit);
    while (now < end && any(status::kMoving)) {
      auto next = axis->next_step_time();
      at(next ? std::min(*next, end) : std::min(now + ms(0.1), end));
      out.push_back({now, mech(), axis->velocity(), axis->status()});
    }
    return out;
  }
  // Direction reversals (the sample index where the mechanical position turned).
  static std::vector<size_t> turns(const std::vector<Sample>& s, int64_t start) {
    std::vector<size_t> out;
    int dir = 0;
    int64_t previous = start;
    for (size_t i = 0; i < s.size(); ++i) {
      int64_t d = s[i].mech - previous;
      if (d != 0) {
        int now_dir = d > 0 ? 1 : -1;
        if (dir != 0 && now_dir != dir) out.push_back(i);
        dir = now_dir;
      }
      previous = s[i].mech;
    }
    return out;
  }
  void expect_homed(int64_t at_mech, int32_t destination) {
    EXPECT_EQ(errors(), 0);
    EXPECT_FALSE(any(status::kMoving));
    EXPECT_TRUE(has(status::kPositionValid | status::kAtHome));
    EXPECT_EQ(mech(), at_mech);
    EXPECT_EQ(axis->motor_position(), destination);
    EXPECT_EQ(axis->encoder_position(), destination);
  }
};

// Steps 1-7 from below the cam, searching up: fast to the cam, back off at base velocity
// till the input has been inactive for 50 ms, then up again at base to its first step.
TEST_F(AxisHoming, Spm30_4_FindHomeUp_NormalMethodFromBelow) {
  axis->words().destination = 0;
  issue(command::kSetPosition);
  ASSERT_TRUE(has(status::kPositionValid));
  home(command::kFindHomeUp, 250);
  EXPECT_FALSE(has(status::kPositionValid));                  // step 1
  EXPECT_TRUE(has(status::kMoving | status::kAccelerating));  // step 2: a normal move
  EXPECT_TRUE(axis->dir_output_high());
  auto s = walk();
  expect_homed(5000, 250);
  // Step 2 reached the running velocity; step 3 stopped on the cam's first step.
  double fastest = 0;
  size_t on_cam = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    fastest = std::max(fastest, s[i].velocity);
    if (s[i].mech == 5000) {
      on_cam = i;
      break;
    }
  }
  EXPECT_DOUBLE_EQ(fastest, 1000.0);
  auto t = turns(s, 0);
  ASSERT_EQ(t.size(), 2u);  // down (steps 4-5), up again (step 6)
  EXPECT_EQ(t[0], on_cam + 1);
  // Steps 4-6 at the base velocity: one step every 10 ms.
  for (size_t i = on_cam + 1; i < s.size(); ++i) {
    EXPECT_DOUBLE_EQ(s[i].velocity == 0 ? 100.0 : s[i].velocity, 100.0) << i;
    EXPECT_FALSE(s[i].status & (status::kAccelerating | status::kDecelerating)) << i;
  }
  // Step 5: inactive from the step onto 4999, reversed 50 ms later.
  size_t off = on_cam + 1;
  ASSERT_EQ(s[off].mech, 4999);
  int64_t lowest = s[t[1] - 1].mech;
  EXPECT_GE(lowest, 4994);
  EXPECT_LE(lowest, 4995);
  Tick reversed_step = s[t[1]].t;  // first step of step 6, one base period after the reversal
  EXPECT_NEAR(ticks_to_ms(reversed_step - s[off].t), 50.0 + 10.0, 10.0);
  EXPECT_GE(reversed_step - s[off].t, ms(50) + ms(10) - 1);
}

TEST_F(AxisHoming, Spm30_4_FindHomeDown_NormalMethodFromAboveEndsOnTheCamsTopStep) {
  motors[0].displace(9000);
  home(command::kFindHomeDown, -7);
  EXPECT_FALSE(axis->dir_output_high());
  auto s = walk();
  expect_homed(5039, -7);
  EXPECT_EQ(turns(s, 9000).size(), 2u);
  int64_t highest = 0;
  bool reached = false;
  for (const auto& x : s) {
    reached = reached || x.mech == 5039;
    if (reached) highest = std::max(highest, x.mech);
  }
  EXPECT_GE(highest, 5045);  // backed off 50 ms (5 steps) beyond the cam top
  EXPECT_LE(highest, 5046);
}

TEST_F(AxisHoming, Spm30_4_FindHomeUp_FromAboveTheCamFindsNothingAndHitsTheLimit) {
  motors[0].displace(9000);
  home(command::kFindHomeUp, 0);
  walk();
  EXPECT_EQ(errors(), status::kUpperLimit);
  EXPECT_EQ(mech(), 20000);
  EXPECT_FALSE(has(status::kPositionValid));
}

TEST_F(AxisHoming, Spm30_4_FindHome_StartingOnTheCamBacksOffAndComesBack) {
  motors[0].displace(5020);
  at(now);  // the axis learns of the input's edge at its next advance
  ASSERT_TRUE(has(status::kAtHome));
  home(command::kFindHomeUp, 1);
  walk();
  expect_homed(5000, 1);  // approached in the search direction: the cam's first step up
}

// Step 3 "When the axis' home input becomes active, motion is stopped immediately": one
// already active when the search starts satisfies it at once, with no step, so a start on
// the cam's last step in the search direction homes as one step lower does (no run off the
// cam to the end limit), both by steps 4-6 at base velocity.
TEST_F(AxisHoming, Spm30_4_FindHome_StartingOnTheCamsLastStepsHomesWithoutAStepOffIt) {
  for (int64_t start : {5038, 5039}) {
    SCOPED_TRACE(testing::Message() << "from " << start);
    build();
    motors[0].displace(start);
    at(now);
    ASSERT_TRUE(has(status::kAtHome));
    home(command::kFindHomeUp, 0);
    auto s = walk();
    expect_homed(5000, 0);
    ASSERT_FALSE(s.empty());
    int64_t highest = start;
    for (const auto& x : s) highest = std::max(highest, x.mech);
    EXPECT_EQ(highest, start);              // no step of the search (step 2)
    EXPECT_EQ(turns(s, start).size(), 1u);  // down off the cam (4-5), up to it (6)
  }
}

// A fast search that overshoots the cam: the load coasts past it after the stop. Step 4
// ("just in case we shot right past home") runs back at base velocity to the cam.
TEST_F(AxisHoming, Spm30_4_FindHome_NormalMethodRecoversFromAnOvershoot) {
  sim::AxisMachineConfig m = machine();
  m.home = sim::Cam{5000, 10};
  build({}, m);
  CommandWords& w = axis->words();
  w.velocity_divisor = 60;    // 10 steps/s per unit
  w.base_velocity = 20;       // 200 steps/s
  w.running_velocity = 2000;  // 20,000 steps/s
  w.acceleration_ms = 200;
  home(command::kFindHomeUp, 42);
  while (mech() < 5000) {
    auto next = axis->next_step_time();
    ASSERT_TRUE(next.has_value());
    at(*next);
  }
  ASSERT_EQ(mech(), 5000);  // stopped on the first step onto the cam...
  motors[0].displace(25);   // ...and the load coasts on, past it
  walk();
  expect_homed(5000, 42);
}

TEST_F(AxisHoming, Stp100_5_3_2_SimpleMethodStopsOnTheFirstOriginStep) {
  AxisConfig c;
  c.home_method = AxisConfig::HomeMethod::Simple;
  build(c);
  home(command::kFindHomeUp, 3);
  auto s = walk();
  expect_homed(5000, 3);
  EXPECT_TRUE(turns(s, 0).empty());  // steps 4-7 skipped
  double fastest = 0;
  for (const auto& x : s) fastest = std::max(fastest, x.velocity);
  EXPECT_DOUBLE_EQ(fastest, 1000.0);
  build(c);
  motors[0].displace(9000);
  home(command::kFindHomeDown, 3);
  walk();
  expect_homed(5039, 3);
}

// STP100 5.3.2 step 4 NOTE: the simple method assumes no overshoot; if there is one, the
// position is loaded where the search stopped, off the cam.
TEST_F(AxisHoming, Stp100_5_3_2_SimpleMethodTrustsTheStopEvenWhenItOvershoots) {
  AxisConfig c;
  c.home_method = AxisConfig::HomeMethod::Simple;
  sim::AxisMachineConfig m = machine();
  m.home = sim::Cam{5000, 10};
  build(c, m);
  home(command::kFindHomeUp, 42);
  while (mech() < 5000) {
    auto next = axis->next_step_time();
    ASSERT_TRUE(next.has_value());
    at(*next);
  }
  motors[0].displace(25);
  at(now);
  walk();
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_FALSE(has(status::kAtHome));
  EXPECT_EQ(axis->motor_position(), 42);
  EXPECT_EQ(mech(), 5025);
}

// STP100 3.2.3 / 5.3.2, SPM30 5.1 (QUAD: the marker as the home input).
TEST_F(AxisHoming, Stp100_5_3_2_MarkerAsOriginSourceIgnoresTheHomeSwitch) {
  AxisConfig c;
  c.module = AxisConfig::Module::Stp100;
  c.origin_source = AxisConfig::OriginSource::Marker;
  c.encoder = sim::EncoderKind::Quadrature;
  c.quadrature_decoding = 4;
  sim::AxisMachineConfig m = machine();
  m.encoder = sim::EncoderKind::Quadrature;  // 2000 steps/rev, 500 lines x4: 1 count per step
  m.home = sim::Cam{100, 40};                // not the origin here
  m.marker_offset = 300;
  m.marker_width = 4;  // active on [300, 303] + k*2000
  build(c, m);
  home(command::kFindHomeUp, 1000);
  auto s = walk();
  expect_homed(300, 1000);
  EXPECT_EQ(turns(s, 0).size(), 2u);
  // %I13 follows the origin source: on only while the marker is.
  EXPECT_TRUE(has(status::kAtHome));
  issue(command::kMoveRelative);  // +1000: off the marker
  walk();
  EXPECT_FALSE(has(status::kAtHome));
  EXPECT_EQ(axis->encoder_position(), 2000);
  EXPECT_EQ(axis->motor_position(), 2000);
}

TEST_F(AxisHoming, Stp100_5_3_2_LimitQualifiedStopsAtTheLimitThenFindsTheNearestMarker) {
  AxisConfig c;
  c.origin_source = AxisConfig::OriginSource::Marker;
  c.limit_qualified_home = true;
  c.encoder = sim::EncoderKind::Quadrature;
  sim::AxisMachineConfig m = machine();
  m.encoder = sim::EncoderKind::Quadrature;
  m.home.reset();
  m.upper_limit = 10000;
  m.marker_offset = 300;  // markers [8300, 8303], [6300, 6303], ... below the limit
  m.marker_width = 4;
  build(c, m);
  home(command::kFindHomeUp, -5);
  auto s = walk();
  // Passed markers on the way up (at running velocity) and stopped on the limit, no error.
  int64_t highest = 0;
  for (const auto& x : s) highest = std::max(highest, x.mech);
  EXPECT_EQ(highest, 10000);
  // Then back at base velocity to the nearest marker below it, and the final approach up.
  expect_homed(8300, -5);
  EXPECT_EQ(turns(s, 0).size(), 2u);  // down from the limit (steps 4-5), up again (step 6)
}

// SPM30 4 FIND HOME: "If the current axis is axis 1, and the ENCODER configuration parameter
// is set to QUAD ... (3) When the axis' End Limit input for the current direction becomes
// active, motion is stopped immediately" and the marker is the home input (5.1), with no
// other setting.
TEST_F(AxisHoming, Spm30_4_FindHome_QuadStopsOnTheEndLimitThenHomesOnTheNearestMarker) {
  AxisConfig c;
  c.encoder = sim::EncoderKind::Quadrature;  // nothing else: no origin or qualification flag
  sim::AxisMachineConfig m = machine();
  m.encoder = sim::EncoderKind::Quadrature;
  m.home = sim::Cam{5000, 40};  // the home switch is not the home input with QUAD
  m.upper_limit = 10000;
  m.marker_offset = 300;  // markers [8300, 8303], [6300, 6303], ... below the limit
  m.marker_width = 4;
  build(c, m);
  home(command::kFindHomeUp, -5);
  auto s = walk();
  int64_t highest = 0;
  for (const auto& x : s) highest = std::max(highest, x.mech);
  EXPECT_EQ(highest, 10000);  // past the home switch and every marker, to the limit
  expect_homed(8300, -5);     // the marker closest to the limit switch
  EXPECT_EQ(turns(s, 0).size(), 2u);
}

TEST_F(AxisHoming, Stp100_3_2_3_QuadWithoutTheOptionsHomesOnTheHomeSwitch) {
  // The STP100 makes the marker and the limit qualification options of their own.
  AxisConfig c;
  c.module = AxisConfig::Module::Stp100;
  c.encoder = sim::EncoderKind::Quadrature;
  sim::AxisMachineConfig m = machine();
  m.encoder = sim::EncoderKind::Quadrature;
  m.marker_offset = 300;
  build(c, m);
  home(command::kFindHomeUp, 0);
  walk();
  expect_homed(5000, 0);
}

TEST_F(AxisHoming, Stp100_5_3_2_LimitQualifiedWithTheHomeSwitchAsOrigin) {
  AxisConfig c;
  c.limit_qualified_home = true;
  sim::AxisMachineConfig m = machine();
  m.home = sim::Cam{-15000, 40};  // [-15000, -14961]
  build(c, m);
  motors[0].displace(-10000);
  home(command::kFindHomeDown, 0);
  auto s = walk();
  int64_t lowest = 0;
  for (const auto& x : s) lowest = std::min(lowest, x.mech);
  EXPECT_EQ(lowest, -20000);  // passed the cam, stopped by the limit
  expect_homed(-14961, 0);    // final approach down: the cam's top step
}

TEST_F(AxisHoming, Stp100_5_3_2_LimitQualifiedStartingOnTheLimitTakesNoStepIntoIt) {
  AxisConfig c;
  c.origin_source = AxisConfig::OriginSource::Marker;
  c.limit_qualified_home = true;
  c.encoder = sim::EncoderKind::Quadrature;
  sim::AxisMachineConfig m = machine();
  m.encoder = sim::EncoderKind::Quadrature;
  m.home.reset();
  m.marker_offset = 1000;  // markers at [-19000, -18997], ...
  build(c, m);
  motors[0].displace(-20000);  // on the lower limit
  home(command::kFindHomeDown, 0);
  auto s = walk();
  int64_t lowest = -20000;
  for (const auto& x : s) lowest = std::min(lowest, x.mech);
  EXPECT_EQ(lowest, -20000);
  expect_homed(-18997, 0);
}

TEST_F(AxisHoming, Stp100_5_3_2_LimitQualifiedWithoutAMarkerEndsOnTheOtherLimit) {
  AxisConfig c;
  c.origin_source = AxisConfig::OriginSource::Marker;
  c.limit_qualified_home = true;
  c.encoder = sim::EncoderKind::QuadratureNoMarker;
  sim::AxisMachineConfig m = machine();
  m.encoder = sim::EncoderKind::QuadratureNoMarker;  // SPM30 5.1 QUAD N/M: no marker at all
  m.home.reset();
  m.lower_limit = -2000;
  m.upper_limit = 2000;
  build(c, m);
  home(command::kFindHomeDown, 0);
  walk();
  EXPECT_EQ(errors(), status::kUpperLimit);  // back up at base velocity, never found
  EXPECT_EQ(mech(), 2000);
  EXPECT_FALSE(has(status::kPositionValid));
}

TEST_F(AxisHoming, Spm30_4_FindHome_DecelerateAndStopEndsTheSearch) {
  home(command::kFindHomeUp, 0);
  while (mech() < 4800) wait(0.5);
  issue(command::kDecelStop);  // ramps down past the cam (about 275 steps)
  EXPECT_TRUE(has(status::kDecelerating));
  walk();
  EXPECT_FALSE(any(status::kMoving));
  EXPECT_FALSE(has(status::kPositionValid));
  EXPECT_FALSE(has(status::kResumable));
  EXPECT_GT(mech(), 5040);
  EXPECT_EQ(errors(), 0);
  wait(2000);
  EXPECT_GT(mech(), 5040);  // and nothing more
}

TEST_F(AxisHoming, Spm30_4_FindHome_DecelerateAndStopDuringTheDwell) {
  home(command::kFindHomeUp, 0);
  while (mech() != 5000) wait(0.1);
  while (mech() != 4997) {
    auto next = axis->next_step_time();
    ASSERT_TRUE(next.has_value());
    at(*next);
  }
  issue(command::kDecelStop);  // at base velocity in step 5: stops at once
  wait(5000);
  EXPECT_FALSE(any(status::kMoving));
  EXPECT_EQ(mech(), 4997);
  EXPECT_FALSE(has(status::kPositionValid));
}

TEST_F(AxisHoming, Spm30_4_FindHome_ImmediateStopHalts) {
  home(command::kFindHomeUp, 0);
  wait(1000);
  issue(command::kImmediateStop);
  int64_t where = mech();
  wait(60000);
  EXPECT_EQ(mech(), where);
  EXPECT_FALSE(has(status::kPositionValid));
}

TEST_F(AxisHoming, Spm30_3_4_FindHome_IgnoresOtherCommandsAndNeedsAValidDestination) {
  home(command::kFindHomeUp, 8'388'608);  // not loadable into MOTOR POSITION (3.3)
  EXPECT_EQ(errors(), status::kIllegalMove);
  EXPECT_FALSE(any(status::kMoving));
  write(command::kClearErrors);
  write(0);
  home(command::kFindHomeUp, 77);
  wait(500);
  issue(command::kFindHomeDown);  // ignored while moving (SPM30 3.2)
  issue(command::kJogDown);
  walk();
  expect_homed(5000, 77);
}

}  // namespace
}  // namespace stepnode::motion
