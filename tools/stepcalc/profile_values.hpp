// The B1.3 figures of one move, as STPCALC shows them or as the engine produced them.
#pragma once
#include <utility>
#include <vector>

namespace stepnode::tools {

struct ProfileValues {
  double acceleration_rate = 0, deceleration_rate = 0;  // pulses/s^2
  double velocity_resolution = 0, base_velocity = 0, running_velocity = 0,
         peak_velocity = 0;  // pulses/s
  double acceleration_pulses = 0, running_pulses = 0, deceleration_pulses = 0;
  double acceleration_time_ms = 0, running_time_ms = 0, deceleration_time_ms = 0, total_time_ms = 0;
};

// Velocity against time: (time ms, velocity pulses/s) corners of a polyline.
using Curve = std::vector<std::pair<double, double>>;

}  // namespace stepnode::tools
