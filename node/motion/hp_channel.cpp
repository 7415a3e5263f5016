#include "node/motion/hp_channel.hpp"

#include <algorithm>
#include <cmath>

namespace stepnode::motion::hp {
namespace {

constexpr Tick kStandbyAutoOffTicks = kClockHz;  // "a one second delay in powering off" (3-6)

Tick seconds_to_ticks(double s) { return static_cast<Tick>(std::llround(s * static_cast<double>(kClockHz))); }

}  // namespace

Channel::Channel(AxisCore& core) : core_(core) {
  core_.listen(*this);
  core_.watch_inputs(*this, true);  // HALT acts whatever runs
  power_up(0);
}

OutputPulse Channel::pulse(const Step& s) const {
  // PULSE SD|SS: the output the pulse appears at and the levels (3-7, Figure 3-1).
  const Pulse p = pulse_for(pulse_, s.direction);
  OutputPulse out;
  out.step_direction = pulse_.mode == PulseMode::StepDirection;
  out.on_ndir = p.output == Output::Ndir;
  out.ndir_level = p.ndir_level;
  out.ndir_positive_level = pulse_.ndir_high;
  out.pstp_level = p.pstp_level;
  return out;
}

void Channel::pulse_sent(const Step& s) {
  last_pulse_ = pulse_for(pulse_, s.direction);
  ++pulse_count_[static_cast<unsigned>(last_pulse_.output)];
}

void Channel::input_changed(unsigned motor, const InputEdge& edge) {
  if (motor != core_.selected()) return;
  if (edge.input == Input::Halt) return halt_input_changed(edge.time);
  // QINDEX ONCE: counting begins on the leading edge of the first index pulse (3-21).
  if (edge.input == Input::Marker && edge.active && q_waiting_for_index_) {
    q_offset_ = core_.motor().encoder_count();
    q_waiting_for_index_ = q_frozen_ = false;
  }
}

void Channel::start_job(const RampSpec& ramp, int direction, std::optional<int64_t> steps, Tick at) {
  core_.advance_to(at);
  core_.start(*this, ramp, direction, steps, at);
}

void Channel::power_up(Tick now) {
  (void)now;
  profile_ = Profile{};
  position_ = PositionCounter{};
  delay_ms_ = 0;
  trig_ = TrigMode::Auto;
  standby_ = StandbyMode::Auto;
  standby_high_ = true;
  pulse_ = PulseSetup{};
  halt_mode_ = HaltMode::Lo;
  plim_high_ = nlim_high_ = false;
  qscale_ = 1.0;
  qindex_ = QIndexMode::Off;
  pending_ = Pending{};
  armed_ = blocking_ = false;
  start_at_.reset();
  run_ = Run::Idle;
  outcome_ = Done::Completed;
  last_error_ = Error::None;
  last_conflict_ = Conflict::None;
  intr_enabled_ = false;  // "After power-on ... all interrupts are disabled"
  events_ = 0;
  powered_ = false;
  idle_since_.reset();
  trigger_time_.reset();
  first_step_.reset();
  awaiting_first_step_ = false;
  q_offset_ = core_.motor().encoder_count();
  q_waiting_for_index_ = q_frozen_ = false;
}

Error Channel::accept(Error e) {
  last_error_ = e;
  return e;
}

// ---------------------------------------------------------------- set-up commands

Conflict Channel::profile(const Profile& given, Tick now, Error* error) {
  (void)now;
  Error e = (blocking_ || run_ != Run::Idle || start_at_ || core_.busy()) ? Error::AccessoryBusy : Error::None;
  if (error) *error = accept(e);
  if (e != Error::None) return Conflict::None;
  // "The scale factor of the PSCALE command affects the PROFILE ... commands" (3-9): FREQ
  // values are units/s of the PSCALE in effect when PROFILE is given; the engine keeps Hz.
  Profile hz = given;
  if (hz.mode == ProfileMode::Freq) {
    double s = std::fabs(position_.scale());
    hz.min /= s;
    hz.max /= s;
    hz.slope /= s;
  }
  last_conflict_ = check_profile(hz);
  if (last_conflict_ == Conflict::None) profile_ = hz;
  return last_conflict_;
}

Error Channel::pscale(double units_per_step) {
  if (blocking_ || run_ != Run::Idle || core_.busy()) return accept(Error::AccessoryBusy);
  position_.set_scale(units_per_step, core_.position());
  return accept(Error::None);
}

Error Channel::standby(StandbyMode mode, bool sense_high, Tick now) {
  if (blocking_) return accept(Error::AccessoryBusy);
  bool moving = run_ != Run::Idle || start_at_ || core_.busy();
  if (mode == StandbyMode::On && moving) return accept(Error::AccessoryBusy);  // power off under a move
  standby_ = mode;
  standby_high_ = sense_high;
  if (mode == StandbyMode::Off) powered_ = true;       // OFF = apply power
  else if (mode == StandbyMode::On) powered_ = false;  // ON = remove power
  else if (!moving && powered_) idle_since_ = now;     // AUTO: off a second after idle
  return accept(Error::None);
}

void Channel::halt_mode(HaltMode mode, Tick now) {
  halt_mode_ = mode;
  if (halt_active() && (run_ != Run::Idle || start_at_)) {
    core_.halt(*this, now);
    end(Done::Halted, intr::kHaltSwitch, now);
  }
}

// ---------------------------------------------------------------- output commands

Error Channel::check_can_move(bool width_allowed) const {
  if (!width_allowed && profile_.mode == ProfileMode::Width) return Error::NotValidInWidthMode;
  if (test_jumper_) return Error::TestJumperSet;
  if (standby_ == StandbyMode::On) return Error::CannotMoveWhileStandbyOn;
  return Error::None;
}

Error Channel::move(double distance, bool absolute, bool nowait, Tick now) {
  // 89 first: a move in progress (this channel's, or the axis' under the Horner registers).
  if (blocking_ || run_ != Run::Idle || start_at_ || core_.busy()) return accept(Error::AccessoryBusy);
  if (Error e = check_can_move(false); e != Error::None) return accept(e);
  int64_t steps = absolute ? position_.abs_steps(distance, core_.position()) : position_.rel_steps(distance);
  // A move that would outlast the engine's 64-bit clock (2^31 pulses at a 2.5 µHz maximum:
  // 27 million years) is refused: its deceleration tick overflowed.
  if (std::fabs(static_cast<double>(steps)) / std::max(profile_.max, kRateResolutionHz) > kLongestMoveS)
    return Error::ValueOutOfRange;
  return arm(Pending{Action::Move, steps, 0}, nowait, now);
}

Error Channel::sustain(double value, bool nowait, Tick now) {
  if (blocking_ || run_ == Run::Move || run_ == Run::SustainStopping || (start_at_ && pending_.action == Action::Move) ||
      (core_.busy() && !core_.owned_by(*this)))
    return accept(Error::AccessoryBusy);
  if (value != 0)
    if (Error e = check_can_move(true); e != Error::None) return accept(e);
  double rate = profile_.mode == ProfileMode::Freq ? position_.to_steps(value) : value;
  if (!std::isfinite(rate) || below_rate_resolution(rate)) return Error::ValueOutOfRange;
  // "A running SUSTAIN command must be stopped with HALT or SUSTAIN 0 before a command to
  // reverse direction can be executed" (error 91).
  if (run_ == Run::Sustain && rate != 0 && (rate > 0 ? +1 : -1) != direction_)
    return accept(Error::MustStopToChangeDirection);
  return arm(Pending{Action::Sustain, 0, rate}, nowait, now);
}

bool Channel::below_rate_resolution(double rate) const {
  // Appendix A: a rate resolved to 2.5 µHz. What the profile's clamp leaves of a rate
  // finer than that (a 0 minimum lets 1E-12 through) never reaches the engine.
  return profile_.mode == ProfileMode::Freq && rate != 0 &&
         clamp_to_profile(profile_, std::fabs(rate)) < kRateResolutionHz;
}

Error Channel::arm(const Pending& p, bool nowait, Tick now) {
  pending_ = p;
  armed_ = true;
  // Without NOWAIT the channel takes no other command until this one is done (3-12).
  blocking_ = !nowait;
  accept(Error::None);
  if (trig_ == TrigMode::Auto) fire(now);  // "generated automatically as the final step"
  return Error::None;
}

Error Channel::trig(TrigMode mode, Tick now) {
  if (mode == TrigMode::Hold) {
    // "A MOVE or SUSTAIN command ... waiting for a SYS, CHAN 0, or SGL trigger can be
    // cancelled by a TRIG HOLD command." Without NOWAIT the manual needs DEVICE CLEAR first;
    // CANopen has no DEVICE CLEAR, so TRIG HOLD is always accepted and also ends the wait.
    trig_ = TrigMode::Hold;
    if (armed_) {
      armed_ = false;
      blocking_ = false;
      pending_ = Pending{};
    }
    return accept(Error::None);
  }
  if (blocking_) return accept(Error::AccessoryBusy);
  if (mode == TrigMode::Sgl) {
    if (!armed_) return accept(Error::NoActionDefined);  // error 90
    trig_ = TrigMode::Hold;  // "After a SGL trigger is generated, TRIG returns to HOLD."
    accept(Error::None);
    fire(now);
    return Error::None;
  }
  trig_ = mode;
  return accept(Error::None);
}

void Channel::sync(Tick now) {
  if (armed_ && trig_ == TrigMode::Sys) fire(now);
}

void Channel::chan0_triggered(Tick now) {
  if (armed_ && trig_ == TrigMode::Chan0) fire(now);
}

Tick Channel::delay_ticks() const { return static_cast<Tick>(delay_ms_) * kClockHz / 1000; }

void Channel::fire(Tick at) {
  armed_ = false;
  trigger_time_ = at;
  first_step_.reset();
  // STANDBY AUTO: "the STBYn output goes low to allow the motor to be powered up before the
  // pulses are applied" - at the trigger, so a DELAY also gives the driver time.
  if (standby_ == StandbyMode::Auto) {
    powered_ = true;
    idle_since_.reset();
  }
  if (on_triggered) on_triggered(at);
  start_at_ = at + delay_ticks();  // DELAY: "all triggers are delayed" (3-14)
  if (*start_at_ <= at) start(at);
}

void Channel::start(Tick at) {
  start_at_.reset();
  Pending p = pending_;
  pending_ = Pending{};
  if (p.action == Action::Move) return start_move_steps(p.steps, at);
  if (p.action == Action::Sustain) return start_sustain_rate(p.rate, at);
}

void Channel::start_move_steps(int64_t steps, Tick at) {
  if (core_.busy()) {  // the Horner registers started a move during the DELAY
    accept(Error::AccessoryBusy);
    return;
  }
  if (steps == 0) return end(Done::Completed, intr::kMoveDone, at);
  int dir = steps > 0 ? +1 : -1;
  if (halt_active()) return end(Done::Halted, intr::kHaltSwitch, at);
  if (limit_active(dir)) return end(Done::HardLimit, intr::kHardLimit, at);
  run_ = Run::Move;
  direction_ = dir;
  move_steps_ = std::llabs(steps);
  steps_taken_ = 0;
  awaiting_first_step_ = true;
  start_job(freq_ramp(profile_, profile_.max), dir, move_steps_, at);
}

void Channel::start_sustain_rate(double rate, Tick at) {
  const bool width = profile_.mode == ProfileMode::Width;
  if (rate == 0) {
    // SUSTAIN 0: "decelerate to the specified minimum and stop" (FREQ), the width ramps to
    // its minimum and the pulses stop (WIDTH).
    if (run_ != Run::Sustain) return;
    run_ = Run::SustainStopping;
    if (width) {
      width_from_ = current_width_at(at);
      width_since_ = at;
      width_target_ = profile_.min;
    } else {
      core_.stop(at);
    }
    return;
  }
  int dir = rate > 0 ? +1 : -1;
  double target = clamp_to_profile(profile_, std::fabs(rate));
  // Checked when given, and again now: a PROFILE given while it waited for its trigger
  // may have moved the clamp below the rate resolution (a 0 maximum).
  if (below_rate_resolution(rate)) return;
  sustain_reached_ = false;
  if (run_ == Run::Sustain) {
    if (dir != direction_) return (void)accept(Error::MustStopToChangeDirection);
    if (width) {
      width_from_ = current_width_at(at);
      width_since_ = at;
      width_target_ = target;
    } else {
      sustain_rate_ = target;
      change_sustain_velocity(target, at);
    }
    return;
  }
  if (core_.busy()) {
    accept(Error::AccessoryBusy);
    return;
  }
  if (halt_active()) return end(Done::Halted, intr::kHaltSwitch, at);
  if (limit_active(dir)) return end(Done::HardLimit, intr::kHardLimit, at);
  run_ = Run::Sustain;
  direction_ = dir;
  awaiting_first_step_ = true;
  if (width) {
    // The pulses start at the minimum width and ramp to the requested one (3-26 NOTE); the
    // period is the profile's.
    width_from_ = profile_.min;
    width_since_ = at;
    width_target_ = target;
    start_job(constant_rate(1.0 / profile_.last), dir, std::nullopt, at);
  } else {
    sustain_rate_ = target;
    start_job(freq_ramp(profile_, target), dir, std::nullopt, at);
  }
}

void Channel::change_sustain_velocity(double target, Tick at) {
  // The running ramp's levels were sized for the first SUSTAIN rate.
  const RampSpec fresh = freq_ramp(profile_, target);
  const RampSpec& running = core_.generator().ramp();
  // Much finer than a ramp made for the new rate (SUSTAIN 2.5E-6, then SUSTAIN 100: 4e7
  // levels of one tick each, minutes of CPU): move to the new rate's grid, then ramp.
  if (running.phase_per_step > 16 * fresh.phase_per_step) {
    core_.regrid(at, fresh);
    return core_.change_velocity(at, fresh.run_level);
  }
  // A level of the running grid within appendix A's 0.01 % of the rate: ramp to it.
  const double level_hz = running.velocity_of(1);
  const int64_t nearest = level_of(running, target);
  if (nearest >= 1 && std::fabs(running.velocity_of(nearest) - target) <= 1e-4 * target)
    return core_.change_velocity(at, nearest);
  // Otherwise (a coarse grid: at 1 MHz/s a level is 13 Hz) ramp on it to the last level
  // short of the rate, then hold the rate exactly on the new rate's grid.
  const double current = core_.generator().velocity();
  const double levels = target / level_hz;
  const int64_t approach = std::max<int64_t>(1, static_cast<int64_t>(target < current ? std::ceil(levels) : std::floor(levels)));
  core_.change_velocity(at, approach, fresh);
}

void Channel::halt_sgl(Tick now) {
  // "The pulse output can be immediately stopped by sending a HALT command with the SGL mode".
  if (run_ == Run::Idle && !start_at_) return;
  core_.halt(*this, now);
  start_at_.reset();
  end(Done::Halted, intr::kHaltSgl, now);
}

void Channel::end(Done how, uint8_t event, Tick at) {
  run_ = Run::Idle;
  start_at_.reset();
  outcome_ = how;
  blocking_ = false;
  awaiting_first_step_ = false;
  idle_since_ = at;
  interrupt(event, at);
}

void Channel::interrupt(uint8_t event, Tick at) {
  // "An enabled interrupt that is serviced is disabled and must be reenabled" (3-16).
  if (!event || !intr_enabled_) return;
  intr_enabled_ = false;
  events_ = event;
  if (on_interrupt) on_interrupt(event, at);
}

void Channel::enable_intr() {
  events_ = 0;
  intr_enabled_ = true;
}

// ---------------------------------------------------------------- inputs

bool Channel::halt_active() const {
  switch (halt_mode_) {
    // The level as the core applied the HALT input's edges (HIGH: open, pulled up).
    case HaltMode::Lo: return !core_.inputs().halt_high();
    case HaltMode::Hi: return core_.inputs().halt_high();
    case HaltMode::Off: return false;
  }
  return false;
}

bool Channel::limit_active(int direction) const {
  // The simulated limit switches close to PCOM when reached (Figure 3-4): the input is LO
  // there, HI (pulled up) elsewhere. HARDLIM sets which level means "limit reached"; only
  // motion toward a reached limit is prohibited (Command Summary: HARDLIM).
  if (direction > 0) return (!core_.inputs().upper_limit()) == plim_high_;
  return (!core_.inputs().lower_limit()) == nlim_high_;
}

void Channel::halt_input_changed(Tick now) {
  if (halt_active() && (run_ != Run::Idle || start_at_)) {
    core_.halt(*this, now);
    end(Done::Halted, intr::kHaltSwitch, now);
  }
}

void Channel::after_step(const Step& step) {
  if (awaiting_first_step_) {
    first_step_ = step.time;
    awaiting_first_step_ = false;
  }
  if (run_ == Run::Move) ++steps_taken_;
  if (limit_active(step.direction)) {
    // "A hardlimit is reached causing pulses to stop": no step goes past it.
    core_.halt(*this, step.time);
    return end(Done::HardLimit, intr::kHardLimit, step.time);
  }
  check_sustain_reached(step.time);
}

void Channel::ended(bool completed, Tick at) {
  if (run_ == Run::Idle) return;
  if (run_ == Run::Move) {
    bool all = completed && steps_taken_ >= move_steps_;
    return end(all ? Done::Completed : Done::Halted, all ? intr::kMoveDone : intr::kHaltSwitch, at);
  }
  if (run_ == Run::SustainStopping && completed)
    return end(Done::Completed, intr::kMoveDone, at);
  // A running SUSTAIN ended by the e-stop, a Horner stop or a lost master: a halt.
  end(Done::Halted, intr::kHaltSwitch, at);
}

void Channel::check_sustain_reached(Tick at) {
  if (run_ != Run::Sustain || sustain_reached_ || profile_.mode != ProfileMode::Freq) return;
  MotionPhase ph = core_.generator().phase();
  if (ph == MotionPhase::Running || ph == MotionPhase::Creeping) {
    sustain_reached_ = true;
    blocking_ = false;
    interrupt(intr::kSustainReached, at);
  }
}

double Channel::current_width_at(Tick t) const {
  if (profile_.mode != ProfileMode::Width || run_ == Run::Idle) return 0;
  double elapsed = static_cast<double>(t - width_since_) / static_cast<double>(kClockHz);
  double change = profile_.slope * elapsed;
  if (width_target_ >= width_from_) return std::min(width_target_, width_from_ + change);
  return std::max(width_target_, width_from_ - change);
}

double Channel::current_width() const { return current_width_at(core_.generator().time()); }

void Channel::width_advance(Tick now) {
  if (profile_.mode != ProfileMode::Width || (run_ != Run::Sustain && run_ != Run::SustainStopping)) return;
  if (run_ == Run::Sustain && sustain_reached_) return;
  // The exact tick the width reaches its target.
  double span = std::fabs(width_target_ - width_from_);
  Tick reach = width_since_ + (profile_.slope > 0 ? seconds_to_ticks(span / profile_.slope) : 0);
  if (reach > now) return;
  core_.advance_to(reach);
  if (run_ == Run::SustainStopping) {
    core_.halt(*this, reach);
    return end(Done::Completed, intr::kMoveDone, reach);
  }
  sustain_reached_ = true;
  blocking_ = false;
  interrupt(intr::kSustainReached, reach);
}

void Channel::advance(Tick now) {
  if (start_at_ && *start_at_ <= now) start(*start_at_);
  width_advance(now);
  core_.advance_to(now);
  check_sustain_reached(now);
  // STANDBY AUTO follows the axis, whichever front end moves it.
  if (standby_ == StandbyMode::Auto) {
    if (core_.busy() || run_ != Run::Idle || start_at_) {
      powered_ = true;
      idle_since_.reset();
    } else if (powered_) {
      if (!idle_since_) idle_since_ = now;
      if (now - *idle_since_ >= kStandbyAutoOffTicks) powered_ = false;
    }
  }
  if (blocking_ && !armed_ && !start_at_ && run_ == Run::Idle) blocking_ = false;
}

Done Channel::done() const {
  if (armed_) return Done::WaitingForTrigger;
  if (start_at_ || run_ == Run::Move || run_ == Run::SustainStopping) return Done::Running;
  if (run_ == Run::Sustain) return sustain_reached_ ? Done::SustainRunning : Done::Running;
  if (core_.busy()) return Done::Running;  // a Horner job on the same axis
  return outcome_;
}

Error Channel::pos(double units) {
  if (blocking_ || run_ != Run::Idle || core_.busy()) return accept(Error::AccessoryBusy);
  position_.load(units, core_.position());
  return accept(Error::None);
}

// ---------------------------------------------------------------- quadrature counter

void Channel::qindex(QIndexMode mode) {
  switch (mode) {
    case QIndexMode::Off: q_waiting_for_index_ = false; q_frozen_ = false; break;
    case QIndexMode::Once:
      // Reset now; counting begins on the first index pulse, later ones are ignored.
      q_offset_ = core_.motor().encoder_count();
      q_frozen_ = q_waiting_for_index_ = true;
      break;
    case QIndexMode::Sgl:
      // Reset now and count at once; QINDEX then returns to OFF.
      q_offset_ = core_.motor().encoder_count();
      q_frozen_ = q_waiting_for_index_ = false;
      mode = QIndexMode::Off;
      break;
  }
  // QINDEX ONCE waits for the index's leading edge (input_changed), whoever moves the axis.
  qindex_ = mode;
}

int32_t Channel::quadrature_count() const {
  if (q_frozen_) return 0;
  // "will rollover from the maximum positive number to the maximum negative number"
  return static_cast<int32_t>(static_cast<uint32_t>(core_.motor().encoder_count() - q_offset_));
}

}  // namespace stepnode::motion::hp
