// stepcalc cia402: the engine's CiA 402 move beside the closed form of its profile. The
// expected figures are computed here from the profile's definition (CiA 402-2 6086h: a
// linear ramp is a trapezoid of slopes 6083h/6084h; the jerk-limited ramp rises with the
// 60A4h jerks), not from the engine.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "tools/stepcalc/cia402_profile.hpp"

namespace stepnode::tools {
namespace {

Cia402Move move(int64_t distance, uint32_t v, uint32_t a, uint32_t d, int16_t type = 0,
                uint32_t jerk = 0) {
  Cia402Move m;
  m.distance = distance;
  m.velocity = v;
  m.acceleration = a;
  m.deceleration = d;
  m.profile_type = type;
  for (auto& j : m.jerk) j = jerk;
  return m;
}

TEST(Cia402Calc, ATrapezoidTakesVOverAPlusTheCruisePlusVOverD) {
  // 4000 steps/s at 40,000 up and 20,000 down: 0.1 s (200 steps) + 0.2 s (400 steps) down,
  // the other 1400 steps at 4000 steps/s: 0.35 s. 0.65 s in all.
  const Cia402Report r = make_cia402_report(move(2000, 4000, 40'000, 20'000));
  ASSERT_TRUE(r.closed_form_time_ms);
  EXPECT_NEAR(*r.closed_form_time_ms, 650.0, 1e-6);
  EXPECT_NEAR(*r.closed_form_peak_velocity, 4000.0, 1e-6);
  EXPECT_EQ(r.steps, 2000);
  EXPECT_NEAR(r.engine_time_ms, 650.0, 1.0);  // the engine's levels are 1 step/s apart
  EXPECT_NEAR(r.peak_velocity, 4000.0, 4000.0 * 0.001);
}

TEST(Cia402Calc, AShortLinearMovePeaksWhereTheSlopesMeet) {
  // 100 steps at 40,000 both ways: the peak v with v^2/40000 = 100, 2000 steps/s, 0.1 s.
  const Cia402Report r = make_cia402_report(move(100, 4000, 40'000, 40'000));
  ASSERT_TRUE(r.closed_form_time_ms);
  EXPECT_NEAR(*r.closed_form_time_ms, 100.0, 1e-6);
  EXPECT_NEAR(*r.closed_form_peak_velocity, 2000.0, 2.0);  // sampled
  // The engine's staircase of 1-step/s levels turns on a level, not on the exact peak.
  EXPECT_NEAR(r.engine_time_ms, 100.0, 2.0);
}

TEST(Cia402Calc, AJerkLimitedMoveTakesTheJerkPhasesLonger) {
  // 4000 steps/s, 5000 steps/s^2, every jerk 10,000 steps/s^3: each ramp is 0.5 s of jerk,
  // 0.3 s at 5000, 0.5 s of jerk: V/A + A/J = 1.3 s over V * 1.3 / 2 = 2600 steps; 8000
  // steps cruise 2800 / 4000 = 0.7 s. 3.3 s in all.
  const Cia402Report r = make_cia402_report(move(8000, 4000, 5000, 5000, 3, 10'000));
  ASSERT_TRUE(r.closed_form_time_ms);
  EXPECT_NEAR(*r.closed_form_time_ms, 3300.0, 1e-6);
  EXPECT_NEAR(r.engine_time_ms, 3300.0, 0.01);
  // The engine puts every step on the first tick at which its cubic reaches it; its phases
  // are whole ticks long and the cruise joins a ramp planned back from the target, so the
  // steps may drift a little from the ideal profile (stepcalc prints by how much: 7.7 us
  // here), never by a millisecond tick.
  ASSERT_TRUE(r.max_step_deviation_us);
  EXPECT_LT(*r.max_step_deviation_us, 50.0);
  // Its trapezoid (6086h = 0) is 0.5 s shorter: the jerk phases add A/J.
  const Cia402Report t = make_cia402_report(move(8000, 4000, 5000, 5000, 0));
  EXPECT_NEAR(*t.closed_form_time_ms, 2800.0, 1e-6);
}

TEST(Cia402Calc, ZeroJerksAreNotLimitedTheTrapezoid) {
  const Cia402Report r = make_cia402_report(move(2000, 4000, 40'000, 20'000, 3, 0));
  EXPECT_NEAR(*r.closed_form_time_ms, 650.0, 1e-6);
}

TEST(Cia402Calc, AJerkLimitedMoveTooShortForTheVelocityHasNoClosedForm) {
  const Cia402Report r = make_cia402_report(move(100, 4000, 5000, 5000, 3, 10'000));
  EXPECT_FALSE(r.closed_form_time_ms);
  EXPECT_EQ(r.steps, 100);
  EXPECT_NE(cia402_text(r).find("no closed form"), std::string::npos);
}

TEST(Cia402Calc, RefusesWhatADriveWouldNotMove) {
  EXPECT_THROW(make_cia402_report(move(0, 4000, 1000, 1000)), std::invalid_argument);
  EXPECT_THROW(make_cia402_report(move(10, 0, 1000, 1000)), std::invalid_argument);
  EXPECT_THROW(make_cia402_report(move(10, 100, 0, 1000)), std::invalid_argument);
  EXPECT_THROW(make_cia402_report(move(10, 100, 1000, 1000, 1)), std::invalid_argument);
}

TEST(Cia402Calc, JsonAndPlotCarryBothSides) {
  const Cia402Report r = make_cia402_report(move(8000, 4000, 5000, 5000, 3, 10'000));
  const auto j = nlohmann::json::parse(cia402_json(r));
  EXPECT_NEAR(j["closed_form"]["time_ms"].get<double>(), 3300.0, 1e-6);
  EXPECT_EQ(j["engine"]["steps"], 8000);
  const std::string svg = render_svg(cia402_plot(r));
  EXPECT_NE(svg.find("<polyline id=\"closed-form\""), std::string::npos);
  EXPECT_NE(svg.find("<polyline id=\"engine\""), std::string::npos);
  EXPECT_NE(svg.find("steps/s"), std::string::npos);
}

}  // namespace
}  // namespace stepnode::tools
