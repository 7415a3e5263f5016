#include "node/motion/axis_core.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace stepnode::motion {
namespace {
constexpr Tick kNever = std::numeric_limits<Tick>::max();  // later than any `now`
}  // namespace

AxisCore::AxisCore(const std::vector<MotorPort*>& motors) {
  if (motors.empty()) throw std::invalid_argument("an axis needs at least one motor");
  for (MotorPort* m : motors) motors_.push_back({m, m->levels()});
  selected_motor_ = motors_.data();
}

void AxisCore::set_owner(FrontEnd* owner) {
  owner_ = owner;
  waiting_ = false;
  hooks_ = owner ? owner->hooks() : FrontEnd::Hooks{};
  update_rounds();
}

void AxisCore::update_rounds() {
  direct_steps_ = horizon_ <= 0 && !hooks_.pulse;
  step_rounds_ = owner_ && !waiting_ && !hooks_.deadline && !hooks_.before_step;
  step_rule_ = owner_ && (hooks_.every_step ||
                          (selected_motor_->levels.active & hooks_.step_rule_inputs) != 0);
  rule_position_ = owner_ && hooks_.step_rule_position ? *hooks_.step_rule_position : kNoPosition;
}

void AxisCore::power_up(Tick now) {
  now_ = std::max(now_, now);
  // The inputs as they are now (a back end reports its levels at power-up); the edges
  // before it are history.
  InputEdge old;
  for (Motor& m : motors_) {
    while (m.port->next_edge(old)) {
    }
    m.levels = m.port->levels();
  }
  generator_.halt(now);
  replan(now);
  set_owner(nullptr);
  position_ = 0;
  select(0);
}

bool AxisCore::start(FrontEnd& by, const RampSpec& ramp, int direction,
                     std::optional<int64_t> steps, Tick now, Tick dir_setup) {
  if (owner_ != &by && busy()) return false;  // one job at a time
  const bool first = owner_ != &by;
  set_owner(&by);  // the hooks of this motion (a homing's next stage may differ)
  set_dir_output(direction > 0, now);
  generator_.start(ramp, now, direction, steps);
  if (dir_setup > 0) {
    // The first step comes one step period after the start: only a period shorter than the
    // setup time left since DIR changed moves the whole motion later, by the difference.
    const Tick ready = dir_changed_at_ + dir_setup;
    const std::optional<Tick> first_step = generator_.peek();
    if (first_step && *first_step < ready)
      generator_.start(ramp, now + (ready - *first_step), direction, steps);
  }
  replan(now);
  if (first)
    for (const Listener& l : listeners_) l.listener->job_started(by, now);
  return true;
}

bool AxisCore::claim(FrontEnd& by, Tick now) {
  if (owner_ != &by && busy()) return false;
  const bool first = owner_ != &by;
  set_owner(&by);
  waiting_ = true;
  update_rounds();
  if (first)
    for (const Listener& l : listeners_) l.listener->job_started(by, now);
  return true;
}

void AxisCore::release(const FrontEnd& by) {
  if (owner_ == &by) set_owner(nullptr);
}

void AxisCore::abort(const FrontEnd* by, Tick at) {
  generator_.halt(at);
  replan(at);
  FrontEnd* was = owner_;
  set_owner(nullptr);
  if (was && was != by) was->aborted(at);
}

void AxisCore::halt(const FrontEnd& by, Tick at) {
  if (owner_ != &by) return;
  generator_.halt(at);
  replan(at);
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

void AxisCore::watch_inputs(const AxisListener& listener, bool on) {
  input_watchers_ = 0;
  for (Listener& l : listeners_) {
    if (l.listener == &listener) l.inputs = on;
    input_watchers_ += l.inputs;
  }
}

void AxisCore::replan(Tick at) {
  horizon_ = port().horizon();
  update_rounds();
  if (horizon_ <= 0) return;
  port().cancel_after(at);
  planner_ = generator_;
  plan();
}

void AxisCore::plan() {
  // The planner computes the same steps the core will take, up to the horizon; the port
  // keeps them until their time.
  const Tick until = now_ + horizon_;
  StepPort& out = port();
  for (;;) {
    std::optional<Tick> t = planner_.peek();
    if (!t || *t > until) return;
    Step s;
    planner_.next(s);
    if (hooks_.pulse) out.queue_pulse(s.time, owner_->pulse(s));
    else out.queue(s.time, s.direction);
  }
}

// Inline: advance_to's step loops are the hot path of every mode.
inline void AxisCore::take(const Step& step) {
  if (direct_steps_) [[likely]]
    port().step(step.time, step.direction);  // the step sink
  else send(step);
  position_ += step.direction;
  // The edges the step made (a switch reached) come before any rule. Only the motor that
  // stepped can have one; the flag is looked at inline (most steps make none).
  if (selected_motor_->port->edges_waiting() || step_watchers_ != 0) [[unlikely]]
    after_take(step);
}

void AxisCore::send(const Step& step) {
  StepPort& out = port();
  if (horizon_ > 0) out.flush(step.time);  // the planner queued it: its time has come
  else if (hooks_.pulse) out.output_pulse(step.time, owner_->pulse(step));
  else out.step(step.time, step.direction);
  if (hooks_.pulse) owner_->pulse_sent(step);
}

void AxisCore::after_take(const Step& step) {
  if (selected_motor_->port->edges_waiting()) read_inputs();
  if (step_watchers_ == 0) return;
  for (const Listener& l : listeners_)
    if (l.steps && (!owner_ || l.self != owner_)) l.listener->step_taken(step);
}

void AxisCore::read_inputs() {
  InputEdge edge;
  bool any = false;
  for (unsigned m = 0; m < motors_.size(); ++m)
    while (motors_[m].port->edges_waiting() && motors_[m].port->next_edge(edge)) {
      any = true;
      motors_[m].levels.set(edge.input, edge.active);
      if (input_watchers_ == 0) continue;
      for (const Listener& l : listeners_)
        if (l.inputs) l.listener->input_changed(m, edge);
    }
  if (any) update_rounds();  // the owner's step_rule_inputs may be active now, or no longer
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

void AxisCore::take_due(Tick now) {
  // A motion whose rounds are only steps (step_rounds_) with the e-stop off: of a round's
  // looks only the ones a step or its rule can change are made. The e-stop changes only
  // with an edge (take reads them), the wait and the hooks only with the job (a rule that
  // halts or starts a motion ends the loop); whatever is not a due step (no step left, a
  // ramp that ends between steps, the job's end) is the general round's.
  for (;;) {
    if (generator_.peek().value_or(kNever) > now) return;  // no step, or none due
    Step step;
    generator_.next(step);
    take(step);
    if (estop_active()) return emergency_stop(step.time);
    if (step_rule_ || position_ == rule_position_) owner_->after_step(step);
    if (!step_rounds_) return;
  }
}

// One round of advance_to: false when nothing is left to do up to `now`.
bool AxisCore::round(Tick now) {
  const bool pending = waiting_;
  // SPM30 3.3.1 / STP100 4.2.1: the e-stop input stops motion at once. It is not a function
  // of the position, so it is looked at before every step (and while a job waits): no step
  // goes out once it is active.
  if (estop_active() && (generator_.moving() || pending)) {
    emergency_stop(now);
    return true;
  }
  if (pending) {
    owner_->poll(now);
    if (waiting_) return false;
  }
  // (kNever for none: a plain tick, which the compiler follows through the inlined peek.)
  const Tick deadline = hooks_.deadline ? owner_->deadline().value_or(kNever) : kNever;
  std::optional<Tick> next = generator_.peek();
  if (!next && generator_.moving()) return !ramp_ends_later(now);
  if (deadline <= now && (!next || *next > deadline)) {
    owner_->at_deadline(deadline);
    return true;
  }
  if (!next || *next > now) {
    if (!generator_.moving() && owner_ && !waiting_) {
      FrontEnd* done = owner_;
      set_owner(nullptr);
      done->motion_ended(generator_.time());
      return true;
    }
    return false;
  }
  if (hooks_.before_step) owner_->before_step();
  Step step;
  generator_.next(step);
  take(step);
  if (estop_active()) {
    emergency_stop(step.time);
    return true;
  }
  if (step_rule_ || position_ == rule_position_) owner_->after_step(step);
  return true;
}

void AxisCore::advance_to(Tick now) {
  now_ = std::max(now_, now);
  read_inputs();  // what changed since the last advance (a switch moved, the e-stop)
  if (horizon_ > 0) plan();
  update_rounds();  // after a select()
  do {
    if (step_rounds_ && !estop_active()) take_due(now);
  } while (round(now));
  // Every step up to `now` is out; the back ends' clocks are at `now` (the time a change
  // made from outside before the next advance happened at).
  for (Motor& m : motors_) m.port->flush(now);
  if (horizon_ > 0) plan();
  for (const Listener& l : listeners_) l.listener->advanced(now);
}

}  // namespace stepnode::motion
