// stepcalc against hand-calculated STPCALC values (SPM30 Appendix B) and its outputs.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "tools/stepcalc/profile_report.hpp"

namespace stepnode::tools {
namespace {

// TOTAL 10000, AQ3 600, AQ4 100, AQ5 1000, AQ6 500, AQ7 0 (= AQ6):
//   Z_A = ceil(500*24576 / (900*5)) = ceil(2730.67) = 2731           (B1.3.1)
//   Rate_A = 4915200*600 / (2731*600) = 1799.780 pulses/s^2
//   Pulse_A = 900*1101*2731 / (16384*600) = 275.284                  (B1.3.7)
//   Time_A = 900*2731*5/24576 = 500.061 ms                          (B1.3.11)
//   Pulse_R = 10000 - 2*275.284 = 9449.433; Time_R = 9449.433 ms at 1000 pulses/s
TEST(StepcalcReport, HandCalculatedTrapezoid) {
  ProfileReport r = make_report({10000, 600, 100, 1000, 500, 0});
  EXPECT_FALSE(r.triangular);
  EXPECT_NEAR(r.stpcalc.acceleration_rate, 1799.780, 1e-3);
  EXPECT_NEAR(r.stpcalc.acceleration_pulses, 275.284, 1e-3);
  EXPECT_NEAR(r.stpcalc.acceleration_time_ms, 500.061, 1e-3);
  EXPECT_NEAR(r.stpcalc.running_pulses, 9449.433, 1e-3);
  EXPECT_NEAR(r.stpcalc.running_time_ms, 9449.433, 1e-3);
  EXPECT_NEAR(r.stpcalc.total_time_ms, 10449.555, 1e-3);
  // The engine: within a pulse and a millisecond, and exactly the total.
  EXPECT_NEAR(r.engine.acceleration_pulses, 275.284, 1.0);
  EXPECT_DOUBLE_EQ(r.engine.acceleration_pulses + r.engine.running_pulses + r.engine.deceleration_pulses, 10000);
  EXPECT_NEAR(r.engine.total_time_ms, 10449.555, 1.0);
}

TEST(StepcalcReport, TextJsonAndSvg) {
  ProfileReport r = make_report({300, 600, 100, 1000, 500, 250});
  EXPECT_TRUE(r.triangular);
  EXPECT_LE(r.engine.peak_velocity, r.stpcalc.peak_velocity);
  std::string text = report_text(r);
  EXPECT_NE(text.find("Actual peak velocity ="), std::string::npos);
  EXPECT_NE(text.find("Actual total move time ="), std::string::npos);
  nlohmann::json j = nlohmann::json::parse(report_json(r));
  for (const char* key : {"acceleration_rate", "deceleration_rate", "velocity_resolution", "base_velocity",
                          "running_velocity", "peak_velocity", "acceleration_pulses", "running_pulses",
                          "deceleration_pulses", "acceleration_time_ms", "running_time_ms",
                          "deceleration_time_ms", "total_time_ms"}) {
    EXPECT_TRUE(j.contains(key)) << key;
    EXPECT_TRUE(j["engine"].contains(key)) << key;
  }
  std::string svg = report_svg(r);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("id=\"engine\""), std::string::npos);
  EXPECT_NE(svg.find("id=\"stpcalc\""), std::string::npos);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
}

TEST(StepcalcReport, NoDestinationAndRefusals) {
  ProfileReport r = make_report({std::nullopt, 20, 1, 8191, 100, 0});
  EXPECT_NEAR(r.engine.running_velocity, 245730.0, 1e-6);
  EXPECT_NEAR(r.engine.acceleration_pulses, r.stpcalc.acceleration_pulses, 1.0);
  EXPECT_NEAR(r.engine.deceleration_pulses, r.stpcalc.deceleration_pulses, 1.0);
  EXPECT_THROW(make_report({16'777'216, 600, 100, 1000, 500, 0}), std::invalid_argument);
  try {
    make_report({100, 600, 100, 1000, 30000, 0});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("1..3000"), std::string::npos);  // (AQ5-AQ4)/0.3
  }
}

}  // namespace
}  // namespace stepnode::tools
