// stepcalc cia402: a CiA 402 profile position move (6081h velocity, 6083h/6084h slopes,
// 6086h motion profile type 0 linear ramp or 3 jerk-limited with the 60A4h jerks) run in the
// engine as a drive runs it, beside the closed form of the same profile: the move's time,
// every step's time against the closed form's, and both velocity curves for a plot.
#pragma once
#include <cstdint>
#include <optional>
#include <string>

#include "tools/stepcalc/profile_values.hpp"
#include "tools/stepcalc/svg_plot.hpp"

namespace stepnode::tools {

struct Cia402Move {
  int64_t distance = 0;       // steps (> 0), 607Ah from standstill at 0
  uint32_t velocity = 0;      // 6081h, steps/s
  uint32_t acceleration = 0;  // 6083h, steps/s^2
  uint32_t deceleration = 0;  // 6084h, steps/s^2
  int16_t profile_type = 0;   // 6086h: 0 linear ramp, 3 jerk-limited ramp
  // 60A4h:1..4 in steps/s^3: begin acceleration, begin deceleration, end acceleration, end
  // deceleration jerk (0: not limited).
  uint32_t jerk[4] = {0, 0, 0, 0};
};

struct Cia402Report {
  Cia402Move move;
  int64_t steps = 0;          // steps the engine made (the distance)
  double engine_time_ms = 0;  // first tick to the last step
  double peak_velocity = 0;   // the engine's fastest step rate, steps/s
  // The closed form of the same profile (the move reaches 6081h; otherwise nullopt: the
  // closed form of a short jerk-limited move, whose peak the planner chooses, is not made).
  std::optional<double> closed_form_time_ms;
  std::optional<double> closed_form_peak_velocity;
  // Largest |step n's tick - the instant the closed form reaches n|, over every step.
  std::optional<double> max_step_deviation_us;
  Curve closed_form_curve, engine_curve;  // velocity (steps/s) against time (ms)
};

// Throws std::invalid_argument for a move the drive would not make (distance 0, a slope or
// velocity of 0, a profile type other than 0 and 3).
Cia402Report make_cia402_report(const Cia402Move& move);
std::string cia402_text(const Cia402Report& r);
std::string cia402_json(const Cia402Report& r);
PlotSpec cia402_plot(const Cia402Report& r);

}  // namespace stepnode::tools
