#include <gtest/gtest.h>

#include "node/motion/step_generator.hpp"
#include "node/motion/stpcalc.hpp"

namespace stepnode::motion {
namespace {

// SPM30 3.4.2: the velocity-divisor table, exactly.
TEST(HornerRamp, VelocityDivisorTableOfSection342) {
  struct Row {
    int64_t aq3;
    double resolution, maximum;
  };
  for (Row r : {Row{20, 30.0, 245730.0}, Row{60, 10.0, 81910.0},
                Row{120, 5.0, 40955.0 /* printed 40,995.0: 5 x 8191 */}, Row{300, 2.0, 16382.0},
                Row{600, 1.0, 8191.0}, Row{1200, 0.5, 4095.5}}) {
    RampSpec ramp = horner_ramp(r.aq3, 1, 8191, 100, 0);
    EXPECT_DOUBLE_EQ(ramp.velocity_of(1), r.resolution) << "AQ3 " << r.aq3;
    EXPECT_DOUBLE_EQ(ramp.velocity_of(8191), r.maximum) << "AQ3 " << r.aq3;
    EXPECT_DOUBLE_EQ(r.resolution * 8191, r.maximum) << "the table's own arithmetic";
    EXPECT_DOUBLE_EQ(stpcalc({std::nullopt, r.aq3, 1, 8191, 100, 0}).velocity_resolution,
                     r.resolution);
  }
}

TEST(HornerRamp, ZaIsRoundedUpAndZeroDecelerationMeansAcceleration) {
  RampSpec r = horner_ramp(600, 100, 1100, 1000, 0);
  // 1000 * 24576 / (1000 * 5) = 4915.2 -> 4916 (B1.3.1)
  EXPECT_EQ(r.accel_ticks_per_level.num, 4916);
  EXPECT_EQ(r.decel_ticks_per_level.num, 4916);  // SPM30 3.4.6
  EXPECT_EQ(horner_ramp(600, 100, 1100, 1000, 500).decel_ticks_per_level.num, 2458);
}

TEST(HornerRamp, OutOfRangeRegistersAreRefusedWithTheirRange) {
  EXPECT_THROW(horner_ramp(19, 1, 2, 1, 0), std::invalid_argument);
  EXPECT_THROW(horner_ramp(600, 0, 2, 1, 0), std::invalid_argument);
  EXPECT_THROW(horner_ramp(600, 10, 10, 1, 0), std::invalid_argument);  // run must exceed base
  EXPECT_THROW(horner_ramp(600, 1, 8192, 1, 0), std::invalid_argument);
  EXPECT_NO_THROW(horner_ramp(600, 1, 301, 1001, 0));  // > (AQ5-AQ4)/0.3: legal, "maximum useful"
  EXPECT_EQ(horner_ramp(600, 1, 301, 27300, 27300).decel_ticks_per_level.num, kHornerMaxZ);
  try {
    horner_ramp(600, 1, 8191, 27301, 0);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("%AQ6"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("1..27300"), std::string::npos);
  }
}

// 245,730 steps/s is reachable (AQ3=20, AQ5=8191) and held exactly while running.
TEST(StepGenerator, RunsAtTheTopRateWithExactIntervals) {
  RampSpec ramp = horner_ramp(20, 1, 8191, 100, 0);
  StepGenerator g;
  g.start(ramp, 0, +1, 1'000'000);
  Step s;
  Tick first = -1, last = -1;
  int64_t counted = 0;
  while (g.next(s)) {
    if (g.marks().run_steps > counted) {  // this step was taken at the running velocity
      counted = g.marks().run_steps;
      if (first < 0) first = s.time;
      last = s.time;
    }
  }
  // n steps at level L span (n-1) * D / L ticks, to one tick (the accumulator's phase).
  double expected =
      static_cast<double>(counted - 1) * static_cast<double>(ramp.phase_per_step) / 8191.0;
  EXPECT_GT(counted, 900'000);
  EXPECT_NEAR(static_cast<double>(last - first), expected, 1.0);
  EXPECT_NEAR(ramp.velocity_of(8191), 245730.0, 1e-9);
}

TEST(StepGenerator, StopDeceleratesToBaseAndEnds) {
  RampSpec ramp = horner_ramp(600, 100, 1000, 200, 100);
  StepGenerator g;
  g.start(ramp, 0, -1, std::nullopt);  // jog down: no destination
  Step s;
  while (g.next(s) && g.phase() != MotionPhase::Running) EXPECT_EQ(s.direction, -1);
  for (int i = 0; i < 100; ++i) ASSERT_TRUE(g.next(s));
  g.stop(s.time);
  EXPECT_EQ(g.phase(), MotionPhase::Decelerating);
  Tick stop_at = s.time;
  int64_t after = 0;
  while (g.next(s)) ++after;
  EXPECT_FALSE(g.moving());
  // Decelerating from 1000 to 100 units at Z_D ticks per unit: STPCALC's time and pulses.
  StpcalcResult want = stpcalc({std::nullopt, 600, 100, 1000, 200, 100});
  EXPECT_NEAR(ticks_to_ms(g.marks().end - stop_at), want.deceleration_time_ms, 1.0);
  EXPECT_NEAR(static_cast<double>(after), want.deceleration_pulses, 1.0);
}

TEST(StepGenerator, HaltEndsAtOnceAndShortMovesAreExact) {
  RampSpec ramp = horner_ramp(600, 100, 1000, 200, 0);
  StepGenerator g;
  g.start(ramp, 0, +1, 50);
  Step s;
  ASSERT_TRUE(g.next(s));
  g.halt(s.time);
  EXPECT_FALSE(g.next(s));
  for (int64_t n : {1, 2, 3, 7, 100}) {
    g.start(ramp, 1000, +1, n);
    int64_t count = 0;
    while (g.next(s)) ++count;
    EXPECT_EQ(count, n);
  }
  g.start(ramp, 0, +1, 0);
  EXPECT_FALSE(g.next(s));
}

}  // namespace
}  // namespace stepnode::motion
