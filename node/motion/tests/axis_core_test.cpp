// The motion core's arbitration between front ends (axis_core.hpp, README "HP 44714A
// channels"): one job at a time, any front end stops any job, the e-stop ends every job,
// and every listener sees every step.
#include "node/motion/axis_core.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "node/motion/axis.hpp"
#include "node/sim/machine.hpp"
#include "node/sim/tests/estop_switch.hpp"

namespace stepnode::motion {
namespace {

// A front end that records what the core told it.
struct Recorder final : FrontEnd, AxisListener {
  std::vector<Tick> own_steps, any_steps;
  int ended = 0, aborted_count = 0, started_by_others = 0, estops = 0;
  void after_step(const Step& s) override { own_steps.push_back(s.time); }
  void motion_ended(Tick) override { ++ended; }
  void aborted(Tick) override { ++aborted_count; }
  void step_taken(const Step& s) override { any_steps.push_back(s.time); }
  void job_started(const FrontEnd& owner, Tick) override { started_by_others += &owner != this; }
  void emergency_stop(Tick, bool) override { ++estops; }
};

// About `steps_per_s` from the start (a 1 ms ramp to one step/s more; AQ3 600: 1 step/s a level).
RampSpec constant(int64_t steps_per_s) {
  return horner_ramp(600, steps_per_s, steps_per_s + 1, 1, 0);
}

class AxisCoreTest : public ::testing::Test {
 protected:
  sim::AxisMachine motor;
  sim::EStopSwitch estop{{&motor}};
  AxisCore core{{&motor}};
  Recorder a, b;
  void SetUp() override {
    core.listen(a);
    core.listen(b);
  }
};

TEST_F(AxisCoreTest, OneJobAtATimeAndTheOwnerAloneGetsItsSteps) {
  ASSERT_TRUE(core.start(a, constant(1000), +1, 10, 0));
  EXPECT_TRUE(core.busy());
  EXPECT_FALSE(core.start(b, constant(1000), -1, 10, 0));  // refused while a's job runs
  EXPECT_FALSE(core.claim(b, 0));
  EXPECT_EQ(b.started_by_others, 1);  // b heard that a started
  core.advance_to(kClockHz);
  EXPECT_EQ(core.position(), 10);
  EXPECT_EQ(motor.position(), 10);
  EXPECT_EQ(a.own_steps.size(), 10u);
  EXPECT_TRUE(b.own_steps.empty());
  EXPECT_EQ(a.any_steps, b.any_steps);  // every listener sees every step
  EXPECT_EQ(a.ended, 1);
  EXPECT_FALSE(core.busy());
  ASSERT_TRUE(core.start(b, constant(1000), -1, 4, kClockHz));  // idle again: b may
  core.advance_to(2 * kClockHz);
  EXPECT_EQ(core.position(), 6);
  EXPECT_EQ(b.ended, 1);
}

TEST_F(AxisCoreTest, AnyFrontEndStopsTheJobAndTheOwnerIsToldHow) {
  ASSERT_TRUE(core.start(a, constant(1000), +1, std::nullopt, 0));
  core.advance_to(kClockHz / 100);
  core.stop(kClockHz / 100);  // b decelerates a's job: a sees its motion end
  core.advance_to(kClockHz);
  EXPECT_FALSE(core.moving());
  EXPECT_EQ(a.ended, 1);
  EXPECT_EQ(a.aborted_count, 0);

  ASSERT_TRUE(core.start(a, constant(1000), +1, std::nullopt, kClockHz));
  core.advance_to(kClockHz + kClockHz / 100);
  core.abort(&b, kClockHz + kClockHz / 100);  // b ends a's job at once
  EXPECT_FALSE(core.busy());
  EXPECT_EQ(a.aborted_count, 1);
  EXPECT_EQ(a.ended, 1);  // no motion_ended after an abort
  const int32_t at = core.position();
  core.advance_to(2 * kClockHz);
  EXPECT_EQ(core.position(), at);
}

TEST_F(AxisCoreTest, TheEStopEndsTheJobBeforeItsNextStepAndEveryListenerHears) {
  ASSERT_TRUE(core.start(a, constant(1000), +1, std::nullopt, 0));
  core.advance_to(kClockHz / 100);
  const size_t steps = a.any_steps.size();
  estop = true;
  core.advance_to(kClockHz);
  EXPECT_EQ(a.any_steps.size(), steps);  // no step once the input is active
  EXPECT_EQ(a.aborted_count, 1);
  EXPECT_EQ(a.estops, 1);
  EXPECT_EQ(b.estops, 1);
  EXPECT_FALSE(core.busy());
}

TEST_F(AxisCoreTest, AHaltByTheOwnerEndsItsJobWithoutAMotionEnd) {
  ASSERT_TRUE(core.start(a, constant(1000), +1, std::nullopt, 0));
  core.advance_to(kClockHz / 100);
  core.halt(b, kClockHz / 100);  // not b's job: nothing
  EXPECT_TRUE(core.moving());
  core.halt(a, kClockHz / 100);
  EXPECT_FALSE(core.busy());
  core.advance_to(kClockHz);
  EXPECT_EQ(a.ended, 0);
}

// The Horner front end reports another front end's job in its status bits and obeys its
// own stops on it (SPM30 %Q16 ends whatever moves the motor).
TEST_F(AxisCoreTest, TheHornerRegistersSeeAndStopAnotherFrontEndsJob) {
  Axis horner(AxisConfig{}, core);
  horner.write_commands(command::kClearErrors, 0);
  horner.write_commands(0, 1);
  ASSERT_TRUE(core.start(a, constant(1000), +1, std::nullopt, 2));
  core.advance_to(kClockHz / 100);
  EXPECT_TRUE(horner.status() & status::kMoving);
  horner.words().destination = 100;
  horner.write_commands(command::kMoveRelative, kClockHz / 100);  // refused: moving
  EXPECT_TRUE(core.owned_by(a));
  horner.write_commands(command::kImmediateStop, kClockHz / 50);
  EXPECT_FALSE(core.busy());
  EXPECT_EQ(a.aborted_count, 1);
  EXPECT_FALSE(horner.status() & status::kMoving);
}

TEST_F(AxisCoreTest, HornerImmediateStopEndsAnotherFrontEndsJobWithPowerUpLatched) {
  // A node that drives an axis through another front end (HP, CiA 402) never clears the
  // Horner %I8 of power-up; %Q16 must still stop the motor (SPM30 4: no status required).
  Axis horner(AxisConfig{}, core);
  ASSERT_EQ(horner.status() & status::kErrors, status::kPowerUp);
  ASSERT_TRUE(core.start(a, constant(1000), +1, std::nullopt, 0));
  core.advance_to(kClockHz / 10);
  horner.write_commands(command::kImmediateStop, kClockHz / 10);
  EXPECT_FALSE(core.busy());
  EXPECT_EQ(a.aborted_count, 1);
  const int32_t at = core.position();
  core.advance_to(kClockHz);
  EXPECT_EQ(core.position(), at);
}

}  // namespace
}  // namespace stepnode::motion
