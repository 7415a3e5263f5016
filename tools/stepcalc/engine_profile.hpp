// The engine's side of stepcalc: runs a Horner-register move in the StepGenerator and reads
// back its exact phase figures and its quantised velocity staircase.
#pragma once
#include "node/motion/step_generator.hpp"
#include "node/motion/stpcalc.hpp"
#include "tools/stepcalc/profile_values.hpp"

namespace stepnode::tools {

struct EngineProfile {
  ProfileValues values;
  motion::StepGenerator::Marks marks;
  int64_t steps = 0;  // steps generated (the total, for a move with a destination)
  // The velocity level of every ramp interval (one level every Z_A / Z_D ticks), the
  // running plateau and any creep at base velocity, from 0 at the start to 0 at the end.
  Curve staircase;
};

// With a total: the move to it. Without (TOTAL '-', B1.2.1): an unbounded move that is
// stop()ped at its first step at running velocity, so its ramps show; the running part
// is not counted (running pulses/time 0, total time = acceleration + deceleration time,
// as B1.3.14). `stpcalc_peak`: a short move cruises at STPCALC's peak (the axis option
// 0x2n09:13) instead of turning where its ramps meet (SPM30 3.4.5, the module's rule).
// Throws std::invalid_argument for illegal registers.
EngineProfile run_engine(const motion::StpcalcInput& in, bool stpcalc_peak = false);

// The staircase of a finished move, from its ramp and marks (exposed for tests).
Curve engine_staircase(const motion::RampSpec& ramp, const motion::StepGenerator::Marks& m);

}  // namespace stepnode::tools
