// Velocity (pulses/s) against time (ms) as a hand-written SVG: STPCALC's ideal outline and
// the engine's quantised staircase, with axes, ticks, grid, labels and a legend.
#pragma once
#include <string>

#include "tools/stepcalc/profile_report.hpp"

namespace stepnode::tools {

// The two series are <polyline id="stpcalc"> and <polyline id="engine">; each has at most
// about kMaxPlotPoints points (corners closer than half a pixel to the last one are dropped).
constexpr size_t kMaxPlotPoints = 4000;
std::string render_svg(const ProfileReport& r);

// Any two velocity curves in the same frame: the reference (dashed) and the engine's.
struct PlotSpec {
  std::string title;    // <title>
  std::string heading;  // the line above the legend
  std::string reference_id, reference_label, engine_label;
  std::string velocity_unit = "pulses/s";
  Curve reference, engine;
};
std::string render_svg(const PlotSpec& p);

}  // namespace stepnode::tools
