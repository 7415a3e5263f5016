// The drive as a front end of the motion core: power-up, the master's writes, the state
// machine's stops and the core's events; the modes are drive_pp.cpp, drive_pv.cpp,
// drive_homing.cpp and drive_cyclic.cpp, what the master reads drive_status.cpp.
#include "node/profiles/cia402/drive.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace stepnode::cia402 {
namespace {

using motion::Tick;

// Error codes (603Fh, CiA 301 / CiA 402-2 error code table).
constexpr uint16_t kReferenceLimit = 0x8612;  // a limit switch was reached
constexpr uint16_t kExternalError = 0x9000;   // the e-stop input

}  // namespace

Drive::Drive(motion::AxisCore& core) : core_(core) {
  core_.listen(*this, this);
  power_up(0, Mode::ProfilePosition);
}

void Drive::power_up(Tick now, Mode mode) {
  (void)now;
  machine_.power_on();  // transitions 0 and 1
  controlword_ = 0;
  mode_ = mode_display_ = mode;  // 6060h as it is at power-up (0: no mode assigned)
  active_.reset();
  next_.reset();
  last_target_.reset();
  acknowledged_ = internal_limit_ = halted_ = stopping_for_machine_ = restart_after_stop_ = false;
  velocity_after_stop_.reset();
  in_window_since_.reset();
  target_reached_ = true;
  own_ramp_ = false;
  homing_ = Homing::Idle;
  search_stopping_ = false;
  connection_lost_ = false;
  last_status_ = statusword();
}

// ---- the state machine's stops -------------------------------------------------------

motion::Rational Drive::quick_stop_slope() const {
  // 6085h on the grid of whatever motion runs (the Horner registers' too).
  const motion::RampSpec& r = core_.generator().ramp();
  const int64_t decel = std::max<uint32_t>(parameters_.quick_stop_deceleration, 1);
  if (r.phase_per_step == motion::kClockHz * grid_)
    return motion::slope_ticks_per_level(decel, grid_);
  // Another grid: ticks per level = kClockHz^2 / (decel * phase_per_step), to 1/4096 tick.
  const double ticks = static_cast<double>(motion::kClockHz) *
                       static_cast<double>(motion::kClockHz) /
                       (static_cast<double>(decel) * static_cast<double>(r.phase_per_step));
  return motion::Rational{std::max<int64_t>(1, std::llround(ticks * 4096)), 4096};
}

void Drive::carry_out(Stop stop, Tick now) {
  switch (stop) {
    case Stop::None: return;
    // Disabled drive function: the pulses stop now, whichever front end moves. Immediate
    // (current or voltage limit): the fastest stop that holds the motor, the same for a stepper.
    case Stop::DisableDrive:
    case Stop::Immediate: core_.abort(this, now); break;
    case Stop::SlowDownRamp: ramp_down(false, now); break;
    case Stop::QuickStopRamp: ramp_down(true, now); break;
  }
  active_.reset();
  next_.reset();
  restart_after_stop_ = false;
  velocity_after_stop_.reset();
  csv_running_ = false;
  if (homing_ == Homing::InProgress) homing_ = Homing::Idle;  // interrupted
  if (machine_.stopping()) {
    stopping_for_machine_ = true;
    if (!core_.moving()) stopped(now);
  }
}

void Drive::ramp_down(bool quick, Tick now) {
  // A cyclic job has nothing to ramp down on: it is carried over to a ramp first (it
  // stopped at once: found in review).
  ramp_from_cyclic(now);
  if (quick) core_.stop(now, quick_stop_slope());
  else core_.stop(now);
}

void Drive::stopped(Tick now) {
  (void)now;
  stopping_for_machine_ = false;
  machine_.motion_stopped();
}

// ---- the master's writes ------------------------------------------------------------

void Drive::controlword(uint16_t cw, Tick now) {
  core_.advance_to(now);
  const uint16_t previous = controlword_;
  controlword_ = cw;
  const bool was_enabled = machine_.operation_enabled();
  carry_out(machine_.on_controlword(cw), now);
  if (!(cw & cw_pp::kNewSetPoint)) acknowledged_ = false;  // the handshake's second half
  if (machine_.operation_enabled()) {
    const bool halt_now = (cw & cw::kHalt) != 0;
    if (halt_now != halted_) halt(halt_now, now);
    if (mode_display_ == Mode::Homing && !halted_ && (cw & kHomingOperationStart) &&
        !(previous & kHomingOperationStart))
      start_homing(now);
    // HM bit 4: "1 = start or continue homing"; taken back while homing runs, the homing
    // is interrupted (status 0/0/1 once stopped; it ran on to its end: found in review).
    if (mode_display_ == Mode::Homing && homing_ == Homing::InProgress &&
        !(cw & kHomingOperationStart) && (previous & kHomingOperationStart))
      interrupt_homing(now);
    if (mode_display_ == Mode::ProfilePosition && !halted_ && (cw & cw_pp::kNewSetPoint) &&
        !(previous & cw_pp::kNewSetPoint))
      new_set_point(cw, now);
    // PV follows the target velocity whenever operation is enabled and not halted.
    if (mode_display_ == Mode::ProfileVelocity && !halted_ &&
        (!was_enabled || (previous & cw::kHalt)))
      velocity_to(target_velocity_, now);
  } else {
    halted_ = false;
  }
  notify();
}

void Drive::set_mode(Mode mode, Tick now) {
  // 6060h 0: "no mode change / no mode assigned". A master that maps 6060h beside 6040h
  // and leaves it 0 keeps the mode it chose (0 stopped the motion and showed mode 0: found
  // in review); before any mode was chosen it is the mode assigned, none.
  if (mode == Mode::None && mode_ != Mode::None) return;
  core_.advance_to(now);
  const bool changed = mode != mode_;
  mode_ = mode;
  // The mode changes once the drive's own motion has ended: a running motion of the old
  // mode ramps down (6084h) first (CiA 402-2 leaves the moment to the drive); 6061h shows
  // the new mode from then on.
  if (!core_.owned_by(*this)) {
    mode_display_ = mode_;
    active_.reset();
    next_.reset();
  } else if (changed && mode_ != mode_display_) {
    active_.reset();
    next_.reset();
    restart_after_stop_ = false;
    velocity_after_stop_.reset();
    csv_running_ = false;
    if (homing_ == Homing::InProgress) homing_ = Homing::Idle;
    ramp_down(false, now);
  }
  if (mode_display_ == Mode::ProfileVelocity && mode_ == mode_display_ &&
      machine_.operation_enabled() && !halted_)
    velocity_to(target_velocity_, now);
  notify();
}

void Drive::halt(bool on, Tick now) {
  halted_ = on;
  if (!on) return resume_after_halt(now);
  if (!core_.owned_by(*this)) return;
  if (homing_ == Homing::InProgress) homing_ = Homing::Idle;  // interrupted
  // 605Dh: the motion stops and the drive stays in Operation enabled. PP keeps its
  // set-points: bit 8 = 0 "positioning shall be executed or continued" (they were given
  // up, and target reached then showed 1 short of the target: found in review); the next
  // one no longer runs on through the first target. PV resumes its target when released.
  if (mode_display_ == Mode::ProfilePosition) {
    if (next_) next_->through = false;
  } else {
    active_.reset();
    next_.reset();
  }
  restart_after_stop_ = false;
  velocity_after_stop_.reset();
  switch (machine_.halt_stop()) {
    case Stop::QuickStopRamp: ramp_down(true, now); break;
    case Stop::Immediate:
    case Stop::DisableDrive: core_.halt(*this, now); break;
    default: ramp_down(false, now); break;
  }
}

void Drive::resume_after_halt(Tick now) {
  // PP: the set-point the halt stopped goes on from where the axis is (once the halt's
  // ramp has ended, if it still runs).
  if (mode_display_ != Mode::ProfilePosition || !active_) return;
  if (core_.owned_by(*this)) restart_after_stop_ = true;
  else start_positioning(*active_, now);
}

void Drive::interrupt_homing(Tick now) {
  homing_ = Homing::Idle;
  search_stopping_ = false;
  if (core_.owned_by(*this)) core_.stop(now);
}

// ---- the core's events ----------------------------------------------------------------

motion::FrontEnd::Hooks Drive::hooks() const {
  // after_step's rules: homing's and a queued set-point's (change on set-point) look at
  // every step; otherwise the rules are the stop at a limit switch and, in the velocity
  // modes, the stop before a software limit (607Dh, drive_limits.cpp).
  return {.every_step = homing_ == Homing::InProgress || next_.has_value(),
          .step_rule_inputs = motion::kLimitInputs,
          .step_rule_position = limit_rule_};
}

void Drive::after_step(const motion::Step& step) {
  if (homing_ == Homing::InProgress) return homing_step(step);
  // A limit switch in the direction of travel: no step goes past it (a fault, 8612h).
  const motion::InputLevels& in = core_.inputs();
  if (step.direction < 0 ? in.lower_limit() : in.upper_limit()) [[unlikely]]
    return stop_at_limit(step.time);
  // A software limit ahead (607Dh): its brake point, or the limit itself.
  if (limit_rule_ && core_.position() == *limit_rule_ && step.direction == limit_direction_)
      [[unlikely]]
    return at_limit_rule(step.time);
  // Change on set-point: on the first target the next set-point takes over (drive_pp.cpp).
  if (next_ && next_->through && active_ && core_.position() == active_->target)
    pass_first_target(step.time);
}

// Out of line, so that after_step, every step's rule, stays a leaf.
[[gnu::noinline]] void Drive::stop_at_limit(Tick at) {
  core_.halt(*this, at);
  active_.reset();
  next_.reset();
  restart_after_stop_ = false;
  velocity_after_stop_.reset();
  carry_out(machine_.fault(kReferenceLimit), at);
}

void Drive::motion_ended(Tick when) {
  limit_rule_.reset();                // the motion's rule ends with it
  if (stopping_for_machine_) return;  // advanced() completes the transition
  if (homing_ == Homing::InProgress && search_stopping_) {
    search_stopping_ = false;
    ++search_;
    return run_search(when);
  }
  if (restart_after_stop_ && active_) {
    restart_after_stop_ = false;
    return start_positioning(*active_, when);
  }
  if (halted_ && mode_display_ == Mode::ProfilePosition && active_ && mode_ == mode_display_)
    return;  // stopped by the halt: its set-points wait for the release
  if (velocity_after_stop_) {
    const int64_t v = *velocity_after_stop_;
    velocity_after_stop_.reset();
    if (mode_display_ == Mode::ProfileVelocity && machine_.operation_enabled() && !halted_)
      velocity_to(v, when);
    return;
  }
  if (active_ && next_) {
    active_ = next_;
    next_.reset();
    return start_positioning(*active_, when);
  }
  if (active_) in_window_since_ = when;
  active_.reset();
  if (mode_display_ == mode_) return;
  mode_display_ = mode_;  // a mode change waited for the motion's end
  if (mode_display_ == Mode::ProfileVelocity && machine_.operation_enabled() && !halted_)
    velocity_to(target_velocity_, when);
}

void Drive::aborted(Tick when) {
  (void)when;
  limit_rule_.reset();
  if (homing_ == Homing::InProgress) homing_ = Homing::Idle;
  active_.reset();
  next_.reset();
  restart_after_stop_ = false;
  velocity_after_stop_.reset();
}

void Drive::emergency_stop(Tick when, bool was_moving) {
  (void)was_moving;
  carry_out(machine_.fault(kExternalError), when);
  notify();
}

void Drive::fault(uint16_t error_code, Tick now) {
  core_.advance_to(now);
  carry_out(machine_.fault(error_code), now);
  notify();
}

void Drive::connection_lost(int16_t option_6007, Tick now) {
  core_.advance_to(now);
  // 6007h 1 (or another value: as 1) makes the loss a fault whose cause persists.
  connection_lost_ = option_6007 != option::kAbortNoAction &&
                     option_6007 != option::kAbortDisableVoltage &&
                     option_6007 != option::kAbortQuickStop;
  carry_out(machine_.abort_connection(option_6007), now);
  notify();
}

void Drive::advance(Tick now) { core_.advance_to(now); }

void Drive::advanced(Tick now) {
  if (stopping_for_machine_ && !core_.moving()) stopped(now);
  check_following_error(now);
  // 6062h: the interpolated trajectory in CSP and IP; otherwise (open loop) the steps given.
  const bool interpolating =
      mode_display_ == Mode::CyclicSyncPosition || mode_display_ == Mode::InterpolatedPosition;
  demand_ = interpolating && core_.owned_by(*this) && !own_ramp_
                ? static_cast<int32_t>(cyclic_demand(now))
                : core_.position();
  machine_.set_fault_condition_active(core_.estop_active() || connection_lost_);
  // The e-stop input is a fault whether or not the axis moves (the core tells of it only
  // when it ends a job).
  const State st = machine_.state();
  if (core_.estop_active() && st != State::Fault && st != State::FaultReactionActive)
    carry_out(machine_.fault(kExternalError), now);
  // Target reached (PP): the trajectory is at the target and has been inside the position
  // window (6067h) for the window time (6068h); halted: the velocity is 0.
  const Tick window =
      static_cast<Tick>(parameters_.position_window_time_ms) * motion::kClockHz / 1000;
  if (halted_) target_reached_ = !core_.moving();
  else if (active_ || core_.owned_by(*this)) target_reached_ = false;
  else if (in_window_since_) target_reached_ = now - *in_window_since_ >= window;
  else target_reached_ = true;  // no set-point since power-up: standing where it is
  notify();
}

std::optional<Tick> Drive::next_event(Tick now) const {
  std::optional<Tick> next;
  const auto sooner = [&next](Tick t) {
    if (!next || t < *next) next = t;
  };
  // As advanced() decides target reached: no set-point running, inside the window since.
  if (!halted_ && !active_ && !core_.owned_by(*this) && in_window_since_) {
    const Tick window =
        static_cast<Tick>(parameters_.position_window_time_ms) * motion::kClockHz / 1000;
    if (now - *in_window_since_ < window) sooner(*in_window_since_ + window);
  }
  if (following_error_since_ && !following_error_) {
    const Tick timeout = Tick{parameters_.following_error_timeout_ms} * motion::kClockHz / 1000;
    sooner(std::max(*following_error_since_ + timeout, now + 1));
  } else if (!following_error_since_) {
    if (const std::optional<Tick> leaves = following_error_exit(now)) sooner(*leaves);
  }
  return next;
}

void Drive::notify() {
  const uint16_t s = statusword();
  if (s == last_status_) return;
  last_status_ = s;
  if (on_status_changed) on_status_changed();
}

}  // namespace stepnode::cia402
