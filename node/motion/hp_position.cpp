#include "node/motion/hp_position.hpp"

#include <cmath>

namespace stepnode::motion::hp {

void PositionCounter::set_scale(double units_per_step, int64_t steps_now) {
  origin_units_ = units(steps_now);
  origin_steps_ = steps_now;
  scale_ = units_per_step;
}

void PositionCounter::load(double value, int64_t steps_now) {
  origin_units_ = value;
  origin_steps_ = steps_now;
}

double PositionCounter::units(int64_t steps_now) const {
  return origin_units_ + static_cast<double>(steps_now - origin_steps_) * scale_;
}

int64_t PositionCounter::rel_steps(double distance) const {
  // A scale like 0.1 is not exact in binary (20 / 0.1 = 200.00000000000003): round to a
  // millionth of a step first, so only true halves round away from zero.
  double exact = distance / scale_;
  return std::llround(std::round(exact * 1e6) / 1e6);
}

int64_t PositionCounter::abs_steps(double target, int64_t steps_now) const {
  return rel_steps(target - units(steps_now));
}

}  // namespace stepnode::motion::hp
