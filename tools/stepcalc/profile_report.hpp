// stepcalc's numbers: STPCALC's values (SPM30 Appendix B) and the engine's exact values for
// the same move, side by side, plus the velocity profile of each for plotting.
#pragma once
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "node/motion/stpcalc.hpp"

namespace stepnode::tools {

struct ProfileValues {
  double acceleration_rate = 0, deceleration_rate = 0, velocity_resolution = 0;
  double base_velocity = 0, running_velocity = 0, peak_velocity = 0;
  double acceleration_pulses = 0, running_pulses = 0, deceleration_pulses = 0;
  double acceleration_time_ms = 0, running_time_ms = 0, deceleration_time_ms = 0, total_time_ms = 0;
};

struct ProfileReport {
  motion::StpcalcInput input;
  bool triangular = false;
  ProfileValues stpcalc, engine;
  // (time ms, velocity steps/s): the ideal STPCALC outline and the engine's staircase.
  std::vector<std::pair<double, double>> ideal_curve, engine_curve;
};

// Throws std::invalid_argument naming the input and its legal range.
ProfileReport make_report(const motion::StpcalcInput& input);

std::string report_text(const ProfileReport& r);
std::string report_json(const ProfileReport& r);
std::string report_svg(const ProfileReport& r);

}  // namespace stepnode::tools
