// stepcalc's numbers: STPCALC's values (SPM30 Appendix B, B1.3) and the engine's exact values
// for the same move, side by side, plus the velocity profile of each for plotting.
#pragma once
#include <string>

#include "node/motion/stpcalc.hpp"
#include "tools/stepcalc/profile_values.hpp"

namespace stepnode::tools {

struct ProfileReport {
  motion::StpcalcInput input;
  bool triangular = false;    // STPCALC: the running velocity is never reached (B1.3.8)
  bool stpcalc_peak = false;  // the engine with the axis option 0x2n09:13
  ProfileValues stpcalc, engine;
  Curve ideal_curve;   // STPCALC's trapezoid or triangle: straight ramps at Rate_A / Rate_D
  Curve engine_curve;  // the engine's quantised staircase, every ramp interval
};

// Throws std::invalid_argument naming the input and its legal range. `stpcalc_peak`: the
// engine side with the axis option 0x2n09:13 (run_engine).
ProfileReport make_report(const motion::StpcalcInput& input, bool stpcalc_peak = false);

// Every B1.3 value in STPCALC's words, STPCALC's value and the engine's beside it.
std::string report_text(const ProfileReport& r);
// One JSON object: STPCALC's values under the B1.3 keys, the engine's under "engine".
std::string report_json(const ProfileReport& r);

}  // namespace stepnode::tools
