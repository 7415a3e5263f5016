// The HP 44714A channel against its manual (HP 3852A HP 44714A Configuration and Programming
// Manual, chapter 3; "3-n" is the manual's page), in virtual time on a simulated motor:
// power-on state, PROFILE and its conflicts, MOVE/PSCALE/POS, SUSTAIN, TRIG, DELAY, STANDBY,
// HALT, HARDLIM, DONE?, the error numbers, interrupts and the quadrature counter.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "node/motion/axis.hpp"
#include "node/motion/hp_channel.hpp"
#include "node/motion/tests/hp_channel_fixture.hpp"
#include "node/sim/machine.hpp"

namespace stepnode::motion::hp {
namespace {

// ---------------------------------------------------------------- power-on (3-2)

TEST_F(HpChannel, PowerOnStateIsTheManualsTable) {
  const Profile& p = ch->active_profile();
  EXPECT_EQ(p.mode, ProfileMode::Freq);
  EXPECT_EQ(p.min, 0);
  EXPECT_EQ(p.max, 250);
  EXPECT_EQ(p.slope, 500);
  EXPECT_EQ(p.last, 50e-6);
  EXPECT_EQ(ch->standby_mode(), StandbyMode::Auto);
  EXPECT_TRUE(ch->standby_sense_high());
  EXPECT_EQ(ch->pulse_setup().mode, PulseMode::StepStep);
  EXPECT_FALSE(ch->pulse_setup().pstp_high);
  EXPECT_FALSE(ch->pulse_setup().ndir_high);
  EXPECT_EQ(ch->scale(), 1.0);
  EXPECT_EQ(ch->delay_ms(), 0);
  EXPECT_EQ(ch->trig_mode(), TrigMode::Auto);
  EXPECT_EQ(ch->halt_mode(), HaltMode::Lo);
  EXPECT_FALSE(ch->plim_sense_high());
  EXPECT_FALSE(ch->nlim_sense_high());
  EXPECT_EQ(ch->qscale(), 1.0);
  EXPECT_EQ(ch->qindex_mode(), QIndexMode::Off);
  EXPECT_FALSE(ch->intr_enabled());  // "all interrupts are disabled"
  EXPECT_EQ(done(), 0);
}

// ---------------------------------------------------------------- PROFILE FREQ (3-8, 3-9)

TEST_F(HpChannel, ProfileFreqSettingConflictsAreTheTablesRows) {
  EXPECT_EQ(ch->profile(freq(100, 800, 0, 25e-6), now), Conflict::SlopeZeroRangeUnattainable);
  EXPECT_EQ(ch->profile(freq(0, 800, 0, 25e-6), now), Conflict::MinZeroSlopeZero);
  EXPECT_EQ(ch->profile(freq(0, 0, 0, 25e-6), now), Conflict::AllZero);
  EXPECT_EQ(ch->profile(freq(0, 1000, 500, 2e-3), now), Conflict::WidthVersusPeriod);
  EXPECT_EQ(ch->profile(freq(500, 100, 200, 2e-3), now), Conflict::MinAboveMax);
  EXPECT_EQ(ch->last_conflict(), Conflict::MinAboveMax);
  // A refused PROFILE leaves the one in effect.
  EXPECT_EQ(ch->active_profile().max, 250);
  // Figure 3-2's profiles are legal, including min = max with slope 0 and with a slope.
  EXPECT_EQ(ch->profile(freq(100, 100, 0, 25e-6), now), Conflict::None);
  EXPECT_EQ(ch->profile(freq(800, 800, 100, 25e-6), now), Conflict::None);
  EXPECT_EQ(ch->profile(freq(100, 800, 200, 25e-6), now), Conflict::None);
  EXPECT_EQ(ch->last_conflict(), Conflict::None);
  EXPECT_EQ(ch->active_profile().max, 800);
  // Appendix A: 10 kHz and 1 MHz/s at most.
  EXPECT_EQ(ch->profile(freq(0, 10'001, 500, 25e-6), now), Conflict::OutOfRange);
  EXPECT_EQ(ch->profile(freq(0, 1000, 1.1e6, 25e-6), now), Conflict::OutOfRange);
  // ... and a rate of change resolved to 25 mHz/s (1 µs/s for widths): a slope above 0
  // but finer is out of range (1e-15 Hz/s overflowed the ramp arithmetic).
  EXPECT_EQ(ch->profile(freq(100, 800, 0.02, 25e-6), now), Conflict::OutOfRange);
  EXPECT_EQ(ch->profile(freq(100, 800, 1e-15, 25e-6), now), Conflict::OutOfRange);
  EXPECT_EQ(ch->profile(freq(100, 800, 0.025, 25e-6), now), Conflict::None);
  EXPECT_EQ(ch->profile(width(1e-6, 10e-6, 1e-7, .1e-3), now), Conflict::OutOfRange);
  EXPECT_EQ(ch->profile(width(1e-6, 10e-6, 1e-6, .1e-3), now), Conflict::None);
}

// 3-8: "You cannot operate at a frequency less than min or greater than max"; rows 2 and 3 of
// the conflict tables (3-9, 3-26) are settings conflicts because "no pulses can be
// generated". With min = max = 0 none can whatever the slope (a MOVE under PROFILE FREQ 0 0
// 500 never sent a pulse and never ended): row 3. The same for widths.
TEST_F(HpChannel, AZeroMinimumAndMaximumWithASlopeIsASettingsConflict) {
  EXPECT_EQ(ch->profile(freq(0, 0, 500, 50e-6), now), Conflict::AllZero);
  EXPECT_EQ(ch->last_conflict(), Conflict::AllZero);
  EXPECT_EQ(ch->profile(width(0, 0, 1e-3, .1e-3), now), Conflict::AllZero);
  // The profile in effect is still the power-on one, and a MOVE under it ends.
  EXPECT_EQ(ch->active_profile().mode, ProfileMode::Freq);
  EXPECT_EQ(ch->active_profile().max, 250);
  ASSERT_EQ(ch->move(10, false, true, now), Error::None);
  wait(2000);
  EXPECT_EQ(position(), 10);
  EXPECT_EQ(done(), 0);
}

TEST_F(HpChannel, AppendixAPulseRateResolutionAndMaximumBoundTheRates) {
  // "Pulse Rate: maximum 10 kHz, resolution 2.5 µHz". A FREQ min or max above 0 but finer
  // than the resolution is out of range, as is a WIDTH period under 100 µs (above 10 kHz).
  EXPECT_EQ(ch->profile(freq(1e-7, 800, 200, 25e-6), now), Conflict::OutOfRange);
  EXPECT_EQ(ch->profile(freq(0, 1e-7, 200, 25e-6), now), Conflict::OutOfRange);
  EXPECT_EQ(ch->profile(freq(2.5e-6, 800, 200, 25e-6), now), Conflict::None);
  EXPECT_EQ(ch->profile(width(1e-6, 10e-6, 1e-6, 99e-6), now), Conflict::OutOfRange);
  EXPECT_EQ(ch->profile(width(1e-6, 10e-6, 1e-6, 1e-300), now), Conflict::OutOfRange);
  EXPECT_EQ(ch->profile(width(1e-6, 10e-6, 1e-6, 100e-6), now), Conflict::None);
  // A SUSTAIN whose clamped rate is finer than 2.5 µHz is refused and changes nothing
  // (SUSTAIN 1E-12 overflowed freq_ramp's llround: the motor ran away).
  ASSERT_EQ(ch->profile(freq(0, 800, 200, 25e-6), now), Conflict::None);
  EXPECT_EQ(ch->sustain(1e-12, true, now), Error::ValueOutOfRange);
  EXPECT_EQ(ch->sustain(-2e-6, true, now), Error::ValueOutOfRange);
  EXPECT_EQ(ch->sustain(std::nan(""), true, now), Error::ValueOutOfRange);
  EXPECT_EQ(ch->last_error(), Error::None);
  wait(1000);
  EXPECT_EQ(position(), 0);
  EXPECT_EQ(done(), 0);
  // At the resolution it runs (one pulse in 4.6 days). A change to 800 Hz moves the
  // motion onto a grid for 800 Hz: it ramps at the slope, not one µHz level per tick.
  EXPECT_EQ(ch->sustain(2.5e-6, true, now), Error::None);
  wait(1000);
  EXPECT_LT(done(), 0);
  EXPECT_EQ(position(), 0);
  EXPECT_EQ(ch->sustain(800, true, now), Error::None);
  wait(4100);  // (800 - 0) / 200 Hz/s = 4 s
  EXPECT_EQ(done(), -1);
  EXPECT_NEAR(axis->velocity(), 800, 800 * 1e-6);
  // Down to a rate below one level of that grid (levels of slope / 76,800 = 2.6 mHz): it
  // ramps to the lowest level, then holds 1e-5 Hz on a grid made for it (level 0 would
  // have divided the next step's time by zero). The generator's level is brought up to
  // date at steps only, so the held rate shows in the positions, not in velocity().
  EXPECT_EQ(ch->sustain(1e-5, true, now), Error::None);
  wait(4100);
  int64_t held = position();
  wait(2000);
  EXPECT_LE(position() - held, 1);
  EXPECT_TRUE(axis->core().busy());
  ch->halt_sgl(now);
  // With a minimum the clamp lifts a tiny rate to it, as the manual says (3-12).
  ASSERT_EQ(ch->profile(freq(100, 800, 200, 25e-6), now), Conflict::None);
  int64_t before = position();
  EXPECT_EQ(ch->sustain(1e-12, true, now), Error::None);
  wait(1000);
  EXPECT_NEAR(position() - before, 100, 1);
}

TEST_F(HpChannel, ASustainChangeOnACoarseRampHoldsTheRateItself) {
  // At 1 MHz/s a ramp level is 13.3 Hz. SUSTAIN 10000 then SUSTAIN 5 held one level
  // (13.3 Hz) and SUSTAIN 20 two (26.7 Hz); appendix A: pulse rate accuracy 0.01 %.
  ASSERT_EQ(ch->profile(freq(0, 10'000, 1e6, 1e-6), now), Conflict::None);
  ASSERT_EQ(ch->sustain(10'000, true, now), Error::None);
  wait(100);
  ASSERT_EQ(ch->sustain(5, true, now), Error::None);
  wait(1000);
  int64_t p0 = position();
  wait(10'000);
  EXPECT_NEAR(position() - p0, 50, 1);
  EXPECT_NEAR(axis->velocity(), 5, 5e-4);
  ASSERT_EQ(ch->sustain(20, true, now), Error::None);
  wait(1000);
  p0 = position();
  wait(10'000);
  EXPECT_NEAR(position() - p0, 200, 1);
}

TEST_F(HpChannel, AMoveAtMinEqualToMaxRunsAtThatRateNotFaster) {
  // PROFILE FREQ 10 10 500: min = max, "no frequencies below the minimum" and none above
  // the maximum (3-12). The creep level (one step from standstill at 500 Hz/s = 31.6 Hz)
  // ran the whole move at 31.6 Hz: 100 steps in 3.2 s instead of 10 s.
  ASSERT_EQ(ch->profile(freq(10, 10, 500, 25e-6), now), Conflict::None);
  ASSERT_EQ(ch->move(100, false, true, now), Error::None);
  wait(9'800);
  EXPECT_LT(position(), 100);
  EXPECT_EQ(done(), -2);
  wait(400);
  EXPECT_EQ(position(), 100);
  EXPECT_EQ(done(), 0);
}

TEST_F(HpChannel, AMoveLongerThanTheEnginesClockIsRefused) {
  // 2^31 - 1 pulses at a 2.5 µHz maximum is 27 million years: its deceleration tick
  // overflowed int64. Refused (a range abort on the bus), nothing armed.
  ASSERT_EQ(ch->profile(freq(0, 2.5e-6, 1, 25e-6), now), Conflict::None);
  EXPECT_EQ(ch->move(2147483647, false, true, now), Error::ValueOutOfRange);
  EXPECT_EQ(done(), 0);
  EXPECT_EQ(ch->move(10, false, true, now), Error::None);  // 46 days: fine
  ch->halt_sgl(now);
}

TEST_F(HpChannel, AnArmedSustainIsCheckedAgainWhenItFires) {
  // SUSTAIN 1E-12 NOWAIT under TRIG HOLD is accepted with a 100 Hz minimum (it runs at min),
  // then PROFILE with a 0 minimum, then TRIG SGL: the clamp leaves 1E-12 Hz, finer than the
  // 2.5 uHz resolution, which never reaches the engine.
  ASSERT_EQ(ch->profile(freq(100, 800, 200, 25e-6), now), Conflict::None);
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  ASSERT_EQ(ch->sustain(1e-12, true, now), Error::None);
  EXPECT_EQ(done(), -3);
  ASSERT_EQ(ch->profile(freq(0, 800, 200, 25e-6), now), Conflict::None);
  ASSERT_EQ(ch->trig(TrigMode::Sgl, now), Error::None);
  wait(1000);
  EXPECT_EQ(position(), 0);
  EXPECT_FALSE(axis->core().busy());
}

TEST_F(HpChannel, ProfileWidthSettingConflictsAreTheTablesRows) {
  EXPECT_EQ(ch->profile(width(1e-6, 10e-6, 0, .1e-3), now), Conflict::SlopeZeroRangeUnattainable);
  EXPECT_EQ(ch->profile(width(0, 10e-6, 0, .1e-3), now), Conflict::MinZeroSlopeZero);
  EXPECT_EQ(ch->profile(width(0, 0, 0, .1e-3), now), Conflict::AllZero);
  EXPECT_EQ(ch->profile(width(1e-3, 10e-3, 1e-3, 9e-3), now), Conflict::WidthVersusPeriod);
  EXPECT_EQ(ch->profile(width(5e-3, 1e-3, 1e-3, 10e-3), now), Conflict::MinAboveMax);
  EXPECT_EQ(ch->active_profile().mode, ProfileMode::Freq);
  EXPECT_EQ(ch->profile(width(1e-3, 10e-3, 5e-3, 20e-3), now), Conflict::None);  // 3-28 example
  EXPECT_EQ(ch->active_profile().mode, ProfileMode::Width);
}

TEST_F(HpChannel, MoveRampsContinuouslyFromMinToMaxAtTheSlope) {
  // PROFILE FREQ 100 800 200: a 2000-step move reaches 800 Hz after (800-100)/200 = 3.5 s
  // having covered (100+800)/2 * 3.5 = 1575 steps, so it is triangular: the peak satisfies
  // v^2 = 100^2 + 2 * 200 * 1000 and the move lasts 2 * (v - 100) / 200 s.
  ASSERT_EQ(ch->profile(freq(100, 800, 200, 25e-6), now), Conflict::None);
  ASSERT_EQ(ch->move(2000, false, true, now), Error::None);
  double peak = std::sqrt(100.0 * 100 + 2 * 200 * 1000);
  double ideal_ms = 2 * (peak - 100) / 200 * 1000;
  wait(ideal_ms + 200);
  EXPECT_EQ(position(), 2000);
  EXPECT_EQ(done(), 0);
  EXPECT_NEAR(to_ms(motor->last_step_time()), ideal_ms, 12);  // within ~one step at min
  EXPECT_LE(axis->core().generator().marks().peak_level,
            level_of(axis->core().generator().ramp(), peak) + 1);
  // First step: at 100 Hz rising, a little under 10 ms after the start.
  ASSERT_TRUE(ch->first_step_time());
  EXPECT_GT(to_ms(*ch->first_step_time()), 9.0);
  EXPECT_LE(to_ms(*ch->first_step_time()), 10.0);
}

TEST_F(HpChannel, AMoveWithAZeroMinimumStartsFromStandstillAndEnds) {
  // Power-on profile: 0..250 Hz at 500 Hz/s. From 0 Hz the first step falls when
  // 1 = 500 t^2 / 2, t = 63.2 ms; the move ends (no creeping at micro-hertz).
  ASSERT_EQ(ch->move(100, false, true, now), Error::None);
  wait(2000);
  EXPECT_EQ(position(), 100);
  EXPECT_EQ(done(), 0);
  EXPECT_NEAR(to_ms(*ch->first_step_time()), 63.2, 0.5);
}

// ---------------------------------------------------------------- PSCALE / MOVE / POS (3-9..3-19)

TEST_F(HpChannel, PscaleRoundOffExampleRel) {
  // "PSCALE ROUND-OFF ERROR EXAMPLES", REL: POS 0, PSCALE 2, MOVE 1 REL three times.
  ASSERT_EQ(ch->pos(0), Error::None);
  ASSERT_EQ(ch->pscale(2), Error::None);
  for (double expected : {2.0, 4.0, 6.0}) {
    ASSERT_EQ(ch->move(1, false, false, now), Error::None);
    wait(1000);
    EXPECT_EQ(ch->pos_query(), expected);
  }
  EXPECT_EQ(position(), 3);
}

TEST_F(HpChannel, PscaleRoundOffExampleAbs) {
  ASSERT_EQ(ch->pos(0), Error::None);
  ASSERT_EQ(ch->pscale(2), Error::None);
  for (auto [target, expected] : {std::pair{1.0, 2.0}, {2.0, 2.0}, {3.0, 4.0}}) {
    ASSERT_EQ(ch->move(target, true, false, now), Error::None);
    wait(1000);
    EXPECT_EQ(ch->pos_query(), expected) << "MOVE " << target << " ABS";
  }
  EXPECT_EQ(position(), 2);
}

TEST_F(HpChannel, MoveInUnitsNegativeScaleAndPosLoad) {
  // 3-12: "a scale factor of 0.1 ... will cause 200 pulses" for a 20-unit move.
  ASSERT_EQ(ch->pscale(0.1), Error::None);
  ASSERT_EQ(ch->move(20, false, true, now), Error::None);
  wait(3000);
  EXPECT_EQ(position(), 200);
  EXPECT_NEAR(ch->pos_query(), 20.0, 1e-9);
  // POS loads the counter in units (3-18); ABS moves go from there.
  ASSERT_EQ(ch->pos(-10), Error::None);
  ASSERT_EQ(ch->move(0, true, true, now), Error::None);
  wait(3000);
  EXPECT_EQ(position(), 300);
  EXPECT_NEAR(ch->pos_query(), 0.0, 1e-9);
  // A negative scale: positive distance is negative motor motion (3-9).
  ASSERT_EQ(ch->pscale(-0.5), Error::None);
  ASSERT_EQ(ch->move(10, false, true, now), Error::None);
  wait(3000);
  EXPECT_EQ(position(), 280);
  EXPECT_NEAR(ch->pos_query(), 10.0, 1e-9);
}

TEST_F(HpChannel, ProfileFrequenciesAreInUnitsOfThePscaleInEffect) {
  // 3-9: "The scale factor of the PSCALE command affects the PROFILE" - after PSCALE 0.5,
  // PROFILE FREQ 50 50 0 is 100 steps/s.
  ASSERT_EQ(ch->pscale(0.5), Error::None);
  ASSERT_EQ(ch->profile(freq(50, 50, 0, 25e-6), now), Conflict::None);
  EXPECT_DOUBLE_EQ(ch->active_profile().min, 100);
  ASSERT_EQ(ch->move(50, false, true, now), Error::None);  // 100 steps at 100 Hz = 1 s
  wait(1100);
  EXPECT_EQ(position(), 100);
  EXPECT_NEAR(to_ms(motor->last_step_time()), 1000, 0.01);
}

// ---------------------------------------------------------------- SUSTAIN (3-12)

TEST_F(HpChannel, SustainRampsToTheVelocityClampedToTheProfile) {
  ASSERT_EQ(ch->profile(freq(100, 800, 200, 25e-6), now), Conflict::None);
  ASSERT_EQ(ch->sustain(1000, true, now), Error::None);  // above max: runs at max
  EXPECT_EQ(done(), -2);
  wait(3400);
  EXPECT_EQ(done(), -2);  // still ramping: 3.5 s to reach 800
  wait(200);
  EXPECT_EQ(done(), -1);
  EXPECT_NEAR(axis->velocity(), 800, 1e-6);
  // Below min: runs at min.
  ASSERT_EQ(ch->sustain(10, true, now), Error::None);
  wait(3600);
  EXPECT_NEAR(axis->velocity(), 100, 1e-6);
  // 100 Hz held: 100 steps a second.
  int64_t p0 = position();
  wait(1000);
  EXPECT_NEAR(position() - p0, 100, 1);
}

TEST_F(HpChannel, ASustainedRateIsExactEvenFractionalAndWithASteepSlope) {
  // Appendix A: pulse rate accuracy 0.01 %. The run rate of a ramp is exact to 0.5 /
  // phase_per_step (< 2e-7 even at 100 kHz/s); 1000 s at 123.456 Hz is 123456 pulses.
  ASSERT_EQ(ch->profile(freq(0, 10'000, 100'000, 1e-6), now), Conflict::None);
  ASSERT_EQ(ch->sustain(123.456, true, now), Error::None);
  wait(100);
  ASSERT_EQ(done(), -1);
  EXPECT_NEAR(axis->velocity(), 123.456, 123.456 * 2e-7);
  int64_t p0 = position();
  wait(1'000'000, 1000);
  EXPECT_NEAR(position() - p0, 123456, 1);
}

TEST_F(HpChannel, SustainZeroStopsAtMinAndReversingNeedsAStopError91) {
  ASSERT_EQ(ch->profile(freq(100, 800, 200, 25e-6), now), Conflict::None);
  ASSERT_EQ(ch->sustain(500, true, now), Error::None);
  wait(3000);
  // 3-3 error 91: "A running SUSTAIN command must be stopped with HALT or SUSTAIN 0".
  EXPECT_EQ(ch->sustain(-500, true, now), Error::MustStopToChangeDirection);
  EXPECT_EQ(ch->last_error(), Error::MustStopToChangeDirection);
  ASSERT_EQ(ch->sustain(0, true, now), Error::None);
  EXPECT_EQ(done(), -2);
  wait(2100);  // (500-100)/200 = 2 s down to min, then stop
  EXPECT_EQ(done(), 0);
  EXPECT_FALSE(axis->core().busy());
  EXPECT_EQ(ch->last_error(), Error::None);
  int64_t p = position();
  ASSERT_EQ(ch->sustain(-500, true, now), Error::None);
  wait(1000);
  EXPECT_LT(position(), p);
}

// ---------------------------------------------------------------- TRIG (3-13) and DELAY (3-14)

TEST_F(HpChannel, TrigHoldArmsSglFiresAndReturnsToHold) {
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  ASSERT_EQ(ch->move(50, false, true, now), Error::None);
  wait(500);
  EXPECT_EQ(done(), -3);  // waiting for trigger
  EXPECT_EQ(position(), 0);
  ASSERT_EQ(ch->trig(TrigMode::Sgl, now), Error::None);
  EXPECT_EQ(ch->trig_mode(), TrigMode::Hold);
  EXPECT_EQ(done(), -2);
  wait(2000);
  EXPECT_EQ(position(), 50);
  EXPECT_EQ(done(), 0);
}

TEST_F(HpChannel, TrigSglWithNothingArmedIsError90AndHoldCancels) {
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  EXPECT_EQ(ch->trig(TrigMode::Sgl, now), Error::NoActionDefined);
  EXPECT_EQ(ch->last_error(), Error::NoActionDefined);
  ASSERT_EQ(ch->move(50, false, true, now), Error::None);
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);  // cancels the armed MOVE (3-14 NOTE)
  EXPECT_EQ(done(), 0);
  EXPECT_EQ(ch->trig(TrigMode::Sgl, now), Error::NoActionDefined);
  wait(1000);
  EXPECT_EQ(position(), 0);
}

TEST_F(HpChannel, TrigSysStartsOnSync) {
  ASSERT_EQ(ch->trig(TrigMode::Sys, now), Error::None);
  ASSERT_EQ(ch->move(20, false, true, now), Error::None);
  wait(300);
  EXPECT_EQ(done(), -3);
  Tick sync_at = now + ms(0.3);
  ch->sync(sync_at);
  EXPECT_EQ(*ch->trigger_time(), sync_at);
  wait(2000);
  EXPECT_EQ(position(), 20);
  EXPECT_EQ(ch->trig_mode(), TrigMode::Sys);  // SYS stays the source
  EXPECT_NEAR(to_ms(*ch->first_step_time() - sync_at), 63.2, 0.5);
  // A SYNC with nothing armed does nothing.
  ch->sync(now);
  EXPECT_EQ(done(), 0);
}

TEST_F(HpChannel, TrigChan0StartsWithChannel0) {
  sim::AxisMachine motor1(plain());
  Axis axis1(AxisConfig{}, {&motor1});
  Channel ch1(axis1.core());
  ch->on_triggered = [&](Tick t) { ch1.chan0_triggered(t); };
  ASSERT_EQ(ch1.trig(TrigMode::Chan0, now), Error::None);
  ASSERT_EQ(ch1.move(30, false, true, now), Error::None);
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  ASSERT_EQ(ch->move(30, false, true, now), Error::None);
  wait(100);
  ch1.advance_to(now);
  EXPECT_EQ(static_cast<int>(ch1.done()), -3);
  ASSERT_EQ(ch->trig(TrigMode::Sgl, now), Error::None);
  EXPECT_EQ(*ch1.trigger_time(), *ch->trigger_time());
  wait(2000);
  ch1.advance_to(now);
  EXPECT_EQ(motor1.position(), 30);
  EXPECT_EQ(*ch1.first_step_time(), *ch->first_step_time());  // same profile, same start
}

TEST_F(HpChannel, DelayPostponesTheFirstPulse) {
  ch->delay(5000);  // Figure 3-3 line 70: "DELAY 5"
  ASSERT_EQ(ch->move(10, false, true, now), Error::None);
  EXPECT_EQ(done(), -2);  // triggered, running the delay
  wait(5000);
  EXPECT_EQ(position(), 0);
  wait(1000);
  EXPECT_EQ(position(), 10);
  EXPECT_NEAR(to_ms(*ch->first_step_time() - *ch->trigger_time()), 5063.2, 0.5);
}

// ---------------------------------------------------------------- STANDBY (3-5, 3-29)

TEST_F(HpChannel, StandbyOnRefusesMovesError94AndOffPowers) {
  ASSERT_EQ(ch->standby(StandbyMode::On, false, now), Error::None);  // "STANDBY ON LO"
  EXPECT_FALSE(ch->motor_powered());
  EXPECT_FALSE(ch->stby_output_high());  // LO sense: low while power is removed
  EXPECT_EQ(ch->move(750, false, true, now), Error::CannotMoveWhileStandbyOn);
  EXPECT_EQ(ch->sustain(100, true, now), Error::CannotMoveWhileStandbyOn);
  ASSERT_EQ(ch->standby(StandbyMode::Off, false, now), Error::None);
  EXPECT_TRUE(ch->motor_powered());
  EXPECT_TRUE(ch->stby_output_high());
  ASSERT_EQ(ch->move(10, false, true, now), Error::None);
  wait(1000);
  EXPECT_EQ(position(), 10);
}

TEST_F(HpChannel, StandbyAutoPowersForTheMoveAndOffOneSecondAfter) {
  EXPECT_FALSE(ch->motor_powered());
  EXPECT_TRUE(ch->stby_output_high());  // AUTO HI: high while idle
  ASSERT_EQ(ch->move(10, false, true, now), Error::None);
  EXPECT_TRUE(ch->motor_powered());
  wait(400);
  ASSERT_EQ(done(), 0);
  wait(800);
  EXPECT_TRUE(ch->motor_powered());  // less than a second since the last pulse
  wait(600);
  EXPECT_FALSE(ch->motor_powered());
  EXPECT_TRUE(ch->stby_output_high());
}

// ---------------------------------------------------------------- HALT (3-14, 3-17)

TEST_F(HpChannel, HaltSglStopsAtOnceDone1) {
  ASSERT_EQ(ch->sustain(200, true, now), Error::None);
  wait(1000);
  ch->enable_intr();
  int64_t p = position();
  ch->halt_sgl(now);
  EXPECT_EQ(done(), 1);
  wait(500);
  EXPECT_EQ(position(), p);
  ASSERT_EQ(interrupts.size(), 1u);
  EXPECT_EQ(interrupts[0].event, intr::kHaltSgl);
}

TEST_F(HpChannel, HaltSwitchStopsPulsesAndHaltOffIgnoresIt) {
  ASSERT_EQ(ch->sustain(200, true, now), Error::None);
  wait(500);
  ch->enable_intr();
  motor->set_halt_input(false);  // switch pulls HALTn LO; HALT LO is the power-on mode
  axis->advance_to(now);         // the channel sees the input's edge
  EXPECT_EQ(done(), 1);
  ASSERT_EQ(interrupts.size(), 1u);
  EXPECT_EQ(interrupts[0].event, intr::kHaltSwitch);
  // While it is active a move halts before its first pulse.
  ASSERT_EQ(ch->move(10, false, true, now), Error::None);
  EXPECT_EQ(done(), 1);
  ch->halt_mode(HaltMode::Off, now);
  ASSERT_EQ(ch->move(10, false, true, now), Error::None);
  wait(1000);
  EXPECT_EQ(done(), 0);
  // HALT HI: the (open, pulled-up) input now reads as active.
  motor->set_halt_input(true);
  axis->advance_to(now);
  ch->halt_mode(HaltMode::Hi, now);
  ASSERT_EQ(ch->move(10, false, true, now), Error::None);
  EXPECT_EQ(done(), 1);
}

// ---------------------------------------------------------------- HARDLIM (3-17)

TEST_F(HpChannel, HardLimitStopsPulsesDone2AndAllowsTheOtherWay) {
  sim::AxisMachineConfig m = plain();
  m.upper_limit = 150;
  m.lower_limit = -1000;
  build(m);
  ch->enable_intr();
  ASSERT_EQ(ch->move(1000, false, true, now), Error::None);
  wait(3000);
  EXPECT_EQ(position(), 150);  // the step that reached the limit is the last
  EXPECT_EQ(done(), 2);
  ASSERT_EQ(interrupts.size(), 1u);
  EXPECT_EQ(interrupts[0].event, intr::kHardLimit);
  // "further positive motion is prohibited but negative motion is allowed"
  ASSERT_EQ(ch->move(5, false, true, now), Error::None);
  EXPECT_EQ(done(), 2);
  EXPECT_EQ(position(), 150);
  ASSERT_EQ(ch->move(-50, false, true, now), Error::None);
  wait(2000);
  EXPECT_EQ(position(), 100);
  EXPECT_EQ(done(), 0);
  // HARDLIM HI: the open (high) input means "limit reached": no positive move at all.
  ch->hardlim(true, false);
  ASSERT_EQ(ch->move(5, false, true, now), Error::None);
  EXPECT_EQ(done(), 2);
}

// ---------------------------------------------------------------- errors 89, 92, 93 (3-3)

TEST_F(HpChannel, Error89AccessoryBusyWhileAMoveIsInProgress) {
  ASSERT_EQ(ch->move(100, false, true, now), Error::None);
  wait(100);
  EXPECT_EQ(ch->move(10, false, true, now), Error::AccessoryBusy);
  EXPECT_EQ(ch->sustain(10, true, now), Error::AccessoryBusy);
  EXPECT_EQ(ch->pos(0), Error::AccessoryBusy);
  EXPECT_EQ(ch->last_error(), Error::AccessoryBusy);
  wait(3000);
  EXPECT_EQ(ch->move(10, false, true, now), Error::None);
  EXPECT_EQ(ch->last_error(), Error::None);
}

TEST_F(HpChannel, WithoutNowaitTheChannelIsBusyUntilTheMoveEnds) {
  ASSERT_EQ(ch->move(100, false, /*nowait=*/false, now), Error::None);
  wait(100);
  EXPECT_EQ(ch->pos(0), Error::AccessoryBusy);
  EXPECT_EQ(ch->trig(TrigMode::Auto, now), Error::AccessoryBusy);
  wait(3000);
  EXPECT_EQ(ch->trig(TrigMode::Auto, now), Error::None);
}

TEST_F(HpChannel, Error92MoveInWidthMode) {
  ASSERT_EQ(ch->profile(width(1e-3, 10e-3, 5e-3, 20e-3), now), Conflict::None);
  EXPECT_EQ(ch->move(10, false, true, now), Error::NotValidInWidthMode);
  EXPECT_EQ(done(), 0);
}

TEST_F(HpChannel, Error93TestJumperSet) {
  ch->set_test_jumper(true);
  EXPECT_EQ(ch->move(10, false, true, now), Error::TestJumperSet);
  EXPECT_EQ(ch->sustain(10, true, now), Error::TestJumperSet);
  ch->set_test_jumper(false);
  EXPECT_EQ(ch->move(10, false, true, now), Error::None);
}

// ---------------------------------------------------------------- interrupts (3-16)

TEST_F(HpChannel, InterruptExampleMoveSustainHalt) {
  // The manual's interrupt example: PROFILE FREQ 0 1200 250 50E-6, ENABLE INTR; MOVE 100
  // interrupts after the move, SUSTAIN 1000 when 1000 Hz is reached, HALT SGL when pulses
  // halt; the service routine re-enables each time.
  ch->on_interrupt = [this](uint8_t e, Tick t) {
    interrupts.push_back({e, t});
    ch->enable_intr();
  };
  ASSERT_EQ(ch->profile(freq(0, 1200, 250, 50e-6), now), Conflict::None);
  ch->enable_intr();
  ASSERT_EQ(ch->move(100, false, true, now), Error::None);
  wait(5000);
  ASSERT_EQ(interrupts.size(), 1u);
  EXPECT_EQ(interrupts[0].event, intr::kMoveDone);
  EXPECT_EQ(interrupts[0].at, motor->last_step_time());
  Tick sustain_at = now;
  ASSERT_EQ(ch->sustain(1000, true, now), Error::None);
  wait(10000);
  ASSERT_EQ(interrupts.size(), 2u);
  EXPECT_EQ(interrupts[1].event, intr::kSustainReached);
  EXPECT_NEAR(to_ms(interrupts[1].at - sustain_at), 4000, 2);  // 1000 Hz / 250 Hz/s
  ch->halt_sgl(now);
  ASSERT_EQ(interrupts.size(), 3u);
  EXPECT_EQ(interrupts[2].event, intr::kHaltSgl);
}

TEST_F(HpChannel, AnInterruptIsDisabledOnceSentUntilReEnabled) {
  ch->enable_intr();
  ASSERT_EQ(ch->move(5, false, true, now), Error::None);
  wait(1000);
  ASSERT_EQ(ch->move(5, false, true, now), Error::None);
  wait(1000);
  ASSERT_EQ(interrupts.size(), 1u);
  EXPECT_EQ(ch->interrupt_events(), intr::kMoveDone);
  EXPECT_FALSE(ch->intr_enabled());
  ch->enable_intr();  // clears, then enables
  EXPECT_EQ(ch->interrupt_events(), 0);
  ch->disable_intr();
  ASSERT_EQ(ch->move(5, false, true, now), Error::None);
  wait(1000);
  EXPECT_EQ(interrupts.size(), 1u);
}

// ---------------------------------------------------------------- DONE? (3-19)

TEST_F(HpChannel, DoneCodesMinus3ToPlus2) {
  EXPECT_EQ(done(), 0);
  ASSERT_EQ(ch->trig(TrigMode::Hold, now), Error::None);
  ASSERT_EQ(ch->sustain(100, true, now), Error::None);
  EXPECT_EQ(done(), -3);
  ASSERT_EQ(ch->trig(TrigMode::Sgl, now), Error::None);
  EXPECT_EQ(done(), -2);
  wait(1000);
  EXPECT_EQ(done(), -1);
  ch->halt_sgl(now);
  EXPECT_EQ(done(), 1);
  // A Horner move on the same axis is "running" too.
  axis->write_commands(command::kClearErrors, now);
  axis->write_commands(0, now);
  axis->words().destination = 100;
  axis->write_commands(command::kMoveRelative, now);
  axis->write_commands(0, now);
  EXPECT_EQ(done(), -2);
  EXPECT_EQ(ch->move(5, false, true, now), Error::AccessoryBusy);
}

TEST_F(HpChannel, AHornerStopEndsAnHpMoveAsAHalt) {
  ASSERT_EQ(ch->move(1000, false, true, now), Error::None);
  wait(500);
  axis->write_commands(command::kClearErrors, now);  // the Horner power-up error first
  axis->write_commands(command::kImmediateStop, now);
  EXPECT_EQ(done(), 1);
  EXPECT_FALSE(axis->core().busy());
}

// ---------------------------------------------------------------- WIDTH mode SUSTAIN (3-26)

// Appendix A in WIDTH mode: "Pulse Rate 10 kHz maximum" (a period of 100 us at least) and
// "Pulse Width 65.535 msec maximum, 1 usec resolution"; every bound.
TEST_F(HpChannel, AppendixAWidthModeBounds) {
  EXPECT_EQ(ch->profile(width(1e-6, 10e-6, 1e-6, 100e-6), now), Conflict::None);  // 10 kHz
  EXPECT_EQ(ch->profile(width(1e-6, 10e-6, 1e-6, 99.9e-6), now), Conflict::OutOfRange);
  EXPECT_EQ(ch->profile(width(1e-6, 10e-6, 1e-6, 10e-6), now), Conflict::OutOfRange);  // 100 kHz
  EXPECT_EQ(ch->profile(width(1e-6, 10e-3, 1e-6, 100e-3), now), Conflict::None);       // 10 Hz
  EXPECT_EQ(ch->profile(width(1e-6, 10e-3, 1e-6, 400'000), now), Conflict::None);      // 2.5 uHz
  EXPECT_EQ(ch->profile(width(1e-6, 10e-3, 1e-6, 400'001), now), Conflict::OutOfRange);
  EXPECT_EQ(ch->profile(width(1e-6, 65.535e-3, 1e-6, 100e-3), now), Conflict::None);  // widest
  EXPECT_EQ(ch->profile(width(1e-6, 65.536e-3, 1e-6, 100e-3), now), Conflict::OutOfRange);
  EXPECT_EQ(ch->profile(width(0.5e-6, 10e-6, 1e-6, 100e-6), now), Conflict::OutOfRange);  // < 1 us
  EXPECT_EQ(ch->profile(width(1e-6, 0.9e-6, 1e-6, 100e-6), now), Conflict::OutOfRange);
  EXPECT_EQ(ch->profile(width(0, 10e-6, 1e-6, 100e-6), now), Conflict::None);
  // A 100 ms period runs: 10 pulses a second.
  ASSERT_EQ(ch->profile(width(1e-3, 50e-3, 1, 100e-3), now), Conflict::None);
  ASSERT_EQ(ch->sustain(20e-3, true, now), Error::None);
  wait(500);
  int64_t p0 = position();
  wait(1000);
  EXPECT_EQ(position() - p0, 10);
}

TEST_F(HpChannel, WidthSustainRampsTheWidthAtAFixedPeriod) {
  // 3-28 example: PROFILE WIDTH 1E-3 10E-3 5E-3 20E-3, SUSTAIN 2E-3: 50 pulses/s, the width
  // ramps from 1 ms to 2 ms at 5 ms/s (0.2 s), then the interrupt.
  ASSERT_EQ(ch->profile(width(1e-3, 10e-3, 5e-3, 20e-3), now), Conflict::None);
  ch->enable_intr();
  ASSERT_EQ(ch->sustain(2e-3, true, now), Error::None);
  wait(100);
  EXPECT_NEAR(ch->current_width(), 1.5e-3, 0.05e-3);
  EXPECT_EQ(done(), -2);
  wait(200);
  EXPECT_EQ(done(), -1);
  ASSERT_EQ(interrupts.size(), 1u);
  EXPECT_EQ(interrupts[0].event, intr::kSustainReached);
  EXPECT_NEAR(to_ms(interrupts[0].at), 200, 0.01);
  int64_t p0 = position();
  wait(1000);
  EXPECT_EQ(position() - p0, 50);  // the period is the profile's
  // SUSTAIN 0: the width ramps down to min (0.2 s) and the pulses stop.
  ASSERT_EQ(ch->sustain(0, true, now), Error::None);
  wait(100);
  EXPECT_EQ(done(), -2);
  wait(200);
  EXPECT_EQ(done(), 0);
  int64_t p1 = position();
  wait(500);
  EXPECT_EQ(position(), p1);
}

// ---------------------------------------------------------------- PULSE (3-7)

TEST(HpPulse, StepDirectionAndStepStepOutputsAndSenses) {
  for (PulseMode mode : {PulseMode::StepDirection, PulseMode::StepStep})
    for (bool ps : {false, true})
      for (bool nd : {false, true}) {
        PulseSetup s{mode, ps, nd};
        for (int dir : {+1, -1}) {
          Pulse p = pulse_for(s, dir);
          EXPECT_EQ(direction_of(s, p), dir);
          if (mode == PulseMode::StepDirection) {
            EXPECT_EQ(p.output, Output::Pstp);  // "all pulses appear at the PSTPn output"
            EXPECT_EQ(p.pstp_level, ps);        // HI: low-high-low pulses
            EXPECT_EQ(p.ndir_level, dir > 0 ? nd : !nd);
          } else {
            EXPECT_EQ(p.output, dir > 0 ? Output::Pstp : Output::Ndir);
            if (dir > 0) EXPECT_EQ(p.pstp_level, ps);
            else EXPECT_EQ(p.ndir_level, nd);
          }
        }
      }
}

TEST_F(HpChannel, StepStepPulsesGoToPstpForwardAndNdirBackward) {
  ch->pulse(PulseSetup{PulseMode::StepStep, true, true});  // Figure 3-3: PULSE SS HI HI
  ASSERT_EQ(ch->move(10, false, true, now), Error::None);
  wait(1000);
  ASSERT_EQ(ch->move(-4, false, true, now), Error::None);
  wait(1000);
  EXPECT_EQ(ch->pulses(Output::Pstp), 10u);
  EXPECT_EQ(ch->pulses(Output::Ndir), 4u);
  EXPECT_EQ(position(), 6);
}

// A motor that keeps the output pulses it was given.
class PulseRecorder : public sim::AxisMachine {
 public:
  using sim::AxisMachine::AxisMachine;
  void output_pulse(Tick time, const OutputPulse& p) override {
    pulses.push_back(p);
    sim::AxisMachine::output_pulse(time, p);  // the driver decodes the direction
  }
  std::vector<OutputPulse> pulses;
};

TEST(HpPulseOutputs, TheMotorGetsTheOutputsAndFollowsTheirDirectionInBothModes) {
  for (PulseMode mode : {PulseMode::StepDirection, PulseMode::StepStep})
    for (bool ndir_high : {false, true}) {
      sim::AxisMachineConfig m;
      m.encoder = sim::EncoderKind::None;
      PulseRecorder motor(m);
      Axis axis(AxisConfig{}, {&motor});
      Channel ch(axis.core());
      ch.pulse(PulseSetup{mode, true, ndir_high});
      ASSERT_EQ(ch.move(7, false, true, 0), Error::None);
      ch.advance_to(kClockHz);
      ASSERT_EQ(ch.move(-3, false, true, kClockHz), Error::None);
      ch.advance_to(2 * kClockHz);
      ASSERT_EQ(motor.pulses.size(), 10u);
      EXPECT_EQ(motor.position(), 4) << "mode " << int(mode) << " ndir " << ndir_high;
      const OutputPulse& fwd = motor.pulses.front();
      const OutputPulse& back = motor.pulses.back();
      if (mode == PulseMode::StepDirection) {
        EXPECT_FALSE(fwd.on_ndir);
        EXPECT_FALSE(back.on_ndir);
        EXPECT_EQ(fwd.ndir_level, ndir_high);  // NDIR at its sense level for positive motion
        EXPECT_EQ(back.ndir_level, !ndir_high);
      } else {
        EXPECT_FALSE(fwd.on_ndir);
        EXPECT_TRUE(back.on_ndir);
      }
      // The position counter counts the engine's steps; here the wiring agrees with it.
      EXPECT_EQ(axis.motor_position(), 4);
    }
}

// ---------------------------------------------------------------- quadrature counter (3-20..3-22)

TEST_F(HpChannel, QscaleQindexSglAndOnce) {
  sim::AxisMachineConfig m = plain();
  m.encoder = sim::EncoderKind::Quadrature;  // 500 lines x4 / 2000 steps: one count per step
  m.marker_offset = 50;
  build(m);
  ASSERT_EQ(ch->move(20, false, true, now), Error::None);
  wait(1000);
  EXPECT_EQ(ch->quadrature_count(), 20);
  ch->qscale(0.5);
  EXPECT_DOUBLE_EQ(ch->qpos_query(), 10.0);
  ch->qindex(QIndexMode::Sgl);  // reset now, count at once, back to OFF
  EXPECT_EQ(ch->qindex_mode(), QIndexMode::Off);
  EXPECT_EQ(ch->quadrature_count(), 0);
  ASSERT_EQ(ch->move(-5, false, true, now), Error::None);
  wait(1000);
  EXPECT_EQ(ch->quadrature_count(), -5);
  // ONCE: reset; counting starts at the index pulse (marker at 50), later ones ignored.
  ch->qindex(QIndexMode::Once);
  ASSERT_EQ(ch->move(45, false, true, now), Error::None);  // 15 -> 60
  wait(2000);
  EXPECT_EQ(position(), 60);
  EXPECT_EQ(ch->quadrature_count(), 10);
  ASSERT_EQ(ch->move(2000, false, true, now), Error::None);  // through the next marker
  wait(20000);
  EXPECT_EQ(ch->quadrature_count(), 2010);
}

// QINDEX ONCE (3-21): "The quadrature counter is reset when the command is executed but the
// counter does not begin counting until the first index pulse is received"; "Indexing can be
// turned off with the OFF option". OFF before any index pulse: the counter holds what it
// counted (nothing; it showed the 30 counts it never counted) and counts from there on, as
// with indexing OFF since power-on.
TEST_F(HpChannel, QindexOnceThenOffBeforeTheIndexKeepsNoCountsItDidNotCount) {
  sim::AxisMachineConfig m = plain();
  m.encoder = sim::EncoderKind::Quadrature;  // one count per step
  m.marker_offset = 1000;                    // no index pulse near 0
  build(m);
  ch->qindex(QIndexMode::Once);
  ASSERT_EQ(ch->move(30, false, true, now), Error::None);
  wait(2000);
  ASSERT_EQ(position(), 30);
  ASSERT_EQ(ch->quadrature_count(), 0);  // not counting yet
  ch->qindex(QIndexMode::Off);
  EXPECT_EQ(ch->qindex_mode(), QIndexMode::Off);
  EXPECT_EQ(ch->quadrature_count(), 0);
  EXPECT_DOUBLE_EQ(ch->qpos_query(), 0.0);
  ASSERT_EQ(ch->move(-10, false, true, now), Error::None);
  wait(2000);
  EXPECT_EQ(ch->quadrature_count(), -10);
}

TEST_F(HpChannel, QuadratureCounterRollsOverAt32Bits) {
  sim::AxisMachineConfig m = plain();
  m.encoder = sim::EncoderKind::Quadrature;
  build(m);
  motor->displace(2'147'483'647);
  EXPECT_EQ(ch->quadrature_count(), 2'147'483'647);
  ASSERT_EQ(ch->move(1, false, true, now), Error::None);
  wait(1000);
  EXPECT_EQ(ch->quadrature_count(), -2'147'483'647 - 1);
}

}  // namespace
}  // namespace stepnode::motion::hp
