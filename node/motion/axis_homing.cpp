// The Horner front end's FIND HOME (SPM30 4 FIND HOME steps 1-8, STP100 5.3.2, STP113 C1.2):
// the search, the stop on the origin (or the end limit, limit-switch-qualified), the run
// back at base velocity, the 50 ms dwell off the origin and the approach.
#include "node/motion/axis.hpp"

namespace stepnode::motion {
namespace {

constexpr Tick kOriginDwellTicks = kClockHz / 20;  // 50 ms (SPM30 4 FIND HOME step 5)

}  // namespace

void Axis::find_home(int direction, Tick now) {
  // SPM30 3.4.1: the destination is loaded into MOTOR POSITION at the end; one the module
  // cannot hold makes the command impossible (Illegal Move), checked before any motion.
  if (words_.destination < kPositionMin || words_.destination > kPositionMax)
    return latch(status::kIllegalMove, now);
  auto ramp = ramp_from_words(now);
  if (!ramp) return;
  position_valid_ = false;  // FIND HOME step 1
  job_ = Job::Home;
  home_stage_ = HomeStage::Seek;
  move_ramp_ = *ramp;
  origin_inactive_since_.reset();
  if (core_.estop_active()) return latch(status::kEmergencyStop, now);
  // SPM30 3.3.1 / 4: an active end limit blocks motion in its direction, so the search
  // takes no step into it: a limit error, or (limit-switch-qualified, STP100 5.3.2 step 3)
  // the limit is already reached and the search goes on from step 4.
  const bool at_limit = direction > 0 ? inputs().upper_limit() : inputs().lower_limit();
  if (at_limit && !limit_qualified_home())
    return latch(direction > 0 ? status::kUpperLimit : status::kLowerLimit, now);
  // Step 3 stops the search when the home input "becomes active": one already active at the
  // start satisfies it at once, with no step (a step first would run off a cam whose last
  // step the axis stands on, to the end limit).
  if (limit_qualified_home() ? at_limit : origin_active()) {
    job_direction_ = direction;
    core_.claim(*this, now);
    core_.set_dir_output(direction > 0, now);
    restart_stall_windows(direction);  // no run of step 2 to judge at the stop (SPM30 5.4)
    return home_event(now, at_limit);
  }
  start_motion(*ramp, direction, std::nullopt, now);
}

void Axis::home_event(Tick now, bool at_limit) {
  bool origin = origin_active();
  switch (home_stage_) {
    case HomeStage::Seek:
      // Step 3: stop at once on the origin, or (limit-switch-qualified, STP100 3.2.3) on
      // the end limit of the direction of travel.
      if (limit_qualified_home() ? !at_limit : !origin) return;
      core_.halt_motion(now);
      break;
    case HomeStage::BackToOrigin:
      if (origin) {
        home_stage_ = HomeStage::Clear;  // step 5: keep going till inactive for 50 ms
        origin_inactive_since_.reset();
      }
      return;
    case HomeStage::Clear:
      if (origin) origin_inactive_since_.reset();
      else if (!origin_inactive_since_) origin_inactive_since_ = now;
      return;
    case HomeStage::Approach:
      if (!origin) return;
      core_.halt_motion(now);  // step 7: precisely at home
      break;
  }
  // Here after a halt in Seek (origin, or limit when qualified) or at the end of Approach:
  // the run that ended is judged for a stall over its last steps (SPM30 5.4).
  if (stalled_at_motion_end()) return latch(status::kMotorStalled, now);
  if (home_stage_ == HomeStage::Seek && config_.home_method == AxisConfig::HomeMethod::Normal) {
    // Step 4: back at base velocity till the origin is active again. Whether it still is
    // active is decided as each step of that run is due (advance_to), not here at the stop:
    // a load that coasted past the origin ("just in case we shot right past home", SPM30 4
    // FIND HOME step 4) must come back to it; one still on it goes straight on to step 5.
    home_stage_ = HomeStage::BackToOrigin;
    origin_inactive_since_.reset();
    start_base_run(-job_direction_, now);
    job_direction_ = core_.generator().direction();
    return;
  }
  // Step 8: the destination becomes motor position, and encoder position "if axis 1 is
  // selected" (SPM30 4 FIND HOME step 7).
  core_.set_position(words_.destination);
  if (core_.selected() == 0) encoder_offset_ += words_.destination - encoder_position();
  position_valid_ = true;
  job_ = Job::None;
  core_.release(*this);
  notify(AxisEvent::MoveDone);
}

std::optional<Tick> Axis::deadline() const {
  // The 50 ms dwell of FIND HOME step 5 ends between steps at base velocity.
  if (job_ == Job::Home && home_stage_ == HomeStage::Clear && origin_inactive_since_)
    return *origin_inactive_since_ + kOriginDwellTicks;
  return std::nullopt;
}

void Axis::at_deadline(Tick when) {
  core_.halt_motion(when);
  if (stalled_at_motion_end()) return latch(status::kMotorStalled, when);  // the step 4-5 run
  home_stage_ = HomeStage::Approach;  // step 6: reverse, base velocity, to the origin
  origin_inactive_since_.reset();
  start_base_run(-job_direction_, when);
  job_direction_ = core_.generator().direction();
}

void Axis::before_step() {
  // FIND HOME step 4 ends when the origin is active again; that includes before the first
  // step back (still on it after the stop) and after the load was moved by hand.
  if (job_ == Job::Home && home_stage_ == HomeStage::BackToOrigin && origin_active()) {
    home_stage_ = HomeStage::Clear;
    origin_inactive_since_.reset();
  }
}

}  // namespace stepnode::motion
