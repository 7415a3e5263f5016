// An HP 44714A MOVE or SUSTAIN waiting for its trigger (DONE? -3) against what can change
// before the trigger comes, each test named after the manual's page: the PROFILE's mode
// (error 92 and the SUSTAIN's units, 3-3, 3-12), STANDBY ON (error 94) and the TEST jumper
// (error 93). A waiting command never runs with its value read in other units, nor pulses a
// motor that cannot move.
#include <gtest/gtest.h>

#include "node/motion/tests/hp_channel_fixture.hpp"

namespace stepnode::motion::hp {
namespace {

// ---------------------------------------------------------------- the PROFILE's mode

// Error 92 (3-3): "A MOVE command cannot be executed when the PROFILE command is in the
// width mode." PROFILE WIDTH while a MOVE waits is a settings conflict: the MOVE runs at its
// trigger under the FREQ profile it was given in.
TEST_F(HpChannel, Hp3_3_Error92_ProfileWidthWhileAMoveWaitsIsASettingsConflict) {
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  ASSERT_EQ(ch->move(20, false, /*nowait=*/true, now), Error::None);
  ASSERT_EQ(done(), -3);
  Error e = Error::None;
  EXPECT_EQ(ch->profile(width(60e-3, 60e-3, 0, 100e-3), now, &e),
            Conflict::ModeVersusWaitingCommand);
  EXPECT_EQ(e, Error::None);
  EXPECT_EQ(ch->last_conflict(), Conflict::ModeVersusWaitingCommand);
  EXPECT_EQ(ch->active_profile().mode, ProfileMode::Freq);
  EXPECT_EQ(done(), -3);  // still waiting
  ASSERT_EQ(ch->trig(TrigMode::Sgl, now), Error::None);
  wait(2000);
  EXPECT_EQ(position(), 20);
  EXPECT_EQ(done(), 0);
  EXPECT_EQ(motor->last_pulse_width_ns(), 50'000u);  // the power-on pwidth: a FREQ move
  // Nothing waits now: PROFILE WIDTH is accepted, and a MOVE is error 92 when given.
  ASSERT_EQ(ch->profile(width(60e-3, 60e-3, 0, 100e-3), now), Conflict::None);
  EXPECT_EQ(ch->move(20, false, true, now), Error::NotValidInWidthMode);
}

// TRIG HOLD cancels the waiting MOVE ("can be cancelled by a TRIG HOLD command", 3-13);
// then the mode may change.
TEST_F(HpChannel, Hp3_13_Note_AfterTrigHoldCancelsTheWaitingMoveProfileWidthIsAccepted) {
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  ASSERT_EQ(ch->move(20, false, true, now), Error::None);
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  EXPECT_EQ(ch->profile(width(1e-3, 10e-3, 5e-3, 20e-3), now), Conflict::None);
  EXPECT_EQ(ch->active_profile().mode, ProfileMode::Width);
  EXPECT_EQ(ch->trig(TrigMode::Sgl, now), Error::NoActionDefined);
  wait(1000);
  EXPECT_EQ(position(), 0);
}

// 3-12: SUSTAIN's value is "The frequency of pulses in Hz (PROFILE in FREQ mode)" or "The
// pulse width in seconds (PROFILE in WIDTH mode)". SUSTAIN 100 (Hz) waits: PROFILE WIDTH
// would make it a 100 s width. A settings conflict; the SUSTAIN runs at 100 Hz.
TEST_F(HpChannel, Hp3_12_AWaitingSustainInHzMakesProfileWidthASettingsConflict) {
  ASSERT_EQ(ch->profile(freq(100, 800, 200, 25e-6), now), Conflict::None);
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  ASSERT_EQ(ch->sustain(100, true, now), Error::None);
  EXPECT_EQ(ch->profile(width(1e-3, 10e-3, 5e-3, 20e-3), now), Conflict::ModeVersusWaitingCommand);
  EXPECT_EQ(ch->active_profile().mode, ProfileMode::Freq);
  ASSERT_EQ(ch->trig(TrigMode::Sgl, now), Error::None);
  wait(1000);
  EXPECT_NEAR(position(), 100, 1);
  EXPECT_EQ(done(), -1);
  EXPECT_EQ(motor->last_pulse_width_ns(), 25'000u);
  ch->halt_sgl(now);
}

// The reverse: a WIDTH SUSTAIN of 2 ms waits under STANDBY ON; PROFILE FREQ would make it a
// stepper's 2 mHz SUSTAIN (error 94 under STANDBY ON). A settings conflict; the SUSTAIN runs
// as the pulse output it was given as, and the STBY output follows its train (3-29).
TEST_F(HpChannel, Hp3_12_AWaitingSustainInSecondsMakesProfileFreqASettingsConflict) {
  ASSERT_EQ(ch->profile(width(1e-3, 10e-3, 5e-3, 20e-3), now), Conflict::None);
  ASSERT_EQ(ch->standby(StandbyMode::On, true, now), Error::None);
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  ASSERT_EQ(ch->sustain(2e-3, true, now), Error::None);
  EXPECT_EQ(ch->profile(freq(100, 800, 200, 25e-6), now), Conflict::ModeVersusWaitingCommand);
  EXPECT_EQ(ch->active_profile().mode, ProfileMode::Width);
  ASSERT_EQ(ch->trig(TrigMode::Sgl, now), Error::None);
  EXPECT_EQ(ch->last_error(), Error::None);
  EXPECT_FALSE(ch->stby_output_high());  // triggered pulse output: low
  wait(1000);
  EXPECT_NEAR(position(), 50, 1);  // a 20 ms period
  EXPECT_EQ(motor->last_pulse_width_ns(), 2'000'000u);
  EXPECT_EQ(done(), -1);
  ch->halt_sgl(now);
  EXPECT_TRUE(ch->stby_output_high());
}

// ---------------------------------------------------------------- STANDBY ON, the TEST jumper

// Error 94 (3-3): "Motor cannot move when powered down by STANDBY in the ON mode"; STANDBY
// "ON = remove power" (3-6). STANDBY ON while a MOVE waits is accepted and removes power at
// once; the MOVE is refused with error 94 when its trigger would start it, and no pulse goes
// out. DONE? keeps the last move's code: this one never started.
TEST_F(HpChannel, Hp3_3_Error94_AWaitingMoveIsRefusedAtItsTriggerAfterStandbyOn) {
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  ASSERT_EQ(ch->move(20, false, /*nowait=*/true, now), Error::None);
  ASSERT_EQ(ch->standby(StandbyMode::On, true, now), Error::None);
  EXPECT_FALSE(ch->motor_powered());
  EXPECT_EQ(done(), -3);
  ASSERT_EQ(ch->trig(TrigMode::Sgl, now), Error::None);
  EXPECT_EQ(ch->last_error(), Error::CannotMoveWhileStandbyOn);
  wait(2000);
  EXPECT_EQ(position(), 0);
  EXPECT_EQ(ch->pulses(Output::Pstp) + ch->pulses(Output::Ndir), 0u);
  EXPECT_DOUBLE_EQ(ch->pos_query(), 0.0);
  EXPECT_FALSE(ch->motor_powered());
  EXPECT_FALSE(axis->core().busy());
  EXPECT_EQ(done(), 0);
  EXPECT_EQ(ch->trig(TrigMode::Sgl, now), Error::NoActionDefined);  // nothing waits
}

// The same for a stepper's SUSTAIN waiting for the SYNC (TRIG SYS).
TEST_F(HpChannel, Hp3_3_Error94_AWaitingSustainIsRefusedAtTheSyncAfterStandbyOn) {
  ASSERT_EQ(ch->trig(TrigMode::Sys, now), Error::None);
  ASSERT_EQ(ch->sustain(100, true, now), Error::None);
  ASSERT_EQ(ch->standby(StandbyMode::On, true, now), Error::None);
  ch->sync(now);
  EXPECT_EQ(ch->last_error(), Error::CannotMoveWhileStandbyOn);
  wait(1000);
  EXPECT_EQ(position(), 0);
  EXPECT_FALSE(axis->core().busy());
  EXPECT_EQ(done(), 0);
}

// Error 93 (3-3): "Will not execute a MOVE or SUSTAIN command when test jumper is in the
// 'TEST' position." The jumper is an input: set while a command waits for its trigger, or
// during the trigger's DELAY, the command is refused with error 93 when it would start.
TEST_F(HpChannel, Hp3_3_Error93_AWaitingCommandIsRefusedWhenTheTestJumperIsSet) {
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  ASSERT_EQ(ch->move(20, false, true, now), Error::None);
  ch->set_test_jumper(true);
  ASSERT_EQ(ch->trig(TrigMode::Sgl, now), Error::None);
  EXPECT_EQ(ch->last_error(), Error::TestJumperSet);
  wait(1000);
  EXPECT_EQ(position(), 0);
  EXPECT_FALSE(axis->core().busy());
  ch->set_test_jumper(false);
  // Set during the DELAY after the trigger.
  ch->delay(100);
  ASSERT_EQ(ch->sustain(100, true, now), Error::None);
  ASSERT_EQ(ch->trig(TrigMode::Sgl, now), Error::None);
  wait(50);
  EXPECT_EQ(done(), -2);  // triggered, the DELAY running
  ch->set_test_jumper(true);
  wait(1000);
  EXPECT_EQ(ch->last_error(), Error::TestJumperSet);
  EXPECT_EQ(position(), 0);
  EXPECT_FALSE(axis->core().busy());
  EXPECT_EQ(done(), 0);
}

}  // namespace
}  // namespace stepnode::motion::hp
