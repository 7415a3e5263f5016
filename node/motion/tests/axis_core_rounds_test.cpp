// The core's step loop leaves out, within a motion, the looks that only a change of the job
// can make matter (axis_core.cpp: take_due). A rule that changes the job from after_step
// must still be obeyed from the very next step: a select of another motor whose e-stop is
// active (SPM30 3.3.1: no step goes out once the selected motor's e-stop is), and a next
// motion whose hooks differ.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace stepnode::motion
