// The motion core with a step port that is given steps ahead of their time (a horizon):
// the steps wait in the port, the ones after a change of course are taken back, and the
// motor receives exactly what it receives without a horizon.
#include <gtest/gtest.h>

#include <vector>

#include "node/motion/axis_core.hpp"
#include "node/sim/machine.hpp"

namespace stepnode::motion {
namespace {

struct Owner final : FrontEnd {
  AxisCore* core = nullptr;
  std::optional<int32_t> halt_at;  // halt the job once the position reaches this
  void after_step(const Step& s) override {
    if (halt_at && core->position() == *halt_at) core->halt(*this, s.time);
  }
  void motion_ended(Tick) override {}
};

// 1000 steps/s after a 1 ms ramp (AQ3 600: 1 step/s a level).
RampSpec constant(int64_t steps_per_s) {
  return horner_ramp(600, steps_per_s, steps_per_s + 1, 1, 0);
}

// Runs a 1 s job in 1 ms advances (a stop at 0.3 s, or the owner's halt) and returns the
// train the motor received.
std::vector<sim::TracedStep> run(Tick horizon, bool stop, std::optional<int32_t> halt_at,
                                 size_t* queued_mid = nullptr) {
  sim::AxisMachine motor;
  motor.set_horizon(horizon);
  std::vector<sim::TracedStep> train;
  motor.trace_into(&train);
  AxisCore core({&motor});
  Owner owner;
  owner.core = &core;
  owner.halt_at = halt_at;
  EXPECT_TRUE(core.start(owner, constant(1000), +1, std::nullopt, 0));
  for (int ms = 0; ms <= 1000; ++ms) {
    const Tick t = kClockHz * ms / 1000;
    core.advance_to(t);
    if (stop && ms == 300) core.stop(t);
    if (queued_mid && ms == 100) *queued_mid = motor.queued();
  }
  return train;
}

TEST(AxisCoreHorizon, StepsWaitInThePortAndGoOutAtTheirTime) {
  size_t queued = 0;
  const auto ahead = run(kClockHz / 10, false, std::nullopt, &queued);  // 100 ms
  EXPECT_GE(queued, 99u);  // about 100 ms of 1000 steps/s wait in the port
  EXPECT_LE(queued, 101u);
  EXPECT_EQ(ahead, run(0, false, std::nullopt));
}

TEST(AxisCoreHorizon, AStopTakesTheQueuedStepsBackAndRampsDownTheSame) {
  const auto at_once = run(0, true, std::nullopt);
  ASSERT_GT(at_once.size(), 250u);
  ASSERT_LT(at_once.size(), 400u);
  EXPECT_EQ(run(kClockHz / 10, true, std::nullopt), at_once);
  EXPECT_EQ(run(kClockHz, true, std::nullopt), at_once);  // a horizon past the stop
}

TEST(AxisCoreHorizon, AHaltFromAStepsRuleEndsOnThatStep) {
  const auto ahead = run(kClockHz / 5, false, 120);
  ASSERT_EQ(ahead.size(), 120u);  // not one step of the 200 ms queued beyond
  EXPECT_EQ(ahead, run(0, false, 120));
}

TEST(AxisCoreHorizon, TheEStopTakesBackEveryQueuedStep) {
  sim::AxisMachine motor;
  motor.set_horizon(kClockHz / 10);
  AxisCore core({&motor});
  Owner owner;
  ASSERT_TRUE(core.start(owner, constant(1000), +1, std::nullopt, 0));
  core.advance_to(kClockHz / 20);  // 50 ms: about 50 steps out, 100 more queued
  const int64_t out = motor.position();
  EXPECT_GT(motor.queued(), 90u);
  motor.set_emergency_stop(true);
  core.advance_to(kClockHz / 20 + 10);
  EXPECT_EQ(motor.queued(), 0u);
  core.advance_to(kClockHz);
  EXPECT_EQ(motor.position(), out);
  EXPECT_FALSE(core.busy());
  // Where the motor was: at 25 ms half of it (the port's history answers).
  EXPECT_EQ(motor.position_at(kClockHz / 20), out);
  const std::optional<int64_t> half = motor.position_at(kClockHz / 40);
  ASSERT_TRUE(half.has_value());
  EXPECT_NEAR(static_cast<double>(*half), static_cast<double>(out) / 2, 2.0);
}

}  // namespace
}  // namespace stepnode::motion
