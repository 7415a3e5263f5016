// The engine's side of stepcalc: the velocity staircase is the move the generator made.
#include <gtest/gtest.h>

#include "tools/stepcalc/engine_profile.hpp"

namespace stepnode::tools {
namespace {

// Area under the staircase, in pulses: sum of velocity * duration.
double area_pulses(const Curve& c) {
  double pulses = 0;
  for (size_t i = 1; i < c.size(); ++i) {
    if (c[i].second == c[i - 1].second)
      pulses += c[i].second * (c[i].first - c[i - 1].first) / 1000.0;
  }
  return pulses;
}

// Every step falls on the first tick the phase reaches k*D, so the staircase's area is the
// number of steps plus less than one step of phase left over: [steps, steps + 1).
TEST(EngineProfile, StaircaseAreaIsTheStepsTaken) {
  for (motion::StpcalcInput in : {motion::StpcalcInput{10000, 600, 100, 1000, 500, 0},
                                  motion::StpcalcInput{300, 600, 100, 1000, 500, 250},
                                  motion::StpcalcInput{50, 600, 100, 1000, 500, 0},
                                  motion::StpcalcInput{1, 600, 100, 1000, 500, 0},
                                  motion::StpcalcInput{std::nullopt, 20, 1, 8191, 100, 0},
                                  motion::StpcalcInput{2'000'000, 20, 1, 8191, 100, 0},
                                  motion::StpcalcInput{123'457, 1200, 37, 5000, 900, 4000}}) {
    EngineProfile p = run_engine(in);
    SCOPED_TRACE(in.total ? *in.total : -1);
    if (in.total) {
      EXPECT_EQ(p.steps, *in.total);
    }
    double area = area_pulses(p.staircase);
    EXPECT_GE(area, static_cast<double>(p.steps) - 1e-6);
    EXPECT_LT(area, static_cast<double>(p.steps) + 1);
    // Starts and ends at standstill, time never runs backwards, never above the peak.
    ASSERT_GE(p.staircase.size(), 4u);
    EXPECT_EQ(p.staircase.front().second, 0.0);
    EXPECT_EQ(p.staircase.back().second, 0.0);
    EXPECT_DOUBLE_EQ(p.staircase.back().first, motion::ticks_to_ms(p.marks.end));
    for (size_t i = 1; i < p.staircase.size(); ++i) {
      EXPECT_GE(p.staircase[i].first, p.staircase[i - 1].first);
      EXPECT_LE(p.staircase[i].second, p.values.peak_velocity);
    }
  }
}

TEST(EngineProfile, OneIntervalPerVelocityLevelOnTheRamps) {
  // 900 levels up and 900 down, two corners each, plus the plateau, start and end.
  EngineProfile p = run_engine({10000, 600, 100, 1000, 500, 0});
  EXPECT_EQ(p.staircase.size(), 1u + 2 * 900 + 2 + 2 * 900 + 1);
  // The first ramp interval: level 101 (101 pulses/s) for Z_A = 2731 ticks.
  EXPECT_DOUBLE_EQ(p.staircase[1].second, 101.0);
  EXPECT_DOUBLE_EQ(p.staircase[2].first, motion::ticks_to_ms(2731));
}

}  // namespace
}  // namespace stepnode::tools
