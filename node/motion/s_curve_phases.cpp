#include "node/motion/s_curve_phases.hpp"

#include <algorithm>
#include <cmath>

namespace stepnode::motion::scurve {
namespace {

double inverse(uint32_t jerk) { return jerk == 0 ? 0.0 : 1.0 / static_cast<double>(jerk); }

// The rising case (a mirrored falling one): dv = v1 - v0 >= 0 to reach, a0 the starting
// acceleration, limit the acceleration, k1/k3 the inverse jerks of phases 1 and 3.
void solve(Phases& ph, double dv, double a0, double limit, double k1, double k3) {
  // Phase 1 from a0 to the peak gains (a0 + peak)/2 * |peak - a0| * k1, phase 3 peak^2 k3 / 2.
  const double gain1 = (a0 + limit) / 2 * std::abs(limit - a0) * k1, gain3 = limit * limit * k3 / 2;
  double t2 = (dv - gain1 - gain3) / limit;
  double peak = limit;
  if (t2 < 0) {
    // Too small a change to reach the limit: the peak where phases 1 and 3 meet.
    t2 = 0;
    peak = k1 + k3 > 0 ? std::sqrt(std::max(0.0, (2 * dv + a0 * a0 * k1) / (k1 + k3))) : limit;
    if (k1 + k3 <= 0) t2 = std::max(0.0, dv / limit);
  }
  ph.peak = peak;
  ph.t1 = std::abs(peak - a0) * k1;
  ph.t2 = t2;
  ph.t3 = peak * k3;
}

}  // namespace

Phases transition(double v0, double a0, double v1, const JerkLimits& l, double decel) {
  Phases ph;
  // Rising if v1 lies at or above where the velocity ends when the acceleration is taken
  // to 0 at once (with the jerk that does it).
  const double settle =
      a0 > 0 ? a0 * a0 * inverse(l.end_accel_jerk) / 2 : -a0 * a0 * inverse(l.begin_accel_jerk) / 2;
  ph.sign = v1 >= v0 + settle ? +1 : -1;
  if (ph.sign > 0) {
    ph.j1 = l.begin_accel_jerk;
    ph.j3 = l.end_accel_jerk;
    solve(ph, v1 - v0, a0, std::max(l.acceleration, 1e-9), inverse(ph.j1), inverse(ph.j3));
  } else {
    ph.j1 = l.begin_decel_jerk;
    ph.j3 = l.end_decel_jerk;
    solve(ph, v0 - v1, -a0, std::max(decel, 1e-9), inverse(ph.j1), inverse(ph.j3));
  }
  return ph;
}

Phases ramp_down_mirror(double v1, const JerkLimits& l, double decel) {
  Phases ph;
  ph.j1 = l.end_decel_jerk;
  ph.j3 = l.begin_decel_jerk;
  solve(ph, v1, 0, std::max(decel, 1e-9), inverse(ph.j1), inverse(ph.j3));
  return ph;
}

Kinematics run(Kinematics k, const Phases& ph) {
  auto phase = [&k](double jerk, double t) {
    k.p += k.v * t + k.a * t * t / 2 + jerk * t * t * t / 6;
    k.v += k.a * t + jerk * t * t / 2;
    k.a += jerk * t;
  };
  const double s = ph.sign, peak = s * ph.peak;
  phase(ph.t1 > 0 ? (peak - k.a) / ph.t1 : 0, ph.t1);
  k.a = peak;
  phase(0, ph.t2);
  phase(ph.t3 > 0 ? -peak / ph.t3 : 0, ph.t3);
  k.a = 0;
  return k;
}

}  // namespace stepnode::motion::scurve
