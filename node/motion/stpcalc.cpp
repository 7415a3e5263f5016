#include "node/motion/stpcalc.hpp"

#include <stdexcept>
#include <string>

#include "node/motion/ramp.hpp"

namespace stepnode::motion {

StpcalcResult stpcalc(const StpcalcInput& in) {
  if (in.total && (*in.total < 0 || *in.total > 16'777'215))
    throw std::invalid_argument("total pulses = " + std::to_string(*in.total) +
                                " is outside 0..16777215");
  (void)horner_ramp(in.aq3, in.aq4, in.aq5, in.aq6, in.aq7);  // validates the rest
  StpcalcResult r;
  const double aq3 = static_cast<double>(in.aq3), aq4 = static_cast<double>(in.aq4),
               aq5 = static_cast<double>(in.aq5);
  // STPCALC's formulas as printed (B1.3.1/B1.3.2): an AQ6/AQ7 above the maximum useful value
  // gives STPCALC's longer figures; the module (the engine) ramps in the maximum useful time.
  r.z_a = horner_z(in.aq6, in.aq4, in.aq5);
  r.z_d = horner_z(in.aq7 == 0 ? in.aq6 : in.aq7, in.aq4, in.aq5);
  const double za = static_cast<double>(r.z_a), zd = static_cast<double>(r.z_d);
  r.acceleration_rate = 4915200.0 * 600.0 / (za * aq3);                          // B1.3.1
  r.deceleration_rate = 4915200.0 * 600.0 / (zd * aq3);                          // B1.3.2
  r.velocity_resolution = 600.0 / aq3;                                           // B1.3.3
  r.base_velocity = aq4 * 600.0 / aq3;                                           // B1.3.4
  r.running_velocity = aq5 * 600.0 / aq3;                                        // B1.3.5 (3.4.4)
  r.acceleration_pulses = (aq5 - aq4) * (aq5 + aq4 + 1) * za / (16384.0 * aq3);  // B1.3.7
  r.deceleration_pulses = (aq5 - aq4) * (aq5 + aq4 + 1) * zd / (16384.0 * aq3);  // B1.3.9
  r.acceleration_time_ms = (aq5 - aq4) * za * 5.0 / 24576.0;                     // B1.3.11
  r.deceleration_time_ms = (aq5 - aq4) * zd * 5.0 / 24576.0;                     // B1.3.13
  r.total_acc_dec_pulses = r.acceleration_pulses + r.deceleration_pulses;        // B1.3.10
  r.peak_velocity = r.running_velocity;
  if (!in.total) {
    r.total_time_ms = r.acceleration_time_ms + r.deceleration_time_ms;  // B1.3.14
    return r;
  }
  const double total = static_cast<double>(*in.total);
  r.running_pulses = total - r.acceleration_pulses - r.deceleration_pulses;  // B1.3.8
  if (r.running_pulses < 0) {
    r.triangular = true;
    double rt = total / (r.acceleration_pulses + r.deceleration_pulses);
    r.running_pulses = 0;
    r.acceleration_pulses *= rt;
    r.deceleration_pulses *= rt;
    r.acceleration_time_ms *= rt;
    r.deceleration_time_ms *= rt;
    r.peak_velocity =
        r.acceleration_rate * r.acceleration_time_ms / 1000.0 + r.base_velocity;  // B1.3.6
  }
  r.running_time_ms = r.running_pulses * 1000.0 / r.running_velocity;                     // B1.3.12
  r.total_time_ms = r.acceleration_time_ms + r.running_time_ms + r.deceleration_time_ms;  // B1.3.15
  return r;
}

}  // namespace stepnode::motion
