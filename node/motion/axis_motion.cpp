// The Horner front end on the motion core: what each step does to the job (limits, stall,
// position check, the index window, the homing stages) and how a job ends (repeat, resume).
#include <cstdlib>

#include "node/motion/axis.hpp"

namespace stepnode::motion {

FrontEnd::Hooks Axis::hooks() const {
  // The steps at which the rules of after_step can act (the core calls it at those only).
  // A Find Home (its stages), an indexed move till its index (the window) and the
  // encoder's checks look at every step; the other rules of a move or a jog act only at
  // an active end limit (SPM30 3.3.1) or at the position a jog's end on the bound is set
  // from (a move's step count is the generator's: move_done_steps()).
  const bool home = job_ == Job::Home;
  return {.deadline = home,
          .before_step = home,
          .every_step = home || (job_ == Job::Move && move_indexed_ && !index_taken_) ||
                        encoder_rules_every_step(),
          .step_rule_inputs = kLimitInputs,
          .step_rule_position = job_ == Job::Jog ? jog_end_from_ : std::nullopt};
}

void Axis::step_taken(const Step& step) {
  (void)step;
  // Another front end's job (the core gives the Horner jobs' steps to after_step): its rules
  // are its own, but the position check (STP100 6.3.2) is the module's, whoever moves the motor.
  check_position_valid();
}

void Axis::job_started(const FrontEnd& owner, Tick when) {
  (void)when;
  if (&owner == this) return;
  resumable_ = false;  // another front end moved the axis: nothing left to resume
  notify(AxisEvent::StatusChanged);
}

void Axis::job_halted(const FrontEnd& owner, Tick when) {
  (void)owner;
  (void)when;
  notify(AxisEvent::StatusChanged);
}

void Axis::aborted(Tick when) {
  end_job(when);  // the e-stop, or another front end's stop (emergency_stop latches %I1)
  waiting_for_limit_release_ = false;
}

void Axis::after_step(const Step& step) {
  Tick t = step.time;
  if (step.direction < 0 && inputs().lower_limit()) {
    if (job_ == Job::Home && home_stage_ == HomeStage::Seek && limit_qualified_home()) {
      return home_event(t, /*at_limit=*/true);
    }
    return latch(status::kLowerLimit, t);
  }
  if (step.direction > 0 && inputs().upper_limit()) {
    if (job_ == Job::Home && home_stage_ == HomeStage::Seek && limit_qualified_home()) {
      return home_event(t, /*at_limit=*/true);
    }
    return latch(status::kUpperLimit, t);
  }
  check_stall(step);
  if (errors_ & status::kMotorStalled) return;
  check_position_valid();
  if (job_ == Job::Home) return home_event(t);
  if (job_ == Job::Jog && core_.position() == jog_end_from_) {
    const int64_t bound = step.direction > 0 ? kPositionMax : kPositionMin;
    core_.retarget(t, std::llabs(bound - core_.position()), move_ramp_);
    jog_end_from_.reset();
    core_.hooks_changed(*this);  // no position rule left
  }
  if (job_ == Job::Move && move_indexed_ && !index_taken_) {
    // STP113 C1.3.4 / STP100 5.3.5: the index input counts only inside the window, which
    // opens at the running velocity and closes at the deceleration point. "The motor must
    // attain Running Velocity": the engine may also cruise below it (a short move capped at
    // STPCALC's peak), which does not open the window. The index counts when it "becomes
    // active" there: one already on when the window opened was "received before" it.
    bool index = inputs().index();
    bool became_active = index && !index_was_active_;
    index_was_active_ = index;
    const StepGenerator& g = core_.generator();
    bool window = g.phase() == MotionPhase::Running && g.level() >= move_ramp_.run_level &&
                  move_done_steps() >= int64_t{index_window_open_} &&
                  move_done_steps() < int64_t{index_window_close_};
    if (window && became_active) {
      index_taken_ = true;
      RampSpec alternate = move_ramp_;
      alternate.decel_ticks_per_level = index_ramp_.decel_ticks_per_level;
      // The new end point is N steps past the index (STP100 5.3.5: "defined to be N more
      // steps"); an N shorter than the deceleration ramp still ends there, decelerating to
      // the base velocity in the time that fits (README: "The Horner module's rules").
      fit_deceleration(alternate, g.level(), index_destination_);
      core_.retarget(t, index_destination_, alternate);
      move_target_steps_ = move_done_steps() + index_destination_;
      core_.hooks_changed(*this);  // the index is taken: no window left to look at
    }
  }
}

void Axis::finish(Tick now) {
  // The motion ran out: no step left to stop, but a stall over its last steps is latched.
  if (stalled_at_motion_end()) return latch(status::kMotorStalled, now);
  Job job = job_;
  end_job(now);
  if (job == Job::None) return;  // the Home a Decelerate and Stop ended (its ramp just ran out)
  if (job == Job::Home) return notify(AxisEvent::StatusChanged);  // stopped before home
  if (job == Job::Move) {
    if (move_done_steps_ >= move_target_steps_) {
      notify(AxisEvent::MoveDone);
      // STP100 5.3.6: a relative or indexed move repeats while %Q12 is on.
      if (move_repeatable_ && is_set(commands_, command::kRepeatMove) && !errors_)
        start_move(repeat_distance_, move_ramp_, now, move_indexed_);
      return;
    }
    // Stopped short by Decelerate and Stop: resumable unless an error came or it was indexed.
    if (preempted_move_resumable()) resumable_ = true;
  }
  notify(AxisEvent::MoveDone);
}

void Axis::poll(Tick now) {
  bool still = job_direction_ > 0 ? inputs().upper_limit() : inputs().lower_limit();
  if (still) return;
  waiting_for_limit_release_ = false;
  start_motion(move_ramp_, job_direction_, move_target_steps_ - move_done_steps_, now);
}

void Axis::advanced(Tick now) {
  (void)now;
  // STP100 6.3.2: motor and encoder positions are compared continuously, so an external force
  // on a standing motor (SPM30 5.4 item 6) turns %I9 off too, not only a step.
  check_position_valid();
  notify(AxisEvent::StatusChanged);
}
}  // namespace stepnode::motion
