// STPCALC (SPM30 Appendix B): the module maker's calculator, formula by formula, in
// floating point as the tool displays it. The engine is checked against these values.
// Where Appendix B contradicts itself, the module's own definitions win: the running
// velocity is AQ5*600/AQ3 (3.4.4; B1.3.5 misprints AQ4), and the running time divides the
// running pulses by the running velocity (B1.3.12 says Vel_Res but cites B1.3.5).
#pragma once
#include <cstdint>
#include <optional>

namespace stepnode::motion {

struct StpcalcInput {
  std::optional<int64_t> total;  // total pulses 0..16777215, or none (jog-type move)
  int64_t aq3 = 600, aq4 = 1, aq5 = 2, aq6 = 1, aq7 = 0;
};

struct StpcalcResult {
  int64_t z_a = 0, z_d = 0;
  double acceleration_rate = 0, deceleration_rate = 0;  // pulses/s^2
  double velocity_resolution = 0, base_velocity = 0, running_velocity = 0, peak_velocity = 0;
  double acceleration_pulses = 0, running_pulses = 0, deceleration_pulses = 0;
  double acceleration_time_ms = 0, running_time_ms = 0, deceleration_time_ms = 0;
  double total_time_ms = 0;  // with a total; else the acc+dec time (B1.3.14)
  double total_acc_dec_pulses = 0;
  bool triangular = false;
};

// Throws std::invalid_argument with the legal range of the first bad input.
StpcalcResult stpcalc(const StpcalcInput& in);

}  // namespace stepnode::motion
