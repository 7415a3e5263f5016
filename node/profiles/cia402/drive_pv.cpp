// Profile velocity mode (CiA 402-2 "Profile velocity mode"): the target velocity with the
// 6083h/6084h ramps, a reversal as a stop and a start the other way, and a stop before the
// software limits 607Dh (drive_limits.cpp; PV ran past them: found in review).
#include <algorithm>
#include <cstdlib>

#include "node/profiles/cia402/drive.hpp"

namespace stepnode::cia402 {
namespace {

using motion::Tick;

int sign(int64_t v) { return v < 0 ? -1 : +1; }

}  // namespace

void Drive::set_target_velocity(int32_t steps_per_s, Tick now) {
  target_velocity_ = steps_per_s;
  if (mode_display_ != Mode::ProfileVelocity || mode_ != mode_display_ ||
      !machine_.operation_enabled() || halted_)
    return;
  core_.advance_to(now);
  velocity_to(steps_per_s, now);
  notify();
}

void Drive::velocity_to(int64_t target, Tick now) {
  target =
      std::clamp<int64_t>(target, -int64_t{parameters_.max_velocity}, parameters_.max_velocity);
  if (!core_.owned_by(*this)) {
    if (core_.busy()) return;
    // 607Dh: not toward a limit the axis could not stop before (drive_limits.cpp).
    const double most = reachable(sign(target), 0, static_cast<double>(std::llabs(target)));
    internal_limit_ = target != 0 && !room_to_stop(sign(target), 0, most);
    if (target == 0 || internal_limit_) return;
    grid_ =
        motion::profile_levels_per_hz(std::max(parameters_.acceleration, parameters_.deceleration));
    if (core_.start(*this, ramp(static_cast<uint32_t>(std::llabs(target))), sign(target),
                    std::nullopt, now))
      watch_limit(sign(target), 0, most, now);
    return;
  }
  const motion::StepGenerator& g = core_.generator();
  if (target == 0) {
    velocity_after_stop_.reset();
    return core_.stop(now);
  }
  if (sign(target) != g.direction() || g.stopping()) {
    // A reversal (or a stop already under way): stop, then start at the new velocity.
    velocity_after_stop_ = target;
    return core_.stop(now);
  }
  core_.change_velocity(now, std::llabs(target) * grid_);
  const double v = g.velocity();
  watch_limit(g.direction(), v,
              reachable(g.direction(), v, static_cast<double>(std::llabs(target))), now);
}

}  // namespace stepnode::cia402
