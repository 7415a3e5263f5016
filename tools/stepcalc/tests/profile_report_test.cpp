// stepcalc's report against hand-calculated STPCALC values (SPM30 Appendix B, B1.3) and the
// engine's exact values for the same moves, worked out by hand from the engine's rules:
// D = 8192*AQ3 phase units per step, a level adds `level` per 4.9152 MHz tick, ramp
// intervals of Z_A / Z_D ticks at levels base+1..peak, a step on the first tick the phase
// reaches k*D, deceleration from the first tick where the phase left equals the ramp's.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "node/motion/timebase.hpp"
#include "tools/stepcalc/profile_report.hpp"

namespace stepnode::tools {
namespace {

using motion::ticks_to_ms;

// TOTAL 10000, AQ3 600, AQ4 100, AQ5 1000, AQ6 500, AQ7 0 (= AQ6, SPM30 3.4.6):
//   Z_A = Z_D = ceil(500*24576 / (900*5)) = ceil(2730.67) = 2731            (B1.3.1)
//   Rate_A = 4915200*600 / (2731*600) = 1799.7803 pulses/s^2
//   Vel_Res = 600/600 = 1, Vel_B = 100, Vel_R = 1000 pulses/s             (B1.3.3-5)
//   Pulse_A = Pulse_D = 900*1101*2731 / (16384*600) = 275.2836              (B1.3.7)
//   Pulse_R = 10000 - 2*275.2836 = 9449.4328                               (B1.3.8)
//   Time_A = Time_D = 900*2731*5/24576 = 500.0610 ms                        (B1.3.11)
//   Time_R = 9449.4328*1000/1000 = 9449.4328 ms; total 10449.5548 ms        (B1.3.12/15)
// Engine: D = 4915200; ramp phase = 2731 * sum(101..1000) = 2731*495450 = 1353073950.
//   accel steps = floor(1353073950 / 4915200) = 275, running from 900*2731 = 2457900 ticks;
//   deceleration starts ceil((10000*4915200 - 2*1353073950) / 1000) = 46445853 ticks later,
//   at phase 47798926950 = 9724.68 steps: 9724 - 275 = 9449 running, 276 decelerating;
//   the ramp down then overshoots the last step's phase by 900 units; its last interval
//   (level 101) adds 101 a tick, so the last step falls floor(900/101) = 8 ticks before
//   the ramp's end: deceleration 2457900 - 8 = 2457892 ticks.
TEST(StepcalcReport, HandCalculatedTrapezoid) {
  ProfileReport r = make_report({10000, 600, 100, 1000, 500, 0});
  EXPECT_FALSE(r.triangular);
  const ProfileValues& s = r.stpcalc;
  EXPECT_NEAR(s.acceleration_rate, 1799.7803, 1e-4);
  EXPECT_NEAR(s.deceleration_rate, 1799.7803, 1e-4);
  EXPECT_DOUBLE_EQ(s.velocity_resolution, 1.0);
  EXPECT_DOUBLE_EQ(s.base_velocity, 100.0);
  EXPECT_DOUBLE_EQ(s.running_velocity, 1000.0);
  EXPECT_DOUBLE_EQ(s.peak_velocity, 1000.0);
  EXPECT_NEAR(s.acceleration_pulses, 275.2836, 1e-4);
  EXPECT_NEAR(s.deceleration_pulses, 275.2836, 1e-4);
  EXPECT_NEAR(s.running_pulses, 9449.4328, 1e-4);
  EXPECT_NEAR(s.acceleration_time_ms, 500.0610, 1e-4);
  EXPECT_NEAR(s.deceleration_time_ms, 500.0610, 1e-4);
  EXPECT_NEAR(s.running_time_ms, 9449.4328, 1e-4);
  EXPECT_NEAR(s.total_time_ms, 10449.5548, 1e-4);

  const ProfileValues& e = r.engine;
  EXPECT_NEAR(e.acceleration_rate, 1799.7803, 1e-4);  // one level (1 pulse/s) per 2731 ticks
  EXPECT_DOUBLE_EQ(e.running_velocity, 1000.0);
  EXPECT_DOUBLE_EQ(e.peak_velocity, 1000.0);
  EXPECT_EQ(e.acceleration_pulses, 275);
  EXPECT_EQ(e.running_pulses, 9449);
  EXPECT_EQ(e.deceleration_pulses, 276);
  EXPECT_DOUBLE_EQ(e.acceleration_time_ms, ticks_to_ms(2'457'900));  // 500.0610 ms
  EXPECT_DOUBLE_EQ(e.running_time_ms, ticks_to_ms(46'445'853));      // 9449.4330 ms
  EXPECT_DOUBLE_EQ(e.deceleration_time_ms, ticks_to_ms(2'457'892));  // 500.0594 ms
  EXPECT_DOUBLE_EQ(e.total_time_ms, ticks_to_ms(51'361'645));        // 10449.5534 ms
}

// TOTAL 300, AQ3 600, AQ4 100, AQ5 1000, AQ6 500, AQ7 250: triangular (B1.3.8).
//   Z_A = 2731 as above; Z_D = ceil(250*24576/4500) = ceil(1365.33) = 1366
//   Rate_D = 4915200/1366 = 3598.2430; Pulse_A = 275.2836, Pulse_D = 900*1101*1366/9830400 =
//   137.6922 Pulse_R = 300 - 412.9758 < 0: R_T = 300/412.9758 = 0.726435 Pulse_A = 199.9756,
//   Pulse_D = 100.0244, Time_A = 500.0610*R_T = 363.2617 ms, Time_D = 250.1221*R_T = 181.6974 ms,
//   Time_R = 0, total 544.9591 ms Vel_P = 1799.7803*0.3632617 + 100 = 753.7913 pulses/s (B1.3.6)
// Engine: peak = 100 + floor(300*4915200*900 / (495450*(2731+1366))) = 100 + 653 = 753;
//   accel phase 2731*sum(101..753) = 2731*278831 = 761487461 -> 154 steps in 653*2731 =
//   1783343 ticks; deceleration ramp phase 1366*278831 = 380883146, so it starts
//   ceil((1474560000 - 380883146 - 761487461)/753) = 441155 ticks later, at phase
//   1093677176 = 222.5 steps: 68 running, 78 decelerating; the ramp down overshoots the
//   last step's phase by 322 units, so it falls floor(322/101) = 3 ticks before the ramp's
//   end: 653*1366 - 3 = 891995 ticks.
TEST(StepcalcReport, HandCalculatedTriangleWithTheStpcalcPeakOption) {
  ProfileReport r = make_report({300, 600, 100, 1000, 500, 250}, /*stpcalc_peak=*/true);
  EXPECT_TRUE(r.triangular);
  const ProfileValues& s = r.stpcalc;
  EXPECT_NEAR(s.deceleration_rate, 3598.2430, 1e-4);
  EXPECT_NEAR(s.acceleration_pulses, 199.9756, 1e-4);
  EXPECT_NEAR(s.deceleration_pulses, 100.0244, 1e-4);
  EXPECT_DOUBLE_EQ(s.running_pulses, 0.0);
  EXPECT_NEAR(s.acceleration_time_ms, 363.2617, 1e-4);
  EXPECT_NEAR(s.deceleration_time_ms, 181.6974, 1e-4);
  EXPECT_DOUBLE_EQ(s.running_time_ms, 0.0);
  EXPECT_NEAR(s.total_time_ms, 544.9591, 1e-4);
  EXPECT_NEAR(s.peak_velocity, 753.7913, 1e-4);

  const ProfileValues& e = r.engine;
  EXPECT_DOUBLE_EQ(e.peak_velocity, 753.0);
  EXPECT_LE(e.peak_velocity, s.peak_velocity);  // never above STPCALC's peak
  EXPECT_EQ(e.acceleration_pulses, 154);
  EXPECT_EQ(e.running_pulses, 68);
  EXPECT_EQ(e.deceleration_pulses, 78);
  EXPECT_DOUBLE_EQ(e.acceleration_time_ms, ticks_to_ms(1'783'343));  // 362.8221 ms
  EXPECT_DOUBLE_EQ(e.running_time_ms, ticks_to_ms(441'155));         // 89.7532 ms
  EXPECT_DOUBLE_EQ(e.deceleration_time_ms, ticks_to_ms(891'995));    // 181.4768 ms
  EXPECT_DOUBLE_EQ(e.total_time_ms, ticks_to_ms(3'116'493));         // 634.0521 ms
  EXPECT_NE(report_text(r).find("Triangular move"), std::string::npos);
}

// The same move as the module makes it (SPM30 3.4.5: it turns where the ramps meet, halfway
// with equal ramps, no cruising): the highest level L whose ramps fit the 300 pulses,
//   (Z_A + Z_D) * sum(101..L) <= 300 * 4915200  ->  4097 * (L-100)(L+101)/2 <= 1474560000
//   L = 853: 4097 * 359181 = 1471564557 (fits); L = 854: 4097 * 360136 = 1475477192 (not)
// so the peak is 853 pulses/s, reached after 753 * 2731 = 2056443 ticks (418.3844 ms); the
// ramp down takes 753 * 1366 = 1028598 ticks, the last of them cut where the move ends.
TEST(StepcalcReport, HandCalculatedTriangleAsTheModuleMovesIt) {
  ProfileReport r = make_report({300, 600, 100, 1000, 500, 250});
  const ProfileValues& e = r.engine;
  EXPECT_DOUBLE_EQ(e.peak_velocity, 853.0);
  EXPECT_GT(e.peak_velocity, r.stpcalc.peak_velocity);  // B1.3.6's peak scales pulses linearly
  EXPECT_EQ(e.acceleration_pulses + e.running_pulses + e.deceleration_pulses, 300);
  EXPECT_LE(e.running_pulses, 1);
  EXPECT_DOUBLE_EQ(e.acceleration_time_ms, ticks_to_ms(2'056'443));
  EXPECT_NEAR(e.deceleration_time_ms, ticks_to_ms(1'028'598), ticks_to_ms(1366));
}

// TOTAL -, AQ3 20, AQ4 1, AQ5 8191, AQ6 100, AQ7 0: the 245,730 pulses/s jog ramps.
//   Z_A = ceil(100*24576/(8190*5)) = ceil(60.015) = 61
//   Rate_A = 4915200*600/(61*20) = 2417311.4754 pulses/s^2; Vel_Res = 30, Vel_B = 30,
//   Vel_R = 8191*30 = 245730; Pulse_A = 8190*8193*61/(16384*20) = 12491.2746;
//   Time_A = 8190*61*5/24576 = 101.6418 ms; acc/dec 24982.5493 pulses, 203.2837 ms
// Engine: ramp phase 61*sum(2..8191) = 61*33550335 = 2046570435 = 12491 steps of 163840
//   + 44995; stopped at its first running step (residue < 8191) it decelerates over the
//   same 61*8190 = 499590 ticks and 12491 steps.
TEST(StepcalcReport, HandCalculatedMoveWithoutDestination) {
  ProfileReport r = make_report({std::nullopt, 20, 1, 8191, 100, 0});
  EXPECT_FALSE(r.triangular);
  const ProfileValues& s = r.stpcalc;
  EXPECT_NEAR(s.acceleration_rate, 2417311.4754, 1e-4);
  EXPECT_DOUBLE_EQ(s.velocity_resolution, 30.0);
  EXPECT_DOUBLE_EQ(s.base_velocity, 30.0);
  EXPECT_DOUBLE_EQ(s.running_velocity, 245730.0);
  EXPECT_NEAR(s.acceleration_pulses, 12491.2746, 1e-4);
  EXPECT_NEAR(s.acceleration_time_ms, 101.6418, 1e-4);
  EXPECT_NEAR(s.total_time_ms, 203.2837, 1e-4);

  const ProfileValues& e = r.engine;
  EXPECT_DOUBLE_EQ(e.running_velocity, 245730.0);
  EXPECT_EQ(e.acceleration_pulses, 12491);
  EXPECT_EQ(e.deceleration_pulses, 12491);
  EXPECT_EQ(e.running_pulses, 0);
  EXPECT_DOUBLE_EQ(e.acceleration_time_ms, ticks_to_ms(499'590));
  EXPECT_DOUBLE_EQ(e.deceleration_time_ms, ticks_to_ms(499'590));
  EXPECT_DOUBLE_EQ(e.total_time_ms, ticks_to_ms(2 * 499'590));

  std::string text = report_text(r);
  for (const char* words :
       {"Actual acceleration rate =", "Actual deceleration rate =", "Actual velocity resolution =",
        "Actual base velocity =", "Actual running velocity =", "Actual acceleration pulses =",
        "Actual deceleration pulses =", "Actual total acc/dec pulses =",
        "Actual acceleration time =", "Actual deceleration time =", "Actual total acc/dec time ="})
    EXPECT_NE(text.find(words), std::string::npos) << words;
  EXPECT_EQ(text.find("Actual running pulses ="), std::string::npos);  // only with a total (B1.3.8)
  EXPECT_EQ(text.find("Actual total move time ="), std::string::npos);
}

TEST(StepcalcReport, TextNamesEveryB13ValueOfAMoveWithATotal) {
  std::string text = report_text(make_report({10000, 600, 100, 1000, 500, 0}));
  for (const char* words :
       {"Actual acceleration rate =", "Actual deceleration rate =", "Actual velocity resolution =",
        "Actual base velocity =", "Actual running velocity =", "Actual acceleration pulses =",
        "Actual running pulses =", "Actual deceleration pulses =", "Actual acceleration time =",
        "Actual running time =", "Actual deceleration time =", "Actual total move time =",
        "pulses/sec^2", "pulses/sec", "mS", "STPCALC", "engine"})
    EXPECT_NE(text.find(words), std::string::npos) << words;
  EXPECT_EQ(text.find("Actual peak velocity ="), std::string::npos);  // trapezoid: running velocity
}

TEST(StepcalcReport, ZeroAndOnePulseMoves) {
  ProfileReport zero = make_report({0, 600, 100, 1000, 500, 0});
  EXPECT_EQ(zero.engine.acceleration_pulses + zero.engine.running_pulses +
                zero.engine.deceleration_pulses,
            0);
  EXPECT_DOUBLE_EQ(zero.engine.total_time_ms, 0.0);
  EXPECT_GE(zero.engine.acceleration_time_ms, 0.0);
  EXPECT_DOUBLE_EQ(zero.stpcalc.total_time_ms, 0.0);
  ProfileReport one = make_report({1, 600, 100, 1000, 500, 0});
  EXPECT_EQ(
      one.engine.acceleration_pulses + one.engine.running_pulses + one.engine.deceleration_pulses,
      1);
  ProfileReport capped = make_report({1, 600, 100, 1000, 500, 0}, /*stpcalc_peak=*/true);
  EXPECT_LE(capped.engine.peak_velocity, capped.stpcalc.peak_velocity);
}

TEST(StepcalcReport, JsonHasEveryKeyForStpcalcAndTheEngine) {
  for (auto total : {std::optional<int64_t>(300), std::optional<int64_t>()}) {
    ProfileReport r = make_report({total, 600, 100, 1000, 500, 250});
    nlohmann::json j = nlohmann::json::parse(report_json(r));
    ASSERT_TRUE(j.contains("engine"));
    for (const char* key :
         {"acceleration_rate", "deceleration_rate", "velocity_resolution", "base_velocity",
          "running_velocity", "peak_velocity", "acceleration_pulses", "running_pulses",
          "deceleration_pulses", "acceleration_time_ms", "running_time_ms", "deceleration_time_ms",
          "total_time_ms"}) {
      ASSERT_TRUE(j.contains(key)) << key;
      ASSERT_TRUE(j["engine"].contains(key)) << key;
      EXPECT_TRUE(j[key].is_number()) << key;
      EXPECT_TRUE(j["engine"][key].is_number()) << key;
    }
    EXPECT_DOUBLE_EQ(j["acceleration_pulses"].get<double>(), r.stpcalc.acceleration_pulses);
    EXPECT_DOUBLE_EQ(j["engine"]["total_time_ms"].get<double>(), r.engine.total_time_ms);
    EXPECT_EQ(j["input"]["total"].is_null(), !total.has_value());
  }
}

// SPM30 3.4.5: AQ6 above (AQ5-AQ4)/0.3 is legal; STPCALC's formulas take it as given
// (B1.3.1: Z_A = ceil(27300*24576/4500) = 149095, Time_A = 900*149095*5/24576 = 27300.1 ms),
// the module ramps in the maximum useful 3000 ms (Z = 16384), and the report says so.
TEST(StepcalcReport, AccelerationAboveTheMaximumUsefulValue) {
  ProfileReport r = make_report({100000, 600, 100, 1000, 27300, 0});
  EXPECT_NEAR(r.stpcalc.acceleration_time_ms, 900.0 * 149095 * 5 / 24576, 1e-6);
  EXPECT_DOUBLE_EQ(r.engine.acceleration_time_ms, ticks_to_ms(900 * 16384));
  std::string text = report_text(r);
  EXPECT_NE(text.find("above its maximum useful value (AQ5-AQ4)/0.3 = 3000 mS"), std::string::npos)
      << text;
}

TEST(StepcalcReport, RefusesOutOfRangeInputsNamingTheRange) {
  auto message = [](motion::StpcalcInput in) -> std::string {
    try {
      make_report(in);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_NE(message({16'777'216, 600, 100, 1000, 500, 0}).find("0..16777215"), std::string::npos);
  EXPECT_NE(message({-1, 600, 100, 1000, 500, 0}).find("0..16777215"), std::string::npos);
  EXPECT_NE(message({100, 19, 100, 1000, 500, 0}).find("20..65535"), std::string::npos);
  EXPECT_NE(message({100, 600, 0, 1000, 500, 0}).find("1..8190"), std::string::npos);
  EXPECT_NE(message({100, 600, 100, 100, 500, 0}).find("101..8191"), std::string::npos);
  EXPECT_NE(message({100, 600, 100, 8192, 500, 0}).find("101..8191"), std::string::npos);
  EXPECT_EQ(message({100, 600, 100, 1000, 3001, 0}),
            "accepted");  // above (1000-100)/0.3: legal (3.4.5)
  EXPECT_NE(message({100, 600, 100, 1000, 0, 0}).find("%AQ6"), std::string::npos);
  EXPECT_NE(message({100, 600, 100, 1000, 500, 27301}).find("%AQ7"), std::string::npos);
  EXPECT_NE(message({100, 600, 1, 8191, 27301, 0}).find("1..27300"), std::string::npos);
  EXPECT_EQ(message({16'777'215, 65535, 8190, 8191, 3, 3}), "accepted");  // the extremes
}

}  // namespace
}  // namespace stepnode::tools
