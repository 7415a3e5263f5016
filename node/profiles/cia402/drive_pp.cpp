// Profile position mode (CiA 402-2 "Profile position mode"): the set-point handshake,
// the buffered next set-point, change set immediately, relative targets and the software
// limits. The trajectory of each set-point is one motion of the core.
#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "node/profiles/cia402/drive.hpp"

namespace stepnode::cia402 {
namespace {

using motion::Tick;

int sign(int64_t v) { return v < 0 ? -1 : +1; }

}  // namespace

int64_t Drive::clamp_to_limits(int64_t target) {
  // 607Dh: a target outside the software limits goes to the limit; bit 11 shows it.
  const int64_t low = parameters_.min_position_limit, high = parameters_.max_position_limit;
  internal_limit_ = low < high && (target < low || target > high);
  if (low < high) target = std::clamp(target, low, high);
  return std::clamp<int64_t>(target, INT32_MIN, INT32_MAX);
}

void Drive::new_set_point(uint16_t cw, Tick now) {
  // The set-point is taken only when the trajectory generator can take it: no other front
  // end's job on the axis, and room in the buffer (one running, one next).
  if (core_.busy() && !core_.owned_by(*this)) return;
  const bool immediately = (cw & cw_pp::kChangeSetImmediately) != 0;
  if (active_ && next_ && !immediately) return;  // bit 12 stays 1: the buffer is full
  // Bit 6: relative to the preceding target position (60F2h's default), or to where the
  // trajectory is when there was none.
  const int64_t base = (cw & cw_pp::kRelative) ? last_target_.value_or(position_demand()) : 0;
  SetPoint sp{clamp_to_limits(base + target_position_), parameters_.profile_velocity};
  last_target_ = sp.target;
  acknowledged_ = true;
  target_reached_ = false;
  in_window_since_.reset();
  if (!core_.owned_by(*this)) {
    active_ = sp;
    next_.reset();
    return start_positioning(sp, now);
  }
  if (!immediately) {
    if (!active_) {
      active_ = sp;
      return start_positioning(sp, now);
    }
    next_ = sp;  // carried out when the running one is done...
    // (after_step looks at every step while a set-point is queued: Drive::hooks)
    core_.hooks_changed(*this);
    if (cw & cw_pp::kChangeOnSetPoint) run_on_to_next(now);  // ...or on from its target
    return;
  }
  // Change set immediately: the new target replaces the running one. On the way and far
  // enough to ramp down: the end point moves; otherwise stop, then go there.
  active_ = sp;
  next_.reset();
  const motion::StepGenerator& g = core_.generator();
  const int64_t ahead = (sp.target - core_.position()) * g.direction();
  const int64_t to_stop = static_cast<int64_t>(std::ceil(g.steps_to_stop())) + 2;
  if (!g.stopping() && g.remaining() && ahead >= to_stop) {
    core_.retarget(now, ahead, g.ramp());
  } else {
    restart_after_stop_ = true;
    core_.stop(now);
  }
}

motion::RampSpec Drive::ramp(uint32_t velocity) const {
  const int64_t v =
      std::clamp<int64_t>(velocity, 1, std::max<uint32_t>(parameters_.max_velocity, 1));
  const int64_t acc = std::max<uint32_t>(parameters_.acceleration, 1);
  const int64_t dec = std::max<uint32_t>(parameters_.deceleration, 1);
  motion::RampSpec r = motion::profile_ramp(v, acc, dec, grid_);
  // 6086h = 3: the same limits with the jerks of 60A4h (PP, PV; homing keeps its trapezoids).
  if (parameters_.motion_profile_type == kJerkLimitedRamp) {
    r.s_curve = true;
    std::copy(std::begin(parameters_.jerk), std::end(parameters_.jerk), std::begin(r.jerk));
  }
  return r;
}

void Drive::start_positioning(const SetPoint& sp, Tick now) {
  const int64_t distance = sp.target - core_.position();
  if (distance == 0) {
    active_.reset();
    in_window_since_ = now;  // already there
    return;
  }
  grid_ =
      motion::profile_levels_per_hz(std::max(parameters_.acceleration, parameters_.deceleration));
  if (!core_.start(*this, ramp(sp.velocity), sign(distance), std::llabs(distance), now))
    active_.reset();
}

// ---- change on set-point ----------------------------------------------------------------
//
// CiA 402-2, profile position, controlword bits 4, 5 and 9: with bit 9 = 1 and bit 5 = 0
// "positioning with the current profile velocity up to the current set-point shall be
// proceeded and then next positioning shall be applied": the axis does not stop at the
// first target; it reaches it at the first set-point's velocity and goes on from there at
// the next one's (6083h/6084h of the running motion, its ramp down to the last target).
// The drive can do that while the next target lies beyond the first in the direction of
// travel and the motion still goes to the first; otherwise (a reversal, a stop under way)
// it stops at the first target and starts the next from there, as with bit 9 = 0.

int64_t Drive::level_of(uint32_t velocity) const {
  return std::clamp<int64_t>(velocity, 1, std::max<uint32_t>(parameters_.max_velocity, 1)) * grid_;
}

void Drive::run_on_to_next(Tick now) {
  const motion::StepGenerator& g = core_.generator();
  if (!g.moving() || g.stopping() || restart_after_stop_ || !g.remaining()) return;
  const int64_t to_first = (active_->target - core_.position()) * g.direction();
  const int64_t beyond = (next_->target - active_->target) * g.direction();
  if (to_first <= 0 || beyond <= 0) return;
  next_->through = true;
  core_.retarget(now, to_first + beyond, g.ramp());
  // Already ramping down to the first target: up again to its velocity.
  if (g.phase() == motion::MotionPhase::Decelerating || g.phase() == motion::MotionPhase::Creeping)
    core_.change_velocity(now, level_of(active_->velocity));
}

void Drive::pass_first_target(Tick at) {
  // On the first target: the next set-point is the running one from here, at its velocity,
  // and the buffer is free again (bit 12 follows bit 4).
  active_ = next_;
  active_->through = false;
  next_.reset();
  core_.change_velocity(at, level_of(active_->velocity));
}

}  // namespace stepnode::cia402
