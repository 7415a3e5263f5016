// The direction output setup time of the Horner modules' specifications (SPM30 "Module
// specifications": Direction Output Setup Time 2 ms min; STP100 1.x specifications: 2 ms),
// in virtual time: the first step after DIR changed comes at least 2 ms after the change.
// With a base velocity of 1000 steps/s the first step of a move would come 1 ms after its
// start, so only a change of direction moves it; a move in the same direction is not slowed.
#include <cstdlib>

#include "node/motion/tests/axis_harness.hpp"

namespace stepnode::motion {
namespace {

using harness::ms;

constexpr Tick kSetup = 9831;  // 2 ms of the 4.9152 MHz clock, rounded up

class AxisDirectionSetup : public harness::AxisHarness {
 protected:
  void SetUp() override { fast_base(AxisConfig{}); }
  void fast_base(AxisConfig c) {
    build(c);
    clear();
    CommandWords& w = axis->words();
    w.velocity_divisor = 600;  // AQ4 steps/s
    w.base_velocity = 1000;    // a 1 ms step period from the start
    w.running_velocity = 2000;
    w.acceleration_ms = 100;
  }
  // A relative move of `distance`, run to its end: how long after the command its first step came.
  Tick first_step_of_move(int32_t distance) {
    const Tick from = now;
    move_rel(distance);
    auto steps = walk_steps();
    EXPECT_FALSE(steps.empty());
    return steps.empty() ? -1 : steps.front() - from;
  }
  // The engine's own first step of that move from a standstill, without a setup time.
  Tick engine_first_step(int32_t distance) const {
    const CommandWords& w = axis->words();
    StepGenerator g;
    g.start(horner_ramp(w.velocity_divisor, w.base_velocity, w.running_velocity, w.acceleration_ms,
                        w.deceleration_ms),
            0, distance > 0 ? +1 : -1, std::llabs(distance));
    return *g.peek();
  }
};

TEST_F(AxisDirectionSetup, Spm30_Specifications_FirstStepAfterAReversalWaits2ms) {
  // Power-up leaves DIR low (down): the first move up changes it.
  Tick up = first_step_of_move(500);
  EXPECT_EQ(up, kSetup);
  EXPECT_TRUE(axis->dir_output_high());
  // At once the other way: DIR changes again.
  Tick down = first_step_of_move(-500);
  EXPECT_EQ(down, kSetup);
  EXPECT_EQ(mech(), 0);
}

TEST_F(AxisDirectionSetup, Spm30_Specifications_SameDirectionIsNotDelayed) {
  first_step_of_move(500);
  Tick again = first_step_of_move(500);
  // About one step period at the base velocity (1 ms), as without a setup time.
  EXPECT_EQ(again, engine_first_step(500));
  EXPECT_LT(again, kSetup);
}

TEST_F(AxisDirectionSetup, Spm30_Specifications_ASlowBaseVelocityAlreadyGivesTheSetupTime) {
  axis->words().base_velocity = 100;  // the first step 6 ms after the start (10 ms at base)
  Tick up = first_step_of_move(200);
  EXPECT_EQ(up, engine_first_step(200));  // nothing added
  EXPECT_GT(up, kSetup);
}

TEST_F(AxisDirectionSetup, Stp100_5_3_5_DirTakenLowAtAnIndexedMovesEndCountsAsAChange) {
  // An indexed move up ends with DIR taken low (5.3.5 NOTE): a move down 0.5 ms after its
  // last step keeps the 2 ms from that change.
  CommandWords& w = axis->words();
  w.destination = 400;
  w.index_window_close = 8'388'607;
  issue(command::kMoveIndexed);
  auto steps = walk_steps();
  ASSERT_FALSE(steps.empty());
  ASSERT_FALSE(axis->dir_output_high());
  const Tick ended = steps.back();
  at(ended + ms(0.5));
  Tick down = first_step_of_move(-100);
  EXPECT_EQ(ended + ms(0.5) + down, ended + kSetup);
  EXPECT_EQ(mech(), 300);
}

TEST_F(AxisDirectionSetup, Spm30_Specifications_ZeroSetupTimeKeepsTheEngineTiming) {
  AxisConfig c;
  c.direction_setup_us = 0;  // 0x2n09:14 = 0
  fast_base(c);
  Tick up = first_step_of_move(500);
  EXPECT_EQ(up, engine_first_step(500));
  EXPECT_LT(up, kSetup);
}

TEST_F(AxisDirectionSetup, Spm30_4_FindHome_EachReversalOfTheSearchWaits) {
  sim::AxisMachineConfig m = plain();
  m.home = sim::Cam{300, 100};  // the home switch on [300, 399]
  build({}, m);
  clear();
  CommandWords& w = axis->words();
  w.velocity_divisor = 600;
  w.base_velocity = 1000;
  w.running_velocity = 2000;
  w.acceleration_ms = 100;
  std::vector<std::pair<Tick, int64_t>> trace;
  issue(command::kFindHomeUp);
  int64_t last = mech();
  Tick end = now + ms(60000);
  while (now < end && any(status::kMoving)) {
    auto next = axis->next_step_time();
    at(next ? std::min(*next, end) : std::min(now + ms(0.1), end));
    if (mech() != last) trace.emplace_back(now, mech() - last);
    last = mech();
  }
  ASSERT_TRUE(has(status::kPositionValid));
  // At every reversal, the gap between the last step one way and the first the other way
  // holds the 2 ms setup time.
  int reversals = 0;
  for (size_t i = 1; i < trace.size(); ++i)
    if (trace[i].second != trace[i - 1].second) {
      ++reversals;
      EXPECT_GE(trace[i].first - trace[i - 1].first, kSetup) << "reversal at step " << i;
    }
  EXPECT_GE(reversals, 2);
}

}  // namespace
}  // namespace stepnode::motion
