// The jerk-limited profile (6086h = 3) against the closed form of an S-curve: the position
// per phase of constant jerk is p = p0 + v0 t + a0 t^2/2 + j t^3/6. Each step n must fall
// on the first tick at which that position reaches n, to within one tick.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "node/motion/ramp.hpp"
#include "node/motion/step_generator.hpp"

namespace stepnode::motion {
namespace {

using Real = long double;

// A profile given as phases of constant jerk (steps/s^3, seconds), from standstill.
struct Phase {
  Real jerk, seconds;
};

Real position(const std::vector<Phase>& phases, Real t) {
  Real p = 0, v = 0, a = 0;
  for (const Phase& ph : phases) {
    const Real d = std::min(t, ph.seconds);
    p += v * d + a * d * d / 2 + ph.jerk * d * d * d / 6;
    v += a * d + ph.jerk * d * d / 2;
    a += ph.jerk * d;
    t -= d;
    if (t <= 0) break;
  }
  return p + v * std::max<Real>(t, 0);
}

// The tick at which the closed form reaches step n (bisection on the time, then the tick).
Tick closed_form_tick(const std::vector<Phase>& phases, Real total, int64_t n) {
  Real lo = 0, hi = total;
  for (int i = 0; i < 200; ++i) {
    const Real mid = (lo + hi) / 2;
    // The tolerance is the long double's rounding: near the end p = n - j (T - t)^3 / 6,
    // so a coarser one would move the last step by ticks.
    (position(phases, mid) >= static_cast<Real>(n) - 1e-16L ? hi : lo) = mid;
  }
  return static_cast<Tick>(std::ceil(hi * kClockHz - 1e-6L));
}

RampSpec s_curve(int64_t v, int64_t a, int64_t d, uint32_t jerk) {
  RampSpec r = profile_ramp(v, a, d, profile_levels_per_hz(std::max(a, d)));
  r.s_curve = true;
  for (uint32_t& j : r.jerk) j = jerk;
  return r;
}

std::vector<Tick> run(const RampSpec& r, int64_t distance) {
  StepGenerator g;
  g.start(r, 0, +1, distance);
  std::vector<Tick> ticks;
  Step s;
  while (g.next(s)) ticks.push_back(s.time);
  return ticks;
}

void expect_closed_form(const std::vector<Tick>& got, const std::vector<Phase>& phases,
                        int64_t distance) {
  Real total = 0;
  for (const Phase& p : phases) total += p.seconds;
  ASSERT_EQ(got.size(), static_cast<size_t>(distance));
  for (int64_t n = 1; n <= distance; ++n)
    EXPECT_NEAR(got[n - 1], closed_form_tick(phases, total, n), 1) << "step " << n;
  // Total move time: the last step on the profile's end (v = 0 there).
  EXPECT_NEAR(got.back(), static_cast<Tick>(std::llround(total * kClockHz)), 1);
}

TEST(SCurve, SevenPhasesMatchTheClosedForm) {
  // 1000 steps/s, 10 000 steps/s^2, 1e6 steps/s^3: jerk phases of a/j = 10 ms, a constant
  // acceleration of (v - a^2/j)/a = 90 ms; each ramp covers v/2 (v/a + a/j) = 55 steps,
  // a 90-step cruise takes 90 ms. Every phase a whole number of ticks.
  const Real j = 1e6, a = 1e4;
  const std::vector<Phase> phases{{j, 0.01L},  {0, 0.09L}, {-j, 0.01L}, {0, 0.09L},
                                  {-j, 0.01L}, {0, 0.09L}, {j, 0.01L}};
  (void)a;
  expect_closed_form(run(s_curve(1000, 10'000, 10'000, 1'000'000), 200), phases, 200);
}

TEST(SCurve, ShortMoveReachesNeitherFullAccelerationNorVelocity) {
  // j = 512 000 steps/s^3, 250 steps: four jerk phases of 1/16 s (D = 2 j T^3), peak
  // velocity j T^2 = 2000 steps/s below 5000, peak acceleration j T = 32 000 below 50 000.
  const Real j = 512'000;
  const std::vector<Phase> phases{{j, 0.0625L}, {-j, 0.0625L}, {-j, 0.0625L}, {j, 0.0625L}};
  expect_closed_form(run(s_curve(5000, 50'000, 50'000, 512'000), 250), phases, 250);
}

TEST(SCurve, RampsAreSymmetric) {
  const std::vector<Tick> t = run(s_curve(2000, 20'000, 20'000, 400'000), 1000);
  ASSERT_EQ(t.size(), 1000u);
  // The time to the k-th step from the start equals the time from k steps before the target
  // to the end (equal ramps): position k is reached at t[k - 1], position n - k at t[n - k - 1].
  const size_t n = t.size();
  for (size_t k = 1; k < 200; ++k) EXPECT_NEAR(t[k - 1], t.back() - t[n - 1 - k], 2) << k;
}

TEST(SCurve, UnequalSlopesStillEndOnTheTarget) {
  // A ramp down at a third of the acceleration: the last step is at velocity ~0 (its gap is
  // the longest of the ramp down), the move exact in steps.
  const std::vector<Tick> t = run(s_curve(3000, 30'000, 10'000, 200'000), 5000);
  ASSERT_EQ(t.size(), 5000u);
  for (size_t k = 1; k < t.size(); ++k) ASSERT_GT(t[k], t[k - 1]);
  EXPECT_GT(t[4999] - t[4998], t[4000] - t[3999]);
}

TEST(SCurve, VelocityModeHoldsTheVelocityExactly) {
  StepGenerator g;
  g.start(s_curve(1000, 10'000, 10'000, 1'000'000), 0, -1, std::nullopt);
  Step s;
  std::vector<Tick> t;
  for (int i = 0; i < 400; ++i) {
    ASSERT_TRUE(g.next(s));
    EXPECT_EQ(s.direction, -1);
    t.push_back(s.time);
  }
  // After the ramp (55 steps) every gap is 1/1000 s = 4915.2 ticks (4915 or 4916).
  for (size_t k = 100; k < t.size(); ++k) EXPECT_NEAR(t[k] - t[k - 1], 4915.2, 1) << k;
  EXPECT_EQ(g.phase(), MotionPhase::Running);
  EXPECT_NEAR(g.velocity(), 1000, 1e-9);
  // Stop: the jerk-limited ramp down ends the motion (55 steps more from cruise, closed form).
  g.stop(t.back());
  int more = 0;
  while (g.next(s)) ++more;
  EXPECT_NEAR(more, 55, 1);
  EXPECT_FALSE(g.moving());
}

TEST(SCurve, RetargetWhileRunningEndsOnTheNewTarget) {
  StepGenerator g;
  g.start(s_curve(1000, 10'000, 10'000, 1'000'000), 0, +1, 1000);
  Step s;
  for (int i = 0; i < 300; ++i) ASSERT_TRUE(g.next(s));
  g.retarget(s.time, 200, g.ramp());  // 500 in all
  int64_t n = 300;
  Tick last = s.time, gap = 0;
  while (g.next(s)) {
    ++n;
    gap = s.time - last;
    last = s.time;
  }
  EXPECT_EQ(n, 500);
  EXPECT_GT(gap, 4 * 4915);  // the last step slow: the ramp down ended there
  // A higher velocity while running, then a lower one: the target holds.
  g.start(s_curve(1000, 10'000, 10'000, 1'000'000), 0, +1, 2000);
  for (int i = 0; i < 300; ++i) ASSERT_TRUE(g.next(s));
  g.change_velocity(s.time, 1500 * g.ramp().phase_per_step / kClockHz);
  for (int i = 0; i < 300; ++i) ASSERT_TRUE(g.next(s));
  EXPECT_GT(g.velocity(), 1000);
  n = 600;
  while (g.next(s)) ++n;
  EXPECT_EQ(n, 2000);
}

}  // namespace
}  // namespace stepnode::motion
