// The HP 44714A internal position counter in PSCALE units ("Scaling Motor Motion" 3-9,
// "Setting and Monitoring Position With the Internal Counter" 3-18). The counter counts
// steps; POS? is the loaded value plus the steps since, times the scale factor, so it
// "can only count in increments of the scale factor" and round-off accumulates exactly as
// in "PSCALE ROUND-OFF ERROR EXAMPLES".
#pragma once
#include <cstdint>

namespace stepnode::motion::hp {

class PositionCounter {
 public:
  // PSCALE: units per step, may be negative, never 0. The position keeps its value.
  void set_scale(double units_per_step, int64_t steps_now);
  double scale() const { return scale_; }
  // POS value: the current step count now reads `units`.
  void load(double value, int64_t steps_now);
  // POS?
  double units(int64_t steps_now) const;

  // Steps a MOVE makes: REL distance / scale, ABS (target - position) / scale, rounded to
  // the nearest step with halves away from zero ("0.5 is rounded up to 1", Note 2).
  int64_t rel_steps(double distance) const;
  int64_t abs_steps(double target, int64_t steps_now) const;
  // Steps/s from units/s (SUSTAIN velocity, PROFILE frequencies given after PSCALE).
  double to_steps(double units) const { return units / scale_; }

 private:
  double scale_ = 1.0;  // power-on: PSCALE 1.0
  double origin_units_ = 0;
  int64_t origin_steps_ = 0;
};

}  // namespace stepnode::motion::hp
