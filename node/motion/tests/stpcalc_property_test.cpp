// The engine against STPCALC (SPM30 Appendix B) on thousands of random legal parameter
// sets: trapezoidal moves within +-1 pulse and +-1 ms of every B1.3 value; triangular
// moves hit the total exactly, split the pulses Z_A:Z_D, and turn where the ramps meet
// (halfway with equal ramps, SPM30 3.4.5), or with the option never pass STPCALC's peak.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "node/motion/step_generator.hpp"
#include "node/motion/stpcalc.hpp"

namespace stepnode::motion {
namespace {

struct MoveRun {
  StepGenerator::Marks marks;
  int64_t steps = 0;
  Tick last = 0;
};

MoveRun run_move(const RampSpec& ramp, int64_t total) {
  StepGenerator g;
  g.start(ramp, 0, +1, total);
  MoveRun r;
  Step s;
  Tick previous = -1;
  while (g.next(s)) {
    EXPECT_GT(s.time, previous) << "step times must increase";
    previous = s.time;
    ++r.steps;
  }
  r.marks = g.marks();
  r.last = previous;
  return r;
}

StpcalcInput random_input(std::mt19937_64& rng) {
  auto pick = [&](int64_t lo, int64_t hi) {
    return std::uniform_int_distribution<int64_t>(lo, hi)(rng);
  };
  StpcalcInput in;
  static const int64_t divisors[] = {20, 60, 120, 300, 600, 1200};
  in.aq3 = pick(0, 3) == 0 ? pick(20, 65535) : divisors[pick(0, 5)];
  in.aq4 = pick(1, 2000);
  in.aq5 = pick(in.aq4 + 1, std::min<int64_t>(8191, in.aq4 + pick(1, 6000)));
  int64_t max_ms = horner_max_ramp_ms(in.aq4, in.aq5);
  if (max_ms < 1) max_ms = 1;
  in.aq6 = pick(1, std::min<int64_t>(max_ms, 2000));
  in.aq7 = pick(0, 2) == 0 ? 0 : pick(1, std::min<int64_t>(max_ms, 2000));
  return in;
}

TEST(StpcalcProperty, TrapezoidalMovesMatchAppendixBWithinOnePulseAndOneMs) {
  std::mt19937_64 rng(20261123);
  int checked = 0;
  while (checked < 3000) {
    StpcalcInput in = random_input(rng);
    StpcalcResult ramp_only = stpcalc(in);
    if (ramp_only.total_acc_dec_pulses > 150'000) continue;  // keep the suite quick
    int64_t extra = std::uniform_int_distribution<int64_t>(2, 20'000)(rng);
    in.total = static_cast<int64_t>(std::ceil(ramp_only.total_acc_dec_pulses)) + extra;
    StpcalcResult want = stpcalc(in);
    ASSERT_FALSE(want.triangular);
    RampSpec ramp = horner_ramp(in.aq3, in.aq4, in.aq5, in.aq6, in.aq7);
    MoveRun got = run_move(ramp, *in.total);
    const auto& m = got.marks;
    SCOPED_TRACE(testing::Message()
                 << "total " << *in.total << " AQ3 " << in.aq3 << " AQ4 " << in.aq4 << " AQ5 "
                 << in.aq5 << " AQ6 " << in.aq6 << " AQ7 " << in.aq7);
    ASSERT_EQ(got.steps, *in.total);
    EXPECT_NEAR(m.accel_steps, want.acceleration_pulses, 1.0);
    EXPECT_NEAR(m.decel_steps + m.creep_steps, want.deceleration_pulses, 1.0);
    EXPECT_NEAR(m.run_steps, want.running_pulses, 1.0);
    EXPECT_NEAR(ticks_to_ms(m.run_start - m.start), want.acceleration_time_ms, 1.0);
    EXPECT_NEAR(ticks_to_ms(m.decel_start - m.run_start), want.running_time_ms, 1.0);
    EXPECT_NEAR(ticks_to_ms(m.end - m.decel_start), want.deceleration_time_ms, 1.0);
    EXPECT_NEAR(ticks_to_ms(m.end - m.start), want.total_time_ms, 1.0);
    EXPECT_EQ(m.peak_level, in.aq5);
    if (HasFailure()) return;
    ++checked;
  }
}

TEST(StpcalcProperty, TriangularMovesHitTheTotalSplitAsTheManualAndTurnWhereTheRampsMeet) {
  std::mt19937_64 rng(7);
  int checked = 0;
  while (checked < 4000) {
    const bool stpcalc_peak = checked % 2 == 1;  // the axis option, every other move
    StpcalcInput in = random_input(rng);
    StpcalcResult ramp_only = stpcalc(in);
    if (ramp_only.total_acc_dec_pulses < 20 || ramp_only.total_acc_dec_pulses > 150'000) continue;
    in.total = std::uniform_int_distribution<int64_t>(
        1, static_cast<int64_t>(ramp_only.total_acc_dec_pulses) - 1)(rng);
    StpcalcResult want = stpcalc(in);
    if (!want.triangular) continue;
    RampSpec ramp = horner_ramp(in.aq3, in.aq4, in.aq5, in.aq6, in.aq7);
    if (stpcalc_peak) ramp.short_move = RampSpec::ShortMove::StpcalcPeak;
    MoveRun got = run_move(ramp, *in.total);
    const auto& m = got.marks;
    SCOPED_TRACE(testing::Message() << "total " << *in.total << " AQ3 " << in.aq3 << " AQ4 "
                                    << in.aq4 << " AQ5 " << in.aq5 << " AQ6 " << in.aq6 << " AQ7 "
                                    << in.aq7 << (stpcalc_peak ? " STPCALC peak" : ""));
    ASSERT_EQ(got.steps, *in.total);
    if (stpcalc_peak) {
      // Never faster than STPCALC's peak velocity (B1.3.6).
      EXPECT_LE(ramp.velocity_of(m.peak_level), want.peak_velocity + 1e-9);
    } else {
      // The turn: the ramps up to the peak and down from it take the move's pulses, to
      // within one velocity level (SPM30 3.4.5: no cruising, from halfway with equal ramps).
      auto pulses = [&](int64_t level) {
        return static_cast<double>(ramp.accel_phase(level) + ramp.decel_phase(level)) /
               static_cast<double>(ramp.phase_per_step);
      };
      const double total = static_cast<double>(*in.total);
      if (m.peak_level > in.aq4) {
        EXPECT_LE(pulses(m.peak_level), total);
      }
      EXPECT_GT(pulses(m.peak_level + 1), total);
      EXPECT_LE(static_cast<double>(m.run_steps),
                pulses(m.peak_level + 1) - pulses(m.peak_level) + 1);
    }
    // Acceleration and deceleration pulses in the manual's proportion Z_A : Z_D (B1.3.8),
    // to within the pulses of one velocity level.
    double ramp_steps = static_cast<double>(m.accel_steps + m.decel_steps + m.creep_steps);
    double level_pulses = ramp.velocity_of(m.peak_level) *
                          static_cast<double>(std::max(want.z_a, want.z_d)) / kClockHz;
    EXPECT_NEAR(static_cast<double>(m.accel_steps) * static_cast<double>(want.z_a + want.z_d),
                ramp_steps * static_cast<double>(want.z_a),
                (level_pulses + 2) * static_cast<double>(want.z_a + want.z_d));
    if (HasFailure()) return;
    ++checked;
  }
}

}  // namespace
}  // namespace stepnode::motion
