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

int sign(int64_t v) { return v < 0 ? -1 : +1; }

}  // namespace

Drive::Drive(motion::AxisCore& core) : core_(core) {
  core_.listen(*this, this);
  power_up(0);
}

void Drive::power_up(Tick now) {
  (void)now;
  machine_.power_on();  // transitions 0 and 1
  controlword_ = 0;
  mode_display_ = mode_;
  active_.reset();
  next_.reset();
  last_target_.reset();
  acknowledged_ = internal_limit_ = halted_ = stopping_for_machine_ = restart_after_stop_ = false;
  velocity_after_stop_.reset();
  in_window_since_.reset();
  target_reached_ = true;
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
  if (r.phase_per_step == motion::kClockHz * grid_) return motion::slope_ticks_per_level(decel, grid_);
  // Another grid: ticks per level = kClockHz^2 / (decel * phase_per_step), to 1/4096 tick.
  const double ticks = static_cast<double>(motion::kClockHz) * static_cast<double>(motion::kClockHz) /
                       (static_cast<double>(decel) * static_cast<double>(r.phase_per_step));
  return motion::Rational{std::max<int64_t>(1, std::llround(ticks * 4096)), 4096};
}

void Drive::carry_out(Stop stop, Tick now) {
  switch (stop) {
    case Stop::None: return;
    case Stop::DisableDrive:
      // The drive function is disabled: the pulses stop now, whichever front end moves.
      core_.abort(this, now);
      break;
    case Stop::Immediate:
      core_.abort(this, now);  // current/voltage limit: the fastest stop that holds the motor
      break;
    case Stop::SlowDownRamp:
      core_.stop(now);
      break;
    case Stop::QuickStopRamp:
      core_.stop(now, quick_stop_slope());
      break;
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
    if (mode_display_ == Mode::ProfilePosition && !halted_ && (cw & cw_pp::kNewSetPoint) &&
        !(previous & cw_pp::kNewSetPoint))
      new_set_point(cw, now);
    // PV follows the target velocity whenever operation is enabled and not halted.
    if (mode_display_ == Mode::ProfileVelocity && !halted_ && (!was_enabled || (previous & cw::kHalt)))
      velocity_to(target_velocity_, now);
  } else {
    halted_ = false;
  }
  notify();
}

void Drive::set_mode(Mode mode, Tick now) {
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
    core_.stop(now);
  }
  if (mode_display_ == Mode::ProfileVelocity && mode_ == mode_display_ && machine_.operation_enabled() && !halted_)
    velocity_to(target_velocity_, now);
  notify();
}

void Drive::set_target_velocity(int32_t steps_per_s, Tick now) {
  target_velocity_ = steps_per_s;
  if (mode_display_ != Mode::ProfileVelocity || mode_ != mode_display_ || !machine_.operation_enabled() || halted_)
    return;
  core_.advance_to(now);
  velocity_to(steps_per_s, now);
  notify();
}

void Drive::halt(bool on, Tick now) {
  halted_ = on;
  if (!on || !core_.owned_by(*this)) return;
  if (homing_ == Homing::InProgress) homing_ = Homing::Idle;  // interrupted
  // 605Dh: the motion stops and the drive stays in Operation enabled; a PP set-point is
  // given up (a new one is needed after the halt), PV resumes its target when released.
  active_.reset();
  next_.reset();
  restart_after_stop_ = false;
  velocity_after_stop_.reset();
  switch (machine_.halt_stop()) {
    case Stop::QuickStopRamp: core_.stop(now, quick_stop_slope()); break;
    case Stop::Immediate:
    case Stop::DisableDrive: core_.halt(*this, now); break;
    default: core_.stop(now); break;
  }
}

// ---- profile position -----------------------------------------------------------------

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
  SetPoint sp{clamp_to_limits(base + target_position_)};
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
    if (active_) next_ = sp;  // carried out when the running one is done
    else active_ = sp, start_positioning(sp, now);
    return;
  }
  // Change set immediately: the new target replaces the running one. On the way and far
  // enough to ramp down: the end point moves; otherwise stop, then go there.
  active_ = sp;
  next_.reset();
  const motion::StepGenerator& g = core_.generator();
  const int64_t ahead = (sp.target - core_.position()) * g.direction();
  const int64_t to_stop = static_cast<int64_t>(g.ramp().decel_phase(g.level()) / g.ramp().phase_per_step) + 2;
  if (!g.stopping() && g.remaining() && ahead >= to_stop) {
    core_.retarget(now, ahead, g.ramp());
  } else {
    restart_after_stop_ = true;
    core_.stop(now);
  }
}

motion::RampSpec Drive::ramp(uint32_t velocity) const {
  const int64_t v = std::clamp<int64_t>(velocity, 1, std::max<uint32_t>(parameters_.max_velocity, 1));
  const int64_t acc = std::max<uint32_t>(parameters_.acceleration, 1);
  const int64_t dec = std::max<uint32_t>(parameters_.deceleration, 1);
  return motion::profile_ramp(v, acc, dec, grid_);
}

void Drive::start_positioning(const SetPoint& sp, Tick now) {
  const int64_t distance = sp.target - core_.position();
  if (distance == 0) {
    active_.reset();
    in_window_since_ = now;  // already there
    return;
  }
  grid_ = motion::profile_levels_per_hz(std::max(parameters_.acceleration, parameters_.deceleration));
  if (!core_.start(*this, ramp(parameters_.profile_velocity), sign(distance), std::llabs(distance), now))
    active_.reset();
}

// ---- profile velocity -----------------------------------------------------------------

void Drive::velocity_to(int64_t target, Tick now) {
  target = std::clamp<int64_t>(target, -int64_t{parameters_.max_velocity}, parameters_.max_velocity);
  if (!core_.owned_by(*this)) {
    if (target == 0 || core_.busy()) return;
    grid_ = motion::profile_levels_per_hz(std::max(parameters_.acceleration, parameters_.deceleration));
    core_.start(*this, ramp(static_cast<uint32_t>(std::llabs(target))), sign(target), std::nullopt, now);
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
}

// ---- the core's events ----------------------------------------------------------------

void Drive::after_step(const motion::Step& step) {
  if (homing_ == Homing::InProgress) return homing_step(step);
  // A limit switch in the direction of travel: no step goes past it (a fault, 8612h).
  const bool limit = step.direction < 0 ? core_.inputs().lower_limit() : core_.inputs().upper_limit();
  if (!limit) return;
  core_.halt(*this, step.time);
  active_.reset();
  next_.reset();
  restart_after_stop_ = false;
  velocity_after_stop_.reset();
  carry_out(machine_.fault(kReferenceLimit), step.time);
}

void Drive::motion_ended(Tick when) {
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
  connection_lost_ = option_6007 != option::kAbortNoAction && option_6007 != option::kAbortDisableVoltage &&
                     option_6007 != option::kAbortQuickStop;
  carry_out(machine_.abort_connection(option_6007), now);
  notify();
}

void Drive::advance(Tick now) { core_.advance_to(now); }

void Drive::advanced(Tick now) {
  if (stopping_for_machine_ && !core_.moving()) stopped(now);
  check_following_error(now);
  // 6062h: the interpolated trajectory in CSP and IP; otherwise (open loop) the steps given.
  const bool interpolating = mode_display_ == Mode::CyclicSyncPosition || mode_display_ == Mode::InterpolatedPosition;
  demand_ = interpolating && core_.owned_by(*this) ? static_cast<int32_t>(cyclic_demand(now)) : core_.position();
  machine_.set_fault_condition_active(core_.estop_active() || connection_lost_);
  // The e-stop input is a fault whether or not the axis moves (the core tells of it only
  // when it ends a job).
  const State st = machine_.state();
  if (core_.estop_active() && st != State::Fault && st != State::FaultReactionActive)
    carry_out(machine_.fault(kExternalError), now);
  // Target reached (PP): the trajectory is at the target and has been inside the position
  // window (6067h) for the window time (6068h); halted: the velocity is 0.
  const Tick window = static_cast<Tick>(parameters_.position_window_time_ms) * motion::kClockHz / 1000;
  if (halted_) target_reached_ = !core_.moving();
  else if (active_ || core_.owned_by(*this)) target_reached_ = false;
  else if (in_window_since_) target_reached_ = now - *in_window_since_ >= window;
  else target_reached_ = true;  // no set-point since power-up: standing where it is
  notify();
}

// ---- what the master reads ----------------------------------------------------------

int32_t Drive::velocity_actual() const {
  const motion::StepGenerator& g = core_.generator();
  return static_cast<int32_t>(std::lround(g.velocity() * g.direction()));
}

uint32_t Drive::digital_inputs() const {
  const motion::InputLevels& m = core_.inputs();
  return (m.lower_limit() ? 1u : 0u) | (m.upper_limit() ? 2u : 0u) | (m.home() ? 4u : 0u);
}

uint16_t Drive::statusword() const {
  uint16_t s = machine_.statusword();
  if (internal_limit_) s |= sw::kInternalLimitActive;
  switch (mode_display_) {
    case Mode::ProfilePosition:
      if (target_reached_) s |= sw::kTargetReached;
      if (acknowledged_ || (active_ && next_)) s |= sw_mode::kSetPointAcknowledge;
      break;
    case Mode::ProfileVelocity: {
      const motion::StepGenerator& g = core_.generator();
      const bool moving = core_.moving();
      const int64_t want = std::llabs(int64_t{target_velocity_});
      // Velocity reached: running at the target (its level), or stopped for a 0 target.
      const bool reached = halted_ ? !moving
                                   : (want == 0 ? !moving
                                                : moving && core_.owned_by(*this) &&
                                                      g.level() == want * grid_ &&
                                                      g.phase() != motion::MotionPhase::Accelerating &&
                                                      g.phase() != motion::MotionPhase::Decelerating);
      if (reached) s |= sw::kTargetReached;
      if (!moving) s |= sw_mode::kSpeedZero;
      break;
    }
    case Mode::Homing:
      // CiA 402-2 homing status: 13/12/10 = 0/0/1 not started or interrupted, 0/0/0 in
      // progress, 0/1/1 completed, 1/0/x error (bit 10: the velocity is 0).
      switch (homing_) {
        case Homing::Idle: s |= core_.owned_by(*this) ? 0 : sw::kTargetReached; break;
        case Homing::InProgress: break;
        case Homing::Attained: s |= sw_mode::kHomingAttained | sw::kTargetReached; break;
        case Homing::Error: s |= sw_mode::kHomingError | (core_.moving() ? 0 : sw::kTargetReached); break;
      }
      break;
    case Mode::CyclicSyncPosition:
    case Mode::CyclicSyncVelocity: {
      // Bit 12: the drive follows the command value (enabled, not halted, no other front
      // end's job); bit 13 (CSP): following error.
      const bool follows = machine_.operation_enabled() && !halted_ && (!core_.busy() || core_.owned_by(*this));
      if (follows) s |= sw_mode::kDriveFollows;
      if (following_error_ && mode_display_ == Mode::CyclicSyncPosition) s |= sw_mode::kFollowingError;
      break;
    }
    case Mode::InterpolatedPosition:
      if (machine_.operation_enabled() && (controlword_ & kEnableIp)) s |= sw_mode::kIpModeActive;
      if (!core_.owned_by(*this) && core_.position() == seg_to_) s |= sw::kTargetReached;
      if (following_error_) s |= sw_mode::kFollowingError;
      break;
    default: break;
  }
  return s;
}

// ---- homing ---------------------------------------------------------------------------

HomingInputs Drive::homing_inputs() const {
  const motion::InputLevels& m = core_.inputs();
  return HomingInputs{m.lower_limit(), m.upper_limit(), m.home(), m.marker()};
}

void Drive::start_homing(Tick now) {
  if (core_.busy()) return;  // another front end's job, or still stopping
  auto plan = homing_plan(parameters_.homing_method, core_.inputs().home());
  if (!plan) {
    homing_ = Homing::Error;  // 6098h names no method this drive performs
    return;
  }
  searches_ = std::move(*plan);
  search_ = 0;
  search_stopping_ = false;
  homing_ = Homing::InProgress;
  if (searches_.empty()) return homing_done(true, now);  // 35, 37: here
  run_search(now);
}

void Drive::run_search(Tick now) {
  if (search_ >= searches_.size()) return homing_done(false, now);
  const HomingSearch& s = searches_[search_];
  const uint32_t speed = s.fast ? parameters_.homing_switch_speed : parameters_.homing_zero_speed;
  const int64_t v = std::clamp<int64_t>(speed, 1, std::max<uint32_t>(parameters_.max_velocity, 1));
  const int64_t acc = std::max<uint32_t>(parameters_.homing_acceleration, 1);
  grid_ = motion::profile_levels_per_hz(acc);
  last_inputs_ = homing_inputs();
  if (!core_.start(*this, motion::profile_ramp(v, acc, acc, grid_), s.direction, std::nullopt, now))
    homing_ = Homing::Idle;
}

void Drive::homing_step(const motion::Step& step) {
  const HomingInputs in = homing_inputs();
  const HomingInputs before = last_inputs_;
  last_inputs_ = in;
  if (search_stopping_) return;  // ramping down after an edge: the next search looks again
  const HomingSearch& s = searches_[search_];
  if (happened(s.until, before, in)) {
    switch (s.then) {
      case HomingSearch::Then::Stop:
        search_stopping_ = true;
        return core_.stop(step.time);
      case HomingSearch::Then::Continue:
        ++search_;
        return;
      case HomingSearch::Then::Home:
        core_.halt(*this, step.time);
        return homing_done(true, step.time);
    }
  }
  // A limit switch the search does not look for: the method cannot be performed here.
  const bool limit = step.direction < 0 ? in.negative_limit : in.positive_limit;
  const bool wanted = s.until == (step.direction < 0 ? HomingEvent::NegativeLimitOn : HomingEvent::PositiveLimitOn);
  if (limit && !wanted) {
    core_.halt(*this, step.time);
    homing_done(false, step.time);
  }
}

void Drive::homing_done(bool ok, Tick now) {
  (void)now;
  homing_ = ok ? Homing::Attained : Homing::Error;
  // The home position is the home offset (607Ch): position actual reads it there.
  if (ok) core_.set_position(parameters_.home_offset);
}

void Drive::notify() {
  const uint16_t s = statusword();
  if (s == last_status_) return;
  last_status_ = s;
  if (on_status_changed) on_status_changed();
}

}  // namespace stepnode::cia402
