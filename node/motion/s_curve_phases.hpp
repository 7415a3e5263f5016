// The three phases of a jerk-limited velocity change (node/motion/s_curve.hpp): jerk to a
// peak acceleration, hold it, jerk back to 0, in real numbers (seconds). The S-curve
// plans with these, then lays the phases on whole ticks.
#pragma once
#include "node/motion/s_curve.hpp"

namespace stepnode::motion::scurve {

struct Phases {
  int sign = +1;                  // +1 the velocity rises, -1 it falls
  double peak = 0;                // |acceleration| held in phase 2
  double t1 = 0, t2 = 0, t3 = 0;  // seconds
  uint32_t j1 = 0, j3 = 0;        // jerk of phases 1 and 3 (0: not limited, no time)
};

// From velocity v0 and acceleration a0 to velocity v1 with acceleration 0, with the limits'
// acceleration (rising) or `decel` (falling) and jerks.
Phases transition(double v0, double a0, double v1, const JerkLimits& limits, double decel);
// The same from standstill to v1 as the mirror image of the ramp down with `decel`: its
// phase 1 is the ramp down's last (end jerk), its phase 3 the first (begin jerk).
Phases ramp_down_mirror(double v1, const JerkLimits& limits, double decel);

struct Kinematics {
  double p = 0, v = 0, a = 0;
};
// Where the phases take a motion in state k (exact formulas per phase).
Kinematics run(Kinematics k, const Phases& ph);

}  // namespace stepnode::motion::scurve
