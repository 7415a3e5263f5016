// HP 44714A rules of issue 11 (items 14-18), each test named after the manual's page: STANDBY
// ON in pulse output (3-29), a frequency outside min/max (3-8, 3-12 NOTE), TRIG SYS / CHAN0
// with a command given without NOWAIT (3-13 note 1, 3-27 NOTE), SUSTAIN without NOWAIT
// (3-12, 3-27) and the pulse rate and width resolutions of appendix A.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "node/motion/hp_self_test.hpp"
#include "node/motion/tests/hp_channel_fixture.hpp"

namespace stepnode::motion::hp {
namespace {

// ---------------------------------------------------------------- STANDBY ON (3-29)

// "When you specify the STANDBY mode ON and the logic sense HI, the STBYn output will be
// high when no pulses are output. When a MOVE or SUSTAIN command is executed and triggered,
// the STBYn output goes low. After all pulses are sent, the STBYn output goes high."
TEST_F(HpChannel, Hp3_29_StandbyOnStbyFollowsTheWidthPulseTrain) {
  ASSERT_EQ(ch->profile(width(1e-3, 10e-3, 5e-3, 20e-3), now), Conflict::None);
  ASSERT_EQ(ch->standby(StandbyMode::On, /*sense_high=*/true, now), Error::None);
  EXPECT_TRUE(ch->stby_output_high());  // no pulses
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  ASSERT_EQ(ch->sustain(2e-3, true, now), Error::None);  // not error 94
  EXPECT_TRUE(ch->stby_output_high());                   // given, not yet triggered
  ASSERT_EQ(ch->trig(TrigMode::Sgl, now), Error::None);
  EXPECT_FALSE(ch->stby_output_high());  // triggered: low
  wait(1000);
  EXPECT_FALSE(ch->stby_output_high());
  EXPECT_TRUE(ch->pulses_reach_powered_motor());
  EXPECT_GE(position(), 49);  // the pulse train went out
  // SUSTAIN 0 (TRIG SGL went back to HOLD): the width ramps to min and the pulses stop;
  // then STBY is high again.
  ASSERT_EQ(ch->trig(TrigMode::Auto, now), Error::None);
  ASSERT_EQ(ch->sustain(0, true, now), Error::None);
  wait(100);
  EXPECT_FALSE(ch->stby_output_high());
  wait(200);
  ASSERT_EQ(done(), 0);
  EXPECT_TRUE(ch->stby_output_high());
  EXPECT_FALSE(ch->pulses_reach_powered_motor());
  // LO sense, ended by HALT SGL: low without pulses, high during them.
  ASSERT_EQ(ch->standby(StandbyMode::On, /*sense_high=*/false, now), Error::None);
  EXPECT_FALSE(ch->stby_output_high());
  ASSERT_EQ(ch->sustain(2e-3, true, now), Error::None);
  EXPECT_TRUE(ch->stby_output_high());
  wait(500);
  ch->halt_sgl(now);
  EXPECT_FALSE(ch->stby_output_high());
  // A stepper motor (PROFILE FREQ) still cannot move while STANDBY ON (error 94, 3-3).
  ASSERT_EQ(ch->profile(freq(100, 800, 200, 25e-6), now), Conflict::None);
  EXPECT_EQ(ch->sustain(100, true, now), Error::CannotMoveWhileStandbyOn);
  EXPECT_EQ(ch->move(10, false, true, now), Error::CannotMoveWhileStandbyOn);
}

TEST_F(HpChannel, Hp3_29_StandbyOnGivenDuringAPulseTrainFollowsIt) {
  ASSERT_EQ(ch->profile(width(1e-3, 10e-3, 5e-3, 20e-3), now), Conflict::None);
  ASSERT_EQ(ch->sustain(2e-3, true, now), Error::None);
  wait(500);
  ASSERT_EQ(ch->standby(StandbyMode::On, true, now), Error::None);
  EXPECT_FALSE(ch->stby_output_high());
  const int64_t p = position();
  wait(1000);
  EXPECT_EQ(position() - p, 50);
  ch->halt_sgl(now);
  EXPECT_TRUE(ch->stby_output_high());
}

// ---------------------------------------------------------------- min/max (3-8, 3-12)

// 3-8 says "A specified frequency not within the min/max window will cause an error"; the
// SUSTAIN pages say what happens instead: "the velocity will not exceed the maximum", "The
// actual frequency generated will be limited by the minimum and maximum" and the NOTE: a
// velocity below min generates pulses at min, above max at max (3-12; widths alike, 3-26).
// The node clamps and accepts the command: no error number.
TEST_F(HpChannel, Hp3_12_Note_AFrequencyOutsideMinMaxIsClampedNotAnError) {
  ASSERT_EQ(ch->profile(freq(100, 800, 200, 25e-6), now), Conflict::None);
  ch->enable_intr();
  ASSERT_EQ(ch->sustain(2000, true, now), Error::None);
  EXPECT_EQ(ch->last_error(), Error::None);
  wait(3600);  // (800 - 100) / 200 = 3.5 s
  EXPECT_EQ(done(), -1);
  EXPECT_NEAR(axis->velocity(), 800, 800 * 1e-4);  // appendix A's 0.01 %
  ASSERT_EQ(interrupts.size(), 1u);
  EXPECT_EQ(interrupts[0].event, intr::kSustainReached);
  EXPECT_NEAR(to_ms(interrupts[0].at), 3500, 5);
  ASSERT_EQ(ch->sustain(10, true, now), Error::None);  // below min: to min
  EXPECT_EQ(ch->last_error(), Error::None);
  wait(3600);
  const int64_t p = position();
  wait(10'000);
  EXPECT_NEAR(position() - p, 1000, 1);  // 100 Hz
  ch->halt_sgl(now);
  // WIDTH: a width above max is max, below min is min.
  std::vector<sim::TracedPulse> train;
  motor->trace_pulses_into(&train);
  ASSERT_EQ(ch->profile(width(1e-3, 10e-3, 5e-3, 20e-3), now), Conflict::None);
  ASSERT_EQ(ch->sustain(50e-3, true, now), Error::None);
  wait(2000);  // (10 - 1) ms / 5 ms/s = 1.8 s
  EXPECT_EQ(motor->last_pulse_width_ns(), 10'000'000u);
  ASSERT_EQ(ch->sustain(0.1e-3, true, now), Error::None);
  wait(2000);
  EXPECT_EQ(motor->last_pulse_width_ns(), 1'000'000u);
  EXPECT_EQ(ch->last_error(), Error::None);
}

// ---------------------------------------------------------------- NOWAIT (3-13, 3-27)

// 3-13 note 1: "The MOVE and SUSTAIN commands must specify the NOWAIT option for these
// trigger modes to work. Without NOWAIT, the HP 44714A must complete the MOVE or SUSTAIN
// command before the next command is recognized." The NOTE: such a command "can be
// cancelled by sending DEVICE CLEAR followed by TRIG HOLD" (TRIG HOLD alone on CANopen).
TEST_F(HpChannel, Hp3_13_Note1_TrigSysWithoutNowaitIsLockedInItsWaitState) {
  ASSERT_EQ(ch->trig(TrigMode::Sys, now), Error::None);
  ASSERT_EQ(ch->move(20, false, /*nowait=*/false, now), Error::None);
  EXPECT_EQ(done(), -3);
  EXPECT_TRUE(ch->locked_in_wait());
  ch->sync(now);  // the system trigger does not reach it
  wait(1000);
  EXPECT_EQ(position(), 0);
  EXPECT_EQ(done(), -3);
  EXPECT_EQ(ch->move(5, false, true, now), Error::AccessoryBusy);
  EXPECT_EQ(ch->trig(TrigMode::Sgl, now),
            Error::AccessoryBusy);  // "cannot access the trigger command"
  EXPECT_EQ(ch->pscale(2), Error::AccessoryBusy);
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);  // cancels it
  EXPECT_FALSE(ch->locked_in_wait());
  EXPECT_EQ(done(), 0);
  // With NOWAIT the same trigger mode works.
  ASSERT_EQ(ch->trig(TrigMode::Sys, now), Error::None);
  ASSERT_EQ(ch->move(20, false, /*nowait=*/true, now), Error::None);
  ch->sync(now);
  wait(2000);
  EXPECT_EQ(position(), 20);
  EXPECT_EQ(done(), 0);
}

TEST_F(HpChannel, Hp3_13_Note1_TrigChan0WithoutNowaitIsLockedInItsWaitState) {
  ASSERT_EQ(ch->trig(TrigMode::Chan0, now), Error::None);
  ASSERT_EQ(ch->sustain(100, /*nowait=*/false, now), Error::None);
  ch->chan0_triggered(now);  // channel 0 was triggered
  wait(1000);
  EXPECT_EQ(position(), 0);
  EXPECT_EQ(done(), -3);
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  ASSERT_EQ(ch->trig(TrigMode::Chan0, now), Error::None);
  ASSERT_EQ(ch->sustain(100, /*nowait=*/true, now), Error::None);
  ch->chan0_triggered(now);
  wait(1000);
  EXPECT_GT(position(), 0);
}

// 3-27 NOTE: "If NOWAIT is not specified, the SUSTAIN command will be locked into a wait state
// preventing it from accepting another command" (TRIG HOLD, then a trigger that never comes).
TEST_F(HpChannel, Hp3_27_Note_AWidthSustainWithoutNowaitUnderTrigHoldIsLocked) {
  ASSERT_EQ(ch->profile(width(1e-3, 10e-3, 5e-3, 20e-3), now), Conflict::None);
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  ASSERT_EQ(ch->sustain(2e-3, /*nowait=*/false, now), Error::None);
  EXPECT_EQ(ch->trig(TrigMode::Sgl, now), Error::AccessoryBusy);
  EXPECT_EQ(ch->sustain(3e-3, true, now), Error::AccessoryBusy);
  wait(1000);
  EXPECT_EQ(position(), 0);
  EXPECT_EQ(done(), -3);
}

// 3-12: without NOWAIT a SUSTAIN takes no other command "before the new velocity ... is
// accepted": the channel is locked while it ramps, free once at the velocity (DONE? -1).
TEST_F(HpChannel, Hp3_12_SustainWithoutNowaitLocksTheChannelUntilTheVelocityIsReached) {
  ASSERT_EQ(ch->profile(freq(100, 800, 200, 25e-6), now), Conflict::None);
  ASSERT_EQ(ch->sustain(500, /*nowait=*/false, now), Error::None);
  wait(1000);  // (500 - 100) / 200 = 2 s of ramp
  EXPECT_EQ(done(), -2);
  EXPECT_EQ(ch->sustain(600, true, now), Error::AccessoryBusy);
  EXPECT_EQ(ch->pscale(2), Error::AccessoryBusy);
  EXPECT_EQ(ch->trig(TrigMode::Hold, now), Error::None);  // always accepted (no DEVICE CLEAR)
  EXPECT_EQ(ch->pos(0), Error::AccessoryBusy);
  wait(1100);
  EXPECT_EQ(done(), -1);
  EXPECT_EQ(ch->sustain(600, true, now), Error::None);
  ch->halt_sgl(now);
}

// 3-27: the same for a pulse width: locked until the width is reached.
TEST_F(HpChannel, Hp3_27_WidthSustainWithoutNowaitLocksTheChannelUntilTheWidthIsReached) {
  ASSERT_EQ(ch->profile(width(1e-3, 10e-3, 5e-3, 20e-3), now), Conflict::None);
  ASSERT_EQ(ch->sustain(2e-3, /*nowait=*/false, now), Error::None);
  wait(100);  // (2 - 1) ms / 5 ms/s = 0.2 s
  EXPECT_EQ(done(), -2);
  EXPECT_EQ(ch->sustain(3e-3, true, now), Error::AccessoryBusy);
  wait(150);
  EXPECT_EQ(done(), -1);
  EXPECT_EQ(ch->sustain(3e-3, true, now), Error::None);
}

// ---------------------------------------------------------------- appendix A resolutions

// "Pulse Rate ... Resolution 2.5 uHz": an average pulse rate selected to that resolution.
// 2.5, 5 and 7.5 uHz give 2, 4 and 6 pulses in 800,000 s.
TEST_F(HpChannel, HpAppendixA_PulseRateResolution2_5MicroHz) {
  ASSERT_EQ(ch->profile(freq(0, 800, 200, 25e-6), now), Conflict::None);
  int64_t expected = 0;
  for (int k = 1; k <= 3; ++k) {
    const int64_t before = position();
    ASSERT_EQ(ch->sustain(k * 2.5e-6, true, now), Error::None);
    wait(800'000'000.0, 1'000'000);
    EXPECT_NEAR(position() - before, 2 * k, 1) << k * 2.5 << " uHz";
    expected += 2 * k;
    ch->halt_sgl(now);
  }
  EXPECT_NEAR(position(), expected, 3);
}

// "Pulse Width ... 65.535 msec maximum, 1 usec resolution", for the FREQ pwidth: every
// bound, and the width at the outputs to the microsecond.
TEST_F(HpChannel, HpAppendixA_FreqPulseWidthLimitsAndResolution) {
  EXPECT_EQ(ch->profile(freq(0, 10'000, 500, 1e-6), now), Conflict::None);
  EXPECT_EQ(ch->profile(freq(0, 10'000, 500, 0.9e-6), now), Conflict::OutOfRange);
  EXPECT_EQ(ch->profile(freq(0, 15, 500, 65.535e-3), now), Conflict::None);
  EXPECT_EQ(ch->profile(freq(0, 15, 500, 65.536e-3), now), Conflict::OutOfRange);
  for (double pwidth : {25.4e-6, 25.6e-6}) {
    ASSERT_EQ(ch->profile(freq(100, 800, 200, pwidth), now), Conflict::None);
    ASSERT_EQ(ch->move(5, false, true, now), Error::None);
    wait(1000);
    EXPECT_EQ(motor->last_pulse_width_ns(), std::llround(pwidth * 1e6) * 1000) << pwidth;
  }
}

}  // namespace
}  // namespace stepnode::motion::hp

namespace stepnode::motion::hp {
namespace {

// ---------------------------------------------------------------- TEST (4-3)

// "TEST Initiates a pass/fail self test." It passes on a sound module, leaves the settings
// and the motor as they were, and is refused while a command is in progress (error 89).
TEST_F(HpChannel, Hp4_3_TestIsAPassFailSelfTestThatKeepsTheSettings) {
  ASSERT_EQ(ch->profile(freq(100, 800, 200, 25e-6), now), Conflict::None);
  ASSERT_EQ(ch->pscale(0.1), Error::None);
  ch->delay(5);
  uint8_t failed = 0xFF;
  EXPECT_EQ(ch->test(failed), Error::None);
  EXPECT_EQ(failed, 0);
  EXPECT_EQ(run_self_test(), 0);
  EXPECT_EQ(ch->active_profile().max, 800);
  EXPECT_EQ(ch->scale(), 0.1);
  EXPECT_EQ(ch->delay_ms(), 5);
  EXPECT_EQ(position(), 0);
  EXPECT_EQ(done(), 0);
  ASSERT_EQ(ch->move(2, false, true, now), Error::None);
  wait(100);
  failed = 0xFF;
  EXPECT_EQ(ch->test(failed), Error::AccessoryBusy);
  EXPECT_EQ(failed, 0xFF);
  wait(2000);
  ASSERT_EQ(done(), 0);
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  ASSERT_EQ(ch->move(2, false, true, now), Error::None);  // waits for its trigger
  EXPECT_EQ(ch->test(failed), Error::AccessoryBusy);
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  EXPECT_EQ(ch->test(failed), Error::None);
  EXPECT_EQ(failed, 0);
}

}  // namespace
}  // namespace stepnode::motion::hp
