// Changes of a running trapezoid motion: a new velocity (HP SUSTAIN, CiA 402 velocity
// modes), a new grid, a constant level (CSV), a moved end point (an indexed move).
#include "node/motion/step_generator.hpp"

#include <algorithm>
#include <cassert>

namespace stepnode::motion {

void StepGenerator::change_velocity(Tick at, int64_t level, std::optional<RampSpec> then) {
  begin_change();
  if (scurve_ && phase_ != MotionPhase::Idle && !stopping_) {
    s_.p->change_velocity(
        at, static_cast<double>(level) * kClockHz / static_cast<double>(ramp_.phase_per_step));
    return s_follow();
  }
  if (phase_ == MotionPhase::Idle || stopping_ || (distance_ && then)) return;
  advance_to(at);
  // Never below one level: at level 0 the motion would stand still for ever and the next
  // step's time divides by the level (a 0 Hz minimum makes base_level 0).
  level = std::max({level, ramp_.base_level, int64_t{1}});
  // Already ramping down to the target: a lower velocity leaves that ramp as it is (slowing
  // to it first at the same deceleration ends at the same place and time); a higher one
  // ramps up again.
  if (distance_ && phase_ == MotionPhase::Decelerating && !holding_ && level <= level_) return;
  then_ = then;
  decel_check_after_ = -1;  // a higher peak: decel_needed() at every step up
  if (level > level_) {
    // Intervals at level+1 .. target, Z_A each (the same convention as a start).
    peak_level_ = level;
    phase_ = MotionPhase::Accelerating;
    ++level_;
    interval_index_ = 0;
    interval_end_ = t_ + interval_length(ramp_.accel_ticks_per_level, 0);
  } else if (level < level_) {
    decel_floor_ = level;
    holding_ = true;  // hold the lower velocity, even the base one, instead of stopping
    peak_level_ = level;
    phase_ = MotionPhase::Decelerating;
    marks_.decel_start = t_;
    interval_index_ = 0;
    interval_end_ = t_ + interval_length(ramp_.decel_ticks_per_level, 0);
  } else {
    phase_ = MotionPhase::Running;  // already there: hold it
    plan_decel();
    reached_velocity();
  }
}

void StepGenerator::reached_velocity() {
  if (!then_) return;
  RampSpec ramp = *then_;
  then_.reset();
  adopt(ramp, ramp.run_level);
}

void StepGenerator::set_level(Tick at, int64_t level) {
  begin_change();
  if (phase_ == MotionPhase::Idle) return;
  leave_s_curve(at);
  advance_to(at);
  level_ = std::max<int64_t>(level, 1);
  ramp_.base_level = ramp_.run_level = level_;  // a constant velocity: nothing to ramp
  ramp_.min_creep_level = level_;
  phase_ = MotionPhase::Creeping;
  stopping_ = holding_ = false;
  then_.reset();
  distance_.reset();
}

void StepGenerator::regrid(Tick at, const RampSpec& ramp) {
  begin_change();
  if (phase_ == MotionPhase::Idle || distance_ || stopping_) return;
  leave_s_curve(at);
  advance_to(at);
  then_.reset();
  const auto level = static_cast<int64_t>(
      (static_cast<__int128>(level_) * ramp.phase_per_step + ramp_.phase_per_step / 2) /
      ramp_.phase_per_step);
  adopt(ramp, level);
}

void StepGenerator::adopt(const RampSpec& ramp, int64_t level) {
  // The phase accumulator keeps its fraction of a step: acc/D is the same on both grids
  // (rounded down, so 0 <= acc < D holds on the new one).
  acc_ = static_cast<int64_t>(static_cast<__int128>(acc_) * ramp.phase_per_step /
                              ramp_.phase_per_step);
  ramp_ = ramp;
  level_ = std::max<int64_t>(1, level);
  phase_ = MotionPhase::Running;
  holding_ = false;
  peak_level_ = level_;
  decel_floor_ = ramp_.base_level;
  assert(acc_ >= 0 && acc_ < ramp_.phase_per_step);
}

void StepGenerator::retarget(Tick at, int64_t steps, const RampSpec& ramp) {
  begin_change();
  if (phase_ == MotionPhase::Idle) return;
  if (scurve_) {
    distance_ = steps_done_ + std::max<int64_t>(steps, 0);
    if (steps <= 0) return halt(at);
    s_.p->retarget(at, *distance_);
    return s_follow();
  }
  advance_to(at);
  distance_ = steps_done_ + std::max<int64_t>(steps, 0);
  ramp_.decel_ticks_per_level = ramp.decel_ticks_per_level;
  decel_check_after_ = -1;  // a nearer end, another ramp down
  if (steps <= 0) {
    halt(t_);
    return;
  }
  if (phase_ == MotionPhase::Running) plan_decel();
}

}  // namespace stepnode::motion
