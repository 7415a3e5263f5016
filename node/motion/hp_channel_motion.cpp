// hp::Channel: the motion of a triggered MOVE or SUSTAIN on the axis core: its start, a
// new SUSTAIN velocity, HALT SGL, each step's rules, its end, and the timed work (advance).
#include "node/motion/hp_channel.hpp"

#include <algorithm>
#include <cmath>

namespace stepnode::motion::hp {
namespace {

constexpr Tick kStandbyAutoOffTicks = kClockHz;  // "a one second delay in powering off" (3-6)

}  // namespace

void Channel::start_job(const RampSpec& ramp, int direction, std::optional<int64_t> steps,
                        Tick at) {
  core_.advance_to(at);
  core_.start(*this, ramp, direction, steps, at);
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
      replan_widths(at);
    } else {
      core_.stop(at);
    }
    return;
  }
  int dir = rate > 0 ? +1 : -1;
  double target = clamp_to_profile(profile_, std::fabs(rate));
  // Checked when given, and again now: a PROFILE given while it waited for its trigger
  // may have moved the clamp below the rate resolution (a 0 minimum under SUSTAIN 1E-12).
  if (below_rate_resolution(rate)) return;
  sustain_reached_ = false;
  if (run_ == Run::Sustain) {
    if (dir != direction_) return (void)accept(Error::MustStopToChangeDirection);
    if (width) {
      width_from_ = current_width_at(at);
      width_since_ = at;
      width_target_ = target;
      replan_widths(at);
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
  const int64_t approach = std::max<int64_t>(
      1, static_cast<int64_t>(target < current ? std::ceil(levels) : std::floor(levels)));
  core_.change_velocity(at, approach, fresh);
}

void Channel::halt_sgl(Tick now) {
  // "The pulse output can be immediately stopped by sending a HALT command with the SGL mode".
  if (run_ == Run::Idle && !start_at_) return;
  core_.halt(*this, now);
  start_at_.reset();
  end(Done::Halted, intr::kHaltSgl, now);
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
  if (run_ == Run::SustainStopping && completed) return end(Done::Completed, intr::kMoveDone, at);
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

void Channel::advance_to(Tick now) {
  if (start_at_ && *start_at_ <= now) start(*start_at_);
  width_advance(now);
  core_.advance_to(now);
  check_sustain_reached(now);
  // STANDBY ON in pulse output follows this channel's pulse train (a triggered SUSTAIN that
  // did not start, the axis busy, leaves it off again).
  if (standby_ == StandbyMode::On) powered_ = pulse_train();
  // STANDBY AUTO follows the axis, whichever front end moves it.
  if (standby_ == StandbyMode::Auto) {
    if (!standby_idle()) {
      powered_ = true;
      idle_since_.reset();
    } else if (powered_) {
      if (!idle_since_) idle_since_ = now;
      if (now - *idle_since_ >= kStandbyAutoOffTicks) powered_ = false;
    }
  }
  if (blocking_ && !armed_ && !start_at_ && run_ == Run::Idle) blocking_ = false;
}

std::optional<Tick> Channel::next_event(Tick now) const {
  std::optional<Tick> next = start_at_;
  const auto sooner = [&next](std::optional<Tick> t) {
    if (t && (!next || *t < *next)) next = t;
  };
  sooner(width_reach());
  // The power-off timer runs from the advance that found the axis idle (advance_to); an
  // axis that became idle since (a job aborted in a frame) starts it at the next advance.
  if (standby_ == StandbyMode::Auto && powered_ && standby_idle())
    sooner(idle_since_ ? *idle_since_ + kStandbyAutoOffTicks : now + 1);
  return next;
}

}  // namespace stepnode::motion::hp
