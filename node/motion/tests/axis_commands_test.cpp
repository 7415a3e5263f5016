// The axis's command bits, error latch and moves against the manuals, in virtual time:
// power-up, Clear Errors and the error interlock, edge sensitivity and priority, jog, move
// relative/absolute and their words, set position, the stops, resume and repeat, and the
// profile timings against STPCALC. Sections: SPM30 = HE693STP manual (chapters 3-4,
// appendix B), STP100 = HE800STP100 manual (chapters 4-5).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "node/motion/stpcalc.hpp"
#include "node/motion/tests/axis_harness.hpp"

namespace stepnode::motion {
namespace {

using harness::ms;

// One axis on a simulated machine (no encoder, no switches unless a test adds them).
class AxisCommands : public harness::AxisHarness {
 protected:
  // Every step until the axis stands still (or `limit` ms pass), with the status after it.
  struct Sample {
    Tick t;
    int32_t position;
    uint16_t status;
    double velocity;
  };
  std::vector<Sample> walk(double limit = 60000) {
    std::vector<Sample> out;
    Tick end = now + ms(limit);
    while (now < end && any(status::kMoving)) {
      auto next = axis->next_step_time();
      at(next ? std::min(*next, end) : std::min(now + ms(0.1), end));
      out.push_back({now, axis->motor_position(), axis->status(), axis->velocity()});
    }
    return out;
  }
  // Step by step until the mechanical position is `p`.
  bool walk_until_position(int64_t p, double limit = 60000) {
    Tick end = now + ms(limit);
    while (now < end && mech() != p) {
      auto next = axis->next_step_time();
      at(next ? std::min(*next, end) : std::min(now + ms(0.1), end));
    }
    return mech() == p;
  }
  // The first sample with or without `bit`, from `from`.
  static Tick first(const std::vector<Sample>& s, uint16_t bit, bool on, Tick from = 0) {
    for (const auto& x : s)
      if (x.t >= from && ((x.status & bit) != 0) == on) return x.t;
    return -1;
  }
};

// ---- SPM30 3.1 / STP100 4.2.1: power-up ----------------------------------------------------

TEST_F(AxisCommands, Spm30_3_1_PowerUpEveryBitOffButWatchdogPositionZeroInvalid) {
  EXPECT_EQ(axis->status(), status::kPowerUp);  // only %I8
  EXPECT_EQ(axis->motor_position(), 0);         // SPM30 3.3.1: zero and invalid
  EXPECT_EQ(axis->encoder_position(), 0);       // SPM30 3.3.2
  EXPECT_FALSE(has(status::kPositionValid));
  EXPECT_EQ(axis->selected_motor(), 0u);  // SPM30 4 SELECT AXIS: axis 1 by default
}

TEST_F(AxisCommands, Spm30_3_2_WatchdogInterlockClearErrorsMustBeFirst) {
  // Every command but Clear Errors is refused while %I8 is on.
  for (uint16_t bit : {command::kFindHomeUp, command::kFindHomeDown, command::kJogUp,
                       command::kJogDown, command::kMoveRelative, command::kResumeMove,
                       command::kMoveIndexed, command::kSetPosition}) {
    axis->words().destination = 500;
    issue(bit);
    wait(100);
    EXPECT_EQ(axis->status(), status::kPowerUp) << bit;
    EXPECT_EQ(mech(), 0) << bit;
    EXPECT_EQ(axis->motor_position(), 0) << bit;
  }
  clear();
  EXPECT_EQ(axis->status(), 0);
  move_rel(200);
  wait(3000);
  EXPECT_EQ(mech(), 200);
}

TEST_F(AxisCommands, Spm30_3_1_PowerUpAgainIsAWatchdogReset) {
  clear();
  set_position(40);
  move_rel(5000);
  wait(1000);
  ASSERT_TRUE(has(status::kMoving));
  int64_t where = mech();
  axis->power_up(now);  // watchdog / NMT reset
  EXPECT_EQ(axis->status(), status::kPowerUp);
  EXPECT_EQ(axis->motor_position(), 0);
  wait(1000);
  EXPECT_EQ(mech(), where);  // stopped at once
}

// ---- SPM30 3.1 / STP100 5.2: error latch ----------------------------------------------------

TEST_F(AxisCommands, Spm30_3_1_ErrorLatchesAndOnlyClearErrorsIsObeyed) {
  clear();
  set_position(100);
  issue(command::kClearErrors);
  axis->words().destination = 8'388'608;  // out of range: Illegal Move (SPM30 3.4)
  issue(command::kMoveRelative);
  ASSERT_EQ(errors(), status::kIllegalMove);
  EXPECT_EQ(events.back().kind, AxisEvent::Error);
  EXPECT_EQ(events.back().error_bits, status::kIllegalMove);
  // Ignored while latched: moves, jogs, home, set position, select, stops.
  axis->words().destination = 300;
  for (uint16_t bit : {command::kMoveRelative, command::kMoveAbsolute, command::kJogUp,
                       command::kFindHomeUp, command::kSetPosition, command::kSelectAxis1,
                       command::kDecelStop, command::kImmediateStop}) {
    issue(bit);
    wait(50);
    EXPECT_EQ(errors(), status::kIllegalMove) << bit;
    EXPECT_FALSE(any(status::kMoving)) << bit;
  }
  EXPECT_EQ(axis->motor_position(), 100);    // Set Position was refused too
  EXPECT_TRUE(has(status::kPositionValid));  // %I9..%I16 unaffected by the error (3.1)
  wait(1000);
  EXPECT_EQ(errors(), status::kIllegalMove);  // stays latched with time
  clear();
  EXPECT_EQ(errors(), 0);
  EXPECT_TRUE(has(status::kPositionValid));  // Clear Errors leaves %I9..%I16 alone
  move_rel(300);
  wait(3000);
  EXPECT_EQ(axis->motor_position(), 400);
  EXPECT_EQ(mech(), 300);
}

// ---- SPM30 3.2 / STP100 4.2.4: edges and priority -------------------------------------------

TEST_F(AxisCommands, Spm30_3_2_CommandsActOnTheOffToOnEdgeOnly) {
  clear();
  axis->words().destination = 250;
  hold(command::kMoveRelative);  // rises: one move
  wait(3000);
  EXPECT_EQ(mech(), 250);
  wait(3000);  // still on: no second move
  write(held);
  wait(3000);
  EXPECT_EQ(mech(), 250);
  hold(0);
  hold(command::kMoveRelative);  // off, on again: a new edge
  wait(3000);
  EXPECT_EQ(mech(), 500);
}

TEST_F(AxisCommands, Spm30_3_2_HighestCommandBitWinsWhenSeveralRiseTogether) {
  clear();
  set_position(200);
  // %Q9 beats %Q8: an absolute move to 500 (a relative one would end at 700).
  axis->words().destination = 500;
  issue(command::kMoveRelative | command::kMoveAbsolute);
  wait(5000);
  EXPECT_EQ(axis->motor_position(), 500);
  EXPECT_EQ(mech(), 300);
  // %Q13 beats %Q8: the position is set, nothing moves.
  axis->words().destination = 777;
  issue(command::kMoveRelative | command::kSetPosition);
  wait(2000);
  EXPECT_EQ(axis->motor_position(), 777);
  EXPECT_EQ(mech(), 300);
  // %Q7 beats %Q6: jogs down.
  hold(command::kJogUp | command::kJogDown);
  wait(300);
  EXPECT_LT(mech(), 300);
  hold(command::kJogUp);  // %Q7 released: the jog down ramps to a stop (%Q6 did not rise)
  wait(2000);
  EXPECT_FALSE(any(status::kMoving));
  hold(0);
  // %Q16 beats %Q15 while moving: stops at once and the position is no longer valid.
  set_position(0);
  move_rel(5000);
  wait(1000);
  issue(command::kDecelStop | command::kImmediateStop);
  EXPECT_FALSE(any(status::kMoving));
  EXPECT_FALSE(any(status::kPositionValid | status::kResumable));
  // With an error latched only %Q14 is legal, and it is obeyed even with a higher bit.
  move_abs(10);  // position invalid: Illegal Move
  ASSERT_EQ(errors(), status::kIllegalMove);
  axis->words().destination = 50;
  issue(command::kClearErrors | command::kMoveRelative);
  EXPECT_EQ(errors(), 0);
  wait(2000);
  EXPECT_FALSE(any(status::kMoving));  // %Q8 lost, not deferred
}

// SPM30 3.2: "more than one legal %Q goes from OFF to ON in the same CPU sweep, the one with
// the highest %Q number will be obeyed and the others will be ignored"; MOVE ABSOLUTE's
// "Status Bits Required: ... %I9 must be ON for %Q9 command". With %I9 off %Q9 is not a legal
// command: the %Q8 rising with it is obeyed and %Q9 ignored (no Illegal Move). Rising alone it
// is still the Illegal Move it always was (STP100 Table 4.2, %I4: "Previous commanded move was
// not possible").
TEST_F(AxisCommands, Spm30_3_2_MoveAbsoluteWithoutI9DoesNotOutrankAMoveRelative) {
  clear();
  ASSERT_FALSE(has(status::kPositionValid));  // not valid after power-up (3.1)
  axis->words().destination = 300;
  issue(command::kMoveRelative | command::kMoveAbsolute);
  EXPECT_EQ(errors(), 0);
  EXPECT_TRUE(has(status::kMoving));
  wait(5000);
  EXPECT_EQ(mech(), 300);
  issue(command::kMoveAbsolute);
  EXPECT_EQ(errors(), status::kIllegalMove);
  wait(1000);
  EXPECT_EQ(mech(), 300);
}

// SPM30 3.2 as above, with RESUME MOVE's "Status Bits Required: ... %I10 must be ON": with
// %I10 off the %Q8 rising with %Q10 is obeyed, and the highest *legal* one wins over several.
TEST_F(AxisCommands, Spm30_3_2_ResumeWithoutI10DoesNotOutrankAMoveRelative) {
  clear();
  ASSERT_FALSE(has(status::kResumable));
  axis->words().destination = 300;
  issue(command::kMoveRelative | command::kResumeMove);
  EXPECT_EQ(errors(), 0);
  wait(5000);
  EXPECT_EQ(mech(), 300);
  // %I9 on, %I10 off: of %Q8, %Q9 and %Q10 the absolute move is the highest legal one.
  set_position(0);
  axis->words().destination = 200;
  issue(command::kMoveRelative | command::kMoveAbsolute | command::kResumeMove);
  EXPECT_EQ(errors(), 0);
  wait(5000);
  EXPECT_EQ(axis->motor_position(), 200);
  EXPECT_EQ(mech(), 500);
  issue(command::kResumeMove);  // alone: Illegal Move
  EXPECT_EQ(errors(), status::kIllegalMove);
}

TEST_F(AxisCommands, Stp100_4_2_4_WhileMovingOnlyTheStopsAreObeyedAndIgnoredEdgesAreLost) {
  clear();
  set_position(0);
  move_rel(3000);
  wait(500);
  ASSERT_TRUE(has(status::kMoving));
  axis->words().destination = 9;
  for (uint16_t bit : {command::kSetPosition, command::kMoveRelative, command::kMoveAbsolute,
                       command::kJogDown, command::kFindHomeDown, command::kResumeMove,
                       command::kMoveIndexed, command::kSelectAxis1, command::kClearErrors}) {
    issue(bit);
    EXPECT_TRUE(has(status::kMoving)) << bit;
    EXPECT_FALSE(any(status::kDecelerating)) << bit;
    EXPECT_EQ(errors(), 0) << bit;
  }
  wait(10000);
  EXPECT_EQ(axis->motor_position(), 3000);  // nothing else happened, then or later
  EXPECT_EQ(mech(), 3000);
  EXPECT_TRUE(has(status::kPositionValid));
}

// ---- SPM30 3.4 / STP100 4.2.3: command words ------------------------------------------------

TEST_F(AxisCommands, Spm30_3_4_1_DestinationOutsideTheModuleRangeIsAnIllegalMove) {
  clear();
  for (int32_t bad : {8'388'608, -8'388'609, 20'000'000, -20'000'000}) {
    move_rel(bad);
    EXPECT_EQ(errors(), status::kIllegalMove) << bad;
    EXPECT_FALSE(any(status::kMoving));
    clear();
  }
  set_position(0);
  move_abs(8'388'608);
  EXPECT_EQ(errors(), status::kIllegalMove);
  clear();
  // The extremes themselves are legal (the move starts).
  move_rel(-8'388'608);
  EXPECT_EQ(errors(), 0);
  EXPECT_TRUE(has(status::kMoving));
  issue(command::kImmediateStop);
  set_position(0);
  move_rel(8'388'607);
  EXPECT_EQ(errors(), 0);
  EXPECT_TRUE(has(status::kMoving));
  issue(command::kImmediateStop);
  EXPECT_EQ(mech(), 0);  // stopped in the same tick it started
}

TEST_F(AxisCommands, Spm30_3_4_1_OutOfRangeDestinationForSetPositionIsRefused) {
  clear();
  set_position(5);
  axis->words().destination = 8'388'608;
  issue(command::kSetPosition);
  EXPECT_EQ(errors(), status::kIllegalMove);
  EXPECT_EQ(axis->motor_position(), 5);
  clear();
  set_position(-8'388'608);  // the minimum is legal
  EXPECT_EQ(errors(), 0);
  EXPECT_EQ(axis->motor_position(), -8'388'608);
}

TEST_F(AxisCommands, Spm30_3_4_RampWordsOutsideTheirRangesAreIllegalMoves) {
  struct Bad {
    uint16_t aq3, aq4, aq5, aq6, aq7;
  };
  const Bad cases[] = {
      {19, 100, 1000, 500, 0},       // 3.4.2: divisor 20..65535
      {600, 0, 1000, 500, 0},        // 3.4.3: base 1..8190
      {600, 100, 100, 500, 0},       // 3.4.4: running must exceed base
      {600, 100, 99, 500, 0},        //
      {600, 100, 8192, 500, 0},      // 3.4.4: running 2..8191
      {600, 8191, 8191, 500, 0},     // base 8191 cannot be below any running velocity
      {600, 100, 1000, 0, 0},        // 3.4.5: acceleration 1..27300
      {600, 100, 1000, 27301, 0},    //
      {600, 100, 1000, 500, 27301},  // 3.4.6: deceleration 0..27300
  };
  clear();
  for (const Bad& b : cases) {
    CommandWords& w = axis->words();
    w.velocity_divisor = b.aq3;
    w.base_velocity = b.aq4;
    w.running_velocity = b.aq5;
    w.acceleration_ms = b.aq6;
    w.deceleration_ms = b.aq7;
    for (uint16_t bit :
         {command::kMoveRelative, command::kJogUp, command::kFindHomeUp, command::kMoveIndexed}) {
      w.destination = 100;
      issue(bit);
      EXPECT_EQ(errors(), status::kIllegalMove) << b.aq3 << " " << b.aq4 << " " << b.aq5 << " "
                                                << b.aq6 << " " << b.aq7 << " bit " << bit;
      EXPECT_FALSE(any(status::kMoving));
      clear();
    }
  }
  EXPECT_EQ(mech(), 0);
  // The range ends themselves are legal.
  CommandWords& w = axis->words();
  w.velocity_divisor = 20;
  w.base_velocity = 1;
  w.running_velocity = 8191;
  w.acceleration_ms = 27300;
  w.deceleration_ms = 1;
  move_rel(10);
  EXPECT_EQ(errors(), 0);
  wait(1000);
  EXPECT_EQ(mech(), 10);
}

// SPM30 3.4 table (AQ6 1..27300, AQ7 0..27,300), 3.4.5/3.4.6: (AQ5-AQ4)/0.3 is only the
// "maximum useful value", so a longer time is legal; the ramp takes the maximum useful time.
TEST_F(AxisCommands, Spm30_3_4_5_RampTimesAboveTheMaximumUsefulValueAreLegal) {
  clear();
  for (uint16_t accel : {3000, 3001, 27300}) {  // AQ5-AQ4 = 900: maximum useful 3000 ms
    CommandWords& w = axis->words();
    w.acceleration_ms = accel;
    w.deceleration_ms = accel == 3000 ? 0 : 27300;
    Tick start = now;
    move_rel(20000);
    auto trace = walk();
    EXPECT_EQ(errors(), 0) << accel;
    EXPECT_EQ(mech() % 20000, 0) << accel;
    const Tick running = first(trace, status::kAccelerating, false);
    EXPECT_NEAR(ticks_to_ms(running - start), 3000.0, 1.5)
        << accel;  // 900 levels of Z = 16384 ticks
    EXPECT_NEAR(ticks_to_ms(trace.back().t - first(trace, status::kDecelerating, true)), 3000.0,
                1.5)
        << accel;
  }
}

TEST_F(AxisCommands, Spm30_3_4_WordsMayChangeAsSoonAsTheMoveStarted) {
  clear();
  set_position(0);
  move_abs(4000);
  CommandWords& w = axis->words();
  w.destination = -50;  // prepared for the next move
  w.running_velocity = 101;
  w.acceleration_ms = 1;
  wait(1000);
  EXPECT_NEAR(axis->velocity(), 1000.0, 1e-9);  // still the running velocity it started with
  wait(10000);
  EXPECT_EQ(axis->motor_position(), 4000);
  EXPECT_EQ(mech(), 4000);
}

// ---- SPM30 4 JOG UP / JOG DOWN, STP100 5.3.3 -----------------------------------------------

TEST_F(AxisCommands, Spm30_4_Jog_RunsWhileHeldAtRunningVelocityThenRampsDown) {
  clear();
  set_position(0);
  hold(command::kJogUp);
  EXPECT_TRUE(has(status::kMoving | status::kAccelerating));
  EXPECT_TRUE(axis->dir_output_high());
  wait(2000);
  EXPECT_TRUE(has(status::kMoving));
  EXPECT_FALSE(any(status::kAccelerating | status::kDecelerating));
  EXPECT_NEAR(axis->velocity(), 1000.0, 1e-9);  // AQ5 * 600 / AQ3 (3.4.4)
  Tick released = now;
  int64_t released_at = mech();
  hold(0);
  EXPECT_TRUE(has(status::kMoving | status::kDecelerating));
  auto trace = walk();
  ASSERT_FALSE(trace.empty());
  EXPECT_FALSE(any(status::kMoving));
  // Ramps down in the deceleration time (AQ7 = 0: the acceleration time, 3.4.6).
  StpcalcResult calc =
      stpcalc({.total = std::nullopt, .aq3 = 600, .aq4 = 100, .aq5 = 1000, .aq6 = 500, .aq7 = 0});
  EXPECT_NEAR(ticks_to_ms(now - released), calc.deceleration_time_ms, 1.0);
  EXPECT_EQ(axis->motor_position(), mech());
  EXPECT_TRUE(has(status::kPositionValid));  // a ramped stop keeps the position
  // The ramp down covers STPCALC's deceleration pulses (B1.3.9), within a pulse.
  EXPECT_NEAR(static_cast<double>(mech() - released_at), calc.deceleration_pulses, 1.5);
}

TEST_F(AxisCommands, Spm30_4_Jog_ReleasedBeforeRunningVelocityIsTriangular) {
  clear();
  hold(command::kJogDown);
  EXPECT_FALSE(axis->dir_output_high());
  wait(200);  // the ramp to 1000 steps/s takes 500 ms
  EXPECT_TRUE(has(status::kAccelerating));
  double peak = axis->velocity();
  // 100 + 900 * 200/500 steps/s, within one velocity level.
  EXPECT_NEAR(peak, 460.0, 1.5);
  Tick released = now;
  hold(0);
  EXPECT_TRUE(has(status::kDecelerating));
  EXPECT_FALSE(any(status::kAccelerating));
  auto trace = walk();
  for (const auto& s : trace) EXPECT_LE(s.velocity, peak);
  // Same slope down as up: the deceleration takes as long as the acceleration did.
  EXPECT_NEAR(ticks_to_ms(now - released), 200.0, 1.0);
  EXPECT_FALSE(any(status::kMoving));
  EXPECT_LT(mech(), -50);
  EXPECT_EQ(axis->motor_position(), mech());
}

TEST_F(AxisCommands, Stp100_5_3_3_JogReleaseOfTheOtherDirectionDoesNotStopIt) {
  clear();
  hold(command::kJogUp);
  wait(300);
  hold(command::kJogUp | command::kJogDown);  // ignored while moving
  hold(command::kJogUp);                      // %Q7 falls: not this jog's bit
  wait(300);
  EXPECT_TRUE(has(status::kMoving));
  EXPECT_FALSE(any(status::kDecelerating));
  EXPECT_GT(mech(), 0);
  hold(0);
  wait(2000);
  EXPECT_FALSE(any(status::kMoving));
}

// ---- SPM30 4 MOVE RELATIVE / MOVE ABSOLUTE, STP100 5.3.4 -----------------------------------

TEST_F(AxisCommands, Spm30_4_MoveRelative_TrapezoidTimedAsStpcalc) {
  clear();
  set_position(1000);
  Tick start = now;
  move_rel(3000);
  EXPECT_TRUE(has(status::kMoving | status::kAccelerating));
  EXPECT_TRUE(axis->dir_output_high());
  auto trace = walk();
  ASSERT_FALSE(trace.empty());
  StpcalcResult calc =
      stpcalc({.total = 3000, .aq3 = 600, .aq4 = 100, .aq5 = 1000, .aq6 = 500, .aq7 = 0});
  ASSERT_FALSE(calc.triangular);
  Tick run = first(trace, status::kAccelerating, false);
  Tick decel = first(trace, status::kDecelerating, true);
  Tick end = trace.back().t;
  // Status after each step: a phase change shows at the next step (1 ms at 1000 steps/s).
  EXPECT_NEAR(ticks_to_ms(run - start), calc.acceleration_time_ms, 1.5);
  EXPECT_NEAR(ticks_to_ms(decel - run), calc.running_time_ms, 2.5);
  EXPECT_NEAR(ticks_to_ms(end - decel), calc.deceleration_time_ms, 1.5);
  EXPECT_NEAR(ticks_to_ms(end - start), calc.total_time_ms, 1.0);
  // Moving through the whole move, Accelerating then (neither) then Decelerating.
  for (const auto& s : trace) {
    if (s.t == end) break;
    EXPECT_TRUE(s.status & status::kMoving);
    EXPECT_FALSE((s.status & status::kAccelerating) && (s.status & status::kDecelerating));
    EXPECT_LE(s.velocity, 1000.0);
  }
  EXPECT_EQ(trace.back().status & status::kMoving, 0);
  EXPECT_EQ(axis->motor_position(), 4000);
  EXPECT_EQ(mech(), 3000);
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_TRUE(axis->dir_output_high());  // STP100 5.3.5: DIR unchanged at the end
  EXPECT_EQ(events.back().kind, AxisEvent::MoveDone);
}

TEST_F(AxisCommands, Spm30_4_MoveRelative_ShortMoveNeverPassesTheStpcalcPeak) {
  AxisConfig c;
  c.stpcalc_peak_short_moves = true;  // the option: STPCALC's figures (B1.3.6)
  build(c);
  clear();
  move_rel(-300);  // needs 550 pulses to reach the running velocity
  EXPECT_FALSE(axis->dir_output_high());
  auto trace = walk();
  StpcalcResult calc =
      stpcalc({.total = 300, .aq3 = 600, .aq4 = 100, .aq5 = 1000, .aq6 = 500, .aq7 = 0});
  ASSERT_TRUE(calc.triangular);
  double peak = 0;
  for (const auto& s : trace) peak = std::max(peak, s.velocity);
  EXPECT_LE(peak, calc.peak_velocity + 1e-9);  // B1.3.6
  EXPECT_LT(peak, 1000.0);                     // never the running velocity
  EXPECT_GT(first(trace, status::kDecelerating, true), 0);
  EXPECT_EQ(mech(), -300);
  EXPECT_EQ(axis->motor_position(), -300);
  EXPECT_FALSE(axis->dir_output_high());
}

// SPM30 3.4.5 and 4 MOVE RELATIVE: "If the move gets halfway to its relative target position
// before accelerating to the RUNNING VELOCITY, the SPM30 will start decelerating at that
// point ... the velocity profile becomes triangular." (STP100 1.7, 5.3.4 the same.)
TEST_F(AxisCommands, Spm30_3_4_5_ShortMoveTurnsAtHalfwayWithoutCruising) {
  clear();
  move_rel(300);
  auto trace = walk();
  int cruising = 0;
  for (const auto& s : trace)
    if ((s.status & status::kMoving) &&
        !(s.status & (status::kAccelerating | status::kDecelerating)))
      ++cruising;
  EXPECT_LE(cruising, 1);
  int32_t turn = -1;
  for (const auto& s : trace)
    if (s.status & status::kDecelerating) {
      turn = s.position;
      break;
    }
  EXPECT_NEAR(turn, 150, 2);  // decelerates from the halfway point
  EXPECT_EQ(mech(), 300);
  // The triangle at the manual's slopes (703 ms) is shorter than the STPCALC-peak option's
  // trapezoid (725 ms); STPCALC's own B1.3 figure (545 ms) scales pulses linearly with time.
  Tick halfway = trace.back().t - trace.front().t;
  AxisConfig c;
  c.stpcalc_peak_short_moves = true;
  build(c);
  clear();
  move_rel(300);
  auto capped = walk();
  EXPECT_LT(halfway, capped.back().t - capped.front().t);
}

TEST_F(AxisCommands, Spm30_3_4_6_SeparateDecelerationTimeAndZeroMeaningAcceleration) {
  clear();
  axis->words().deceleration_ms = 250;
  Tick start = now;
  move_rel(3000);
  auto trace = walk();
  StpcalcResult calc =
      stpcalc({.total = 3000, .aq3 = 600, .aq4 = 100, .aq5 = 1000, .aq6 = 500, .aq7 = 250});
  Tick decel = first(trace, status::kDecelerating, true);
  EXPECT_NEAR(ticks_to_ms(trace.back().t - decel), calc.deceleration_time_ms, 1.5);
  EXPECT_NEAR(ticks_to_ms(trace.back().t - start), calc.total_time_ms, 1.0);
  EXPECT_EQ(mech(), 3000);
}

TEST_F(AxisCommands, Spm30_3_4_2_VelocityResolutionScalesBaseAndRunning) {
  clear();
  CommandWords& w = axis->words();
  w.velocity_divisor = 20;    // 30 steps/s per unit
  w.base_velocity = 10;       // 300 steps/s
  w.running_velocity = 2000;  // 60,000 steps/s
  w.acceleration_ms = 100;
  move_rel(20000);
  EXPECT_NEAR(axis->velocity(), 330.0, 1e-9);  // first level above base
  wait(150);
  EXPECT_NEAR(axis->velocity(), 60000.0, 1e-6);
  wait(1000);
  EXPECT_EQ(mech(), 20000);
}

TEST_F(AxisCommands, Spm30_4_MoveAbsolute_NeedsAValidPositionAndGoesBothWays) {
  clear();
  move_abs(100);  // position invalid at power-up (3.3.1)
  EXPECT_EQ(errors(), status::kIllegalMove);
  EXPECT_EQ(mech(), 0);
  clear();
  set_position(1000);
  move_abs(400);  // down 600
  EXPECT_FALSE(axis->dir_output_high());
  wait(5000);
  EXPECT_EQ(axis->motor_position(), 400);
  EXPECT_EQ(mech(), -600);
  move_abs(1500);  // up 1100
  EXPECT_TRUE(axis->dir_output_high());
  wait(5000);
  EXPECT_EQ(axis->motor_position(), 1500);
  EXPECT_EQ(mech(), 500);
  size_t before = events.size();
  move_abs(1500);  // already there: done, no motion
  EXPECT_FALSE(any(status::kMoving));
  ASSERT_GT(events.size(), before);
  EXPECT_EQ(mech(), 500);
  // A relative move needs no valid position (3.3.1).
  issue(command::kDecelStop | command::kImmediateStop);
  move_rel(5000);
  wait(300);
  issue(command::kImmediateStop);
  ASSERT_FALSE(has(status::kPositionValid));
  move_rel(-20);
  EXPECT_EQ(errors(), 0);
  EXPECT_TRUE(has(status::kMoving));
}

// ---- SPM30 4 SET CURRENT POSITION, STP100 5.3.8 --------------------------------------------

TEST_F(AxisCommands, Spm30_4_SetCurrentPosition_LoadsMotorAndEncoderPositionNoMotion) {
  clear();
  set_position(-123'456);
  EXPECT_EQ(axis->motor_position(), -123'456);
  EXPECT_EQ(axis->encoder_position(), -123'456);  // no encoder: %AI3/4 match axis 1 (5.1)
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_FALSE(any(status::kMoving));
  wait(100);
  EXPECT_EQ(mech(), 0);
  move_rel(10);
  wait(1000);
  EXPECT_EQ(axis->motor_position(), -123'446);
  EXPECT_EQ(axis->encoder_position(), -123'446);
}

// ---- SPM30 4 IMMEDIATE STOP / DECELERATE AND STOP, STP100 5.3.9-10 --------------------------

TEST_F(AxisCommands, Spm30_4_ImmediateStop_HaltsAndInvalidatesOnlyIfMoving) {
  clear();
  set_position(0);
  issue(command::kImmediateStop);
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_EQ(errors(), 0);
  move_rel(5000);
  wait(700);
  ASSERT_TRUE(has(status::kMoving));
  issue(command::kImmediateStop);
  int32_t stopped = axis->motor_position();
  EXPECT_FALSE(any(status::kMoving | status::kAccelerating | status::kDecelerating));
  EXPECT_FALSE(has(status::kPositionValid));
  EXPECT_FALSE(has(status::kResumable));  // only Decelerate and Stop pre-empts resumably
  EXPECT_EQ(errors(), 0);                 // a command, not an error
  wait(2000);
  EXPECT_EQ(axis->motor_position(), stopped);
  EXPECT_EQ(mech(), stopped);
  // During a jog too.
  hold(command::kJogDown);
  wait(100);
  issue(command::kImmediateStop);
  EXPECT_FALSE(any(status::kMoving));
  hold(0);
}

TEST_F(AxisCommands, Spm30_4_DecelerateAndStop_RampsToBaseAndStopsKeepingPosition) {
  clear();
  set_position(0);
  move_rel(5000);
  wait(1500);
  ASSERT_FALSE(any(status::kAccelerating));
  Tick stop = now;
  issue(command::kDecelStop);
  EXPECT_TRUE(has(status::kDecelerating | status::kMoving));
  walk();
  StpcalcResult calc =
      stpcalc({.total = std::nullopt, .aq3 = 600, .aq4 = 100, .aq5 = 1000, .aq6 = 500, .aq7 = 0});
  EXPECT_NEAR(ticks_to_ms(now - stop), calc.deceleration_time_ms, 1.0);
  EXPECT_TRUE(has(status::kPositionValid));
  EXPECT_TRUE(has(status::kResumable));
  EXPECT_LT(mech(), 5000);
  EXPECT_EQ(axis->motor_position(), mech());
  // While standing still it does nothing (and the move stays... resumable only until a
  // command other than Resume: Decelerate and Stop is one).
  issue(command::kDecelStop);
  EXPECT_FALSE(any(status::kMoving));
}

// ---- SPM30 4 RESUME MOVE, STP100 5.3.7 -------------------------------------------------------

TEST_F(AxisCommands, Spm30_4_ResumeMove_PreemptedAnyNumberOfTimesUntilTheTarget) {
  clear();
  set_position(-500);
  move_abs(7000);  // 7500 steps up
  CommandWords& w = axis->words();
  w.destination = 0;  // changed words do not change the move being resumed
  w.running_velocity = 300;
  int64_t last = 0;
  for (int i = 0; i < 4; ++i) {
    wait(900);
    ASSERT_TRUE(has(status::kMoving)) << i;
    EXPECT_NEAR(axis->velocity(), 1000.0, 1e-9) << i;  // the original ramp, not the new words
    issue(command::kDecelStop);
    EXPECT_FALSE(has(status::kResumable)) << i;  // only once stopped
    walk();
    ASSERT_TRUE(has(status::kResumable)) << i;
    EXPECT_GT(mech(), last);
    EXPECT_LT(mech(), 7500);
    last = mech();
    wait(500);
    EXPECT_EQ(mech(), last);
    issue(command::kResumeMove);
    EXPECT_FALSE(has(status::kResumable)) << i;
    EXPECT_TRUE(has(status::kMoving | status::kAccelerating)) << i;
    EXPECT_TRUE(axis->dir_output_high());
  }
  wait(20000);
  EXPECT_EQ(axis->motor_position(), 7000);
  EXPECT_EQ(mech(), 7500);
  EXPECT_FALSE(has(status::kResumable));
  EXPECT_TRUE(has(status::kPositionValid));
  issue(command::kResumeMove);  // the target was reached: nothing to resume
  EXPECT_EQ(errors(), status::kIllegalMove);
  EXPECT_EQ(mech(), 7500);
}

TEST_F(AxisCommands, Spm30_4_ResumeMove_RelativeMoveDownResumesDown) {
  clear();
  move_rel(-2000);
  wait(800);
  issue(command::kDecelStop);
  walk();
  ASSERT_TRUE(has(status::kResumable));
  issue(command::kResumeMove);
  EXPECT_FALSE(axis->dir_output_high());
  wait(10000);
  EXPECT_EQ(mech(), -2000);
}

// RESUME MOVE (3): "Some command other than %Q10 is issued after the move is pre-empted".
// Select Axis is none of them on one motor: SELECT AXIS "(1) If requested new axis is the same
// as the old axis or is illegal, do nothing" (selecting another axis of a multiplexed one ends
// it: axis_multiplexed_test.cpp).
TEST_F(AxisCommands, Spm30_4_ResumeMove_LostOnAnyOtherCommand) {
  clear();
  for (uint16_t other : {command::kSetPosition, command::kDecelStop, command::kImmediateStop,
                         command::kClearErrors, command::kMoveRelative}) {
    set_position(0);
    move_rel(4000);
    wait(800);
    issue(command::kDecelStop);
    walk();
    ASSERT_TRUE(has(status::kResumable)) << other;
    axis->words().destination = 0;  // a zero move: completes at once
    issue(other);
    EXPECT_FALSE(has(status::kResumable)) << other;
    issue(command::kResumeMove);  // %I10 off: not resumable (Illegal Move)
    EXPECT_EQ(errors(), status::kIllegalMove) << other;
    EXPECT_FALSE(any(status::kMoving));
    clear();
  }
}

TEST_F(AxisCommands, Spm30_4_ResumeMove_LostOnAnError) {
  clear();
  // A limit error during the resumed part ends it.
  sim::AxisMachineConfig m = plain();
  m.upper_limit = 3000;
  build({}, m);
  clear();
  move_rel(5000);
  wait(800);
  issue(command::kDecelStop);
  walk();
  ASSERT_TRUE(has(status::kResumable));
  issue(command::kResumeMove);
  wait(10000);
  EXPECT_EQ(errors(), status::kUpperLimit);
  EXPECT_EQ(mech(), 3000);
  EXPECT_FALSE(has(status::kResumable));
  clear();
  issue(command::kResumeMove);
  EXPECT_EQ(errors(), status::kIllegalMove);
  // The master lost while pre-empted (STP100: the watchdog error) ends it too.
  build({}, plain());
  clear();
  move_rel(5000);
  wait(800);
  issue(command::kDecelStop);
  walk();
  ASSERT_TRUE(has(status::kResumable));
  axis->master_lost(now);
  EXPECT_FALSE(has(status::kResumable));
  // A move pre-empted by an error is never resumable (DECELERATE AND STOP: "unless an
  // error occurred").
  build({}, plain());
  clear();
  move_rel(5000);
  wait(800);
  issue(command::kDecelStop);
  axis->master_lost(now);  // during the ramp down
  walk();
  EXPECT_FALSE(has(status::kResumable));
}

TEST_F(AxisCommands, Spm30_4_DecelerateAndStop_OfAJogOrHomeIsNotResumable) {
  clear();
  hold(command::kJogUp);
  wait(800);
  issue(command::kDecelStop);  // %Q15 while jogging (the bit is still held)
  walk();
  EXPECT_FALSE(any(status::kMoving));
  EXPECT_FALSE(has(status::kResumable));
  hold(0);
}

// ---- STP100 5.3.6 REPEAT MOVE ----------------------------------------------------------------

TEST_F(AxisCommands, Stp100_5_3_6_RepeatMove_RelativeRepeatsBackToBackWhileQ12IsOn) {
  clear();
  set_position(0);
  hold(command::kRepeatMove);
  Tick start = now;
  move_rel(600);
  StpcalcResult calc =
      stpcalc({.total = 600, .aq3 = 600, .aq4 = 100, .aq5 = 1000, .aq6 = 500, .aq7 = 0});
  // Each move ends and the next starts at once: after k moves the time is k * total time.
  for (int k = 1; k <= 4; ++k) {
    ASSERT_TRUE(walk_until_position(600 * k)) << k;
    EXPECT_NEAR(ticks_to_ms(now - start), k * calc.total_time_ms, 1.0 * k) << k;
    wait(0.01);
    EXPECT_TRUE(has(status::kMoving)) << k;  // the next one already running
  }
  hold(0);  // off during the 5th move: it completes, no more
  wait(10000);
  EXPECT_EQ(mech(), 3000);
  EXPECT_EQ(axis->motor_position(), 3000);
  EXPECT_FALSE(any(status::kMoving));
}

TEST_F(AxisCommands, Stp100_5_3_6_RepeatMove_NotForAbsoluteMovesNorAfterAStop) {
  clear();
  set_position(0);
  hold(command::kRepeatMove);
  move_abs(500);
  wait(5000);
  EXPECT_EQ(mech(), 500);
  EXPECT_FALSE(any(status::kMoving));
  // Q12 rising alone is no command.
  hold(0);
  hold(command::kRepeatMove);
  wait(1000);
  EXPECT_EQ(mech(), 500);
  // A relative move stopped by %Q15 is not repeated (it did not complete normally).
  move_rel(3000);
  wait(800);
  issue(command::kDecelStop);
  wait(3000);
  EXPECT_FALSE(any(status::kMoving));
  EXPECT_LT(mech(), 3500);
  EXPECT_TRUE(has(status::kResumable));
  hold(0);
}

}  // namespace
}  // namespace stepnode::motion
