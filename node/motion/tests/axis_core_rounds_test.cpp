// The core's step loop leaves out, within a motion, the looks that only a change of the job
// can make matter (axis_core.cpp: take_due). A rule that changes the job from after_step
// must still be obeyed from the very next step: a select of another motor whose e-stop is
// active (SPM30 3.3.1: no step goes out once the selected motor's e-stop is), and a next
// motion whose hooks differ. And a rule that asks for steps only at some inputs
// (FrontEnd::Hooks::step_rule_inputs) or at one position (step_rule_position) is called at
// exactly those steps.
#include <gtest/gtest.h>

#include <vector>

#include "node/motion/axis.hpp"
#include "node/motion/axis_core.hpp"
#include "node/sim/machine.hpp"

namespace stepnode::motion {
namespace {

// About `steps_per_s` from the start (a 1 ms ramp to one step/s more; AQ3 600: 1 step/s a level).
RampSpec constant(int64_t steps_per_s) {
  return horner_ramp(600, steps_per_s, steps_per_s + 1, 1, 0);
}

// Selects motor 1 in the rule of its `select_after`-th step.
struct Selector final : FrontEnd {
  AxisCore* core = nullptr;
  int select_after = 0, steps = 0, aborts = 0;
  void after_step(const Step&) override {
    if (++steps == select_after) core->select(1);
  }
  void motion_ended(Tick) override {}
  void aborted(Tick) override { ++aborts; }
};

TEST(AxisCoreRounds, ARuleThatSelectsAMotorWithItsEStopActiveStopsBeforeTheNextStep) {
  sim::AxisMachine m0, m1;
  AxisCore core({&m0, &m1});
  m1.set_emergency_stop(true);  // only the motor not selected yet
  Selector fe;
  fe.core = &core;
  fe.select_after = 5;
  ASSERT_TRUE(core.start(fe, constant(1000), +1, 10, 0));
  core.advance_to(kClockHz);  // 10 steps at 1000/s would be done by then
  EXPECT_EQ(fe.steps, 5);
  EXPECT_EQ(m0.position(), 5);
  EXPECT_EQ(m1.pulses_received(), 0u);
  EXPECT_EQ(fe.aborts, 1);  // the e-stop ended the job: its owner is told
  EXPECT_FALSE(core.busy());
}

// Its first motion has no hooks; the rule of its `restart_after`-th step starts a second
// motion of `second` steps that asks for before_step.
struct Restarter final : FrontEnd {
  AxisCore* core = nullptr;
  int restart_after = 0, second = 0, steps = 0, before = 0;
  bool restarted = false;
  Hooks hooks() const override { return {.before_step = restarted}; }
  void before_step() override { ++before; }
  void after_step(const Step& s) override {
    if (++steps != restart_after) return;
    restarted = true;
    core->start(*this, constant(1000), +1, second, s.time);
  }
  void motion_ended(Tick) override {}
};

TEST(AxisCoreRounds, ANextMotionStartedInARuleHasItsHooksFromItsFirstStep) {
  sim::AxisMachine m;
  AxisCore core({&m});
  Restarter fe;
  fe.core = &core;
  fe.restart_after = 3;
  fe.second = 5;
  ASSERT_TRUE(core.start(fe, constant(1000), +1, std::nullopt, 0));
  core.advance_to(kClockHz);
  EXPECT_EQ(fe.steps, 3 + 5);
  EXPECT_EQ(fe.before, 5);  // every step of the second motion, none of the first
  EXPECT_EQ(m.position(), 8);
  EXPECT_FALSE(core.busy());
}

// A rule that acts only at the upper limit, until it asks for every step.
struct LimitRule final : FrontEnd {
  AxisCore* core = nullptr;
  bool every = false;
  std::vector<int32_t> seen;  // the core's position at each after_step
  Hooks hooks() const override {
    return {.every_step = every, .step_rule_inputs = static_cast<uint8_t>(Input::UpperLimit)};
  }
  void after_step(const Step&) override { seen.push_back(core->position()); }
  void motion_ended(Tick) override {}
};

TEST(AxisCoreRounds, ARuleOfTheLimitsIsCalledOnlyAtTheStepsWithTheLimitActive) {
  sim::AxisMachineConfig c;
  c.upper_limit = 5;  // active at and above 5 (the steps to 5, 6 and 7)
  sim::AxisMachine m(c);
  AxisCore core({&m});
  LimitRule fe;
  fe.core = &core;
  ASSERT_TRUE(core.start(fe, constant(1000), +1, 7, 0));
  core.advance_to(kClockHz);
  EXPECT_EQ(fe.seen, (std::vector<int32_t>{5, 6, 7}));

  // Back down from 7 to 1: active at 6 and 5, released at 4. Half-way the rule asks for
  // every step (hooks_changed): from then on each step is its.
  fe.seen.clear();
  ASSERT_TRUE(core.start(fe, constant(1000), -1, 6, kClockHz));
  core.advance_to(kClockHz + 3 * kClockHz / 1000 + kClockHz / 2000);  // 3 steps: to 4
  fe.every = true;
  core.hooks_changed(fe);
  core.advance_to(2 * kClockHz);
  EXPECT_EQ(fe.seen, (std::vector<int32_t>{6, 5, 3, 2, 1}));
}

// A rule of one position only (FrontEnd::Hooks::step_rule_position), no inputs.
struct PositionRule final : FrontEnd {
  AxisCore* core = nullptr;
  std::vector<int32_t> seen;  // the core's position at each after_step
  Hooks hooks() const override { return {.every_step = false, .step_rule_position = 4}; }
  void after_step(const Step&) override { seen.push_back(core->position()); }
  void motion_ended(Tick) override {}
};

TEST(AxisCoreRounds, ARuleOfAPositionIsCalledAtTheStepsThatReachItOnly) {
  sim::AxisMachine m;
  AxisCore core({&m});
  PositionRule fe;
  fe.core = &core;
  ASSERT_TRUE(core.start(fe, constant(1000), +1, 7, 0));
  core.advance_to(kClockHz);  // all 7 steps in one advance
  EXPECT_EQ(fe.seen, (std::vector<int32_t>{4}));
  ASSERT_TRUE(core.start(fe, constant(1000), -1, 7, kClockHz));  // 7 down to 0: 4 once more
  core.advance_to(2 * kClockHz);
  EXPECT_EQ(fe.seen, (std::vector<int32_t>{4, 4}));
  EXPECT_EQ(core.position(), 0);
}

}  // namespace
}  // namespace stepnode::motion
