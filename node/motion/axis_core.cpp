#include "node/motion/axis_core.hpp"

#include <stdexcept>

namespace stepnode::motion {

AxisCore::AxisCore(std::vector<MotorPort*> motors, const bool* estop) : motors_(std::move(motors)), estop_(estop) {
  if (motors_.empty()) throw std::invalid_argument("an axis needs at least one motor");
}

void AxisCore::set_owner(FrontEnd* owner) {
  owner_ = owner;
  waiting_ = false;
  hooks_ = owner ? owner->hooks() : FrontEnd::Hooks{};
}

void AxisCore::power_up(Tick now) {
  generator_.halt(now);
  set_owner(nullptr);
  position_ = 0;
  selected_ = 0;
}

bool AxisCore::start(FrontEnd& by, const RampSpec& ramp, int direction, std::optional<int64_t> steps, Tick now) {
  if (owner_ != &by && busy()) return false;  // one job at a time
  const bool first = owner_ != &by;
  set_owner(&by);  // the hooks of this motion (a homing's next stage may differ)
  dir_high_ = direction > 0;
  generator_.start(ramp, now, direction, steps);
  if (first)
    for (const Listener& l : listeners_) l.listener->job_started(by, now);
  return true;
}

bool AxisCore::claim(FrontEnd& by, Tick now) {
  if (owner_ != &by && busy()) return false;
  const bool first = owner_ != &by;
  set_owner(&by);
  waiting_ = true;
  if (first)
    for (const Listener& l : listeners_) l.listener->job_started(by, now);
  return true;
}

void AxisCore::release(const FrontEnd& by) {
  if (owner_ == &by) set_owner(nullptr);
}

void AxisCore::abort(const FrontEnd* by, Tick at) {
  generator_.halt(at);
  FrontEnd* was = owner_;
  set_owner(nullptr);
  if (was && was != by) was->aborted(at);
}

void AxisCore::halt(const FrontEnd& by, Tick at) {
  if (owner_ != &by) return;
  generator_.halt(at);
  set_owner(nullptr);
  for (const Listener& l : listeners_) l.listener->job_halted(by, at);
}

void AxisCore::emergency_stop(Tick now) {
  const bool was_moving = generator_.moving();
  abort(nullptr, now);
  for (const Listener& l : listeners_) l.listener->emergency_stop(now, was_moving);
}

void AxisCore::watch_steps(const AxisListener& listener, bool on) {
  step_watchers_ = 0;
  for (Listener& l : listeners_) {
    if (l.listener == &listener) l.steps = on;
    step_watchers_ += l.steps;
  }
}

void AxisCore::take(const Step& step) {
  if (hooks_.pulse) motor().output_pulse(step.time, owner_->pulse(step));
  else motor().step(step.time, step.direction);  // the step sink
  position_ += step.direction;
  if (step_watchers_ == 0) return;
  for (const Listener& l : listeners_)
    if (l.steps && (!owner_ || l.self != owner_)) l.listener->step_taken(step);
}

bool AxisCore::ramp_ends_later(Tick now) {
  // The ramp ends between steps (a stop at base velocity): go idle when it ends.
  StepGenerator ahead = generator_;
  Step none;
  ahead.next(none);
  if (ahead.marks().end > now) return true;
  generator_.next(none);
  return false;
}

void AxisCore::advance_to(Tick now) {
  for (;;) {
    const bool pending = waiting_;
    // SPM30 3.3.1 / STP100 4.2.1: the e-stop input stops motion at once. It is not a function
    // of the position, so it is looked at before every step (and while a job waits): no step
    // goes out once it is active.
    if (estop_active() && (generator_.moving() || pending)) {
      emergency_stop(now);
      continue;
    }
    if (pending) {
      owner_->poll(now);
      if (waiting_) break;
    }
    std::optional<Tick> deadline = hooks_.deadline ? owner_->deadline() : std::nullopt;
    std::optional<Tick> next = generator_.peek();
    if (!next && generator_.moving()) {
      if (ramp_ends_later(now)) break;
      continue;
    }
    if (deadline && *deadline <= now && (!next || *next > *deadline)) {
      owner_->at_deadline(*deadline);
      continue;
    }
    if (!next || *next > now) {
      if (!generator_.moving() && owner_ && !waiting_) {
        FrontEnd* done = owner_;
        set_owner(nullptr);
        done->motion_ended(generator_.time());
        continue;
      }
      break;
    }
    if (hooks_.before_step) owner_->before_step();
    Step step;
    generator_.next(step);
    take(step);
    if (estop_active()) {
      emergency_stop(step.time);
      continue;
    }
    if (owner_) owner_->after_step(step);
  }
  for (const Listener& l : listeners_) l.listener->advanced(now);
}

}  // namespace stepnode::motion
