// hp::Channel: the output commands MOVE and SUSTAIN as given, TRIG and DELAY (3-12..3-14):
// what is refused, what is armed, and when an armed command fires.
#include "node/motion/hp_channel.hpp"

#include <algorithm>
#include <cmath>

namespace stepnode::motion::hp {

// ---------------------------------------------------------------- output commands

Error Channel::check_can_move(bool width_allowed) const {
  if (!width_allowed && profile_.mode == ProfileMode::Width) return Error::NotValidInWidthMode;
  if (test_jumper_) return Error::TestJumperSet;
  // Error 94: "Motor cannot move when powered down by STANDBY in the ON mode". A WIDTH-mode
  // SUSTAIN is pulse output, not a motor: there STBY follows the pulse train (3-29).
  if (standby_ == StandbyMode::On && profile_.mode == ProfileMode::Freq)
    return Error::CannotMoveWhileStandbyOn;
  return Error::None;
}

Error Channel::move(double distance, bool absolute, bool nowait, Tick now) {
  // 89 first: a move in progress (this channel's, or the axis' under the Horner registers).
  if (blocking_ || run_ != Run::Idle || start_at_ || core_.busy())
    return accept(Error::AccessoryBusy);
  if (Error e = check_can_move(false); e != Error::None) return accept(e);
  int64_t steps =
      absolute ? position_.abs_steps(distance, core_.position()) : position_.rel_steps(distance);
  // A move that would outlast the engine's 64-bit clock (2^31 pulses at a 2.5 µHz maximum:
  // 27 million years) is refused: its deceleration tick overflowed.
  if (std::fabs(static_cast<double>(steps)) / std::max(profile_.max, kRateResolutionHz) >
      kLongestMoveS)
    return Error::ValueOutOfRange;
  return arm(Pending{Action::Move, steps, 0}, nowait, now);
}

Error Channel::sustain(double value, bool nowait, Tick now) {
  if (blocking_ || run_ == Run::Move || run_ == Run::SustainStopping ||
      (start_at_ && pending_.action == Action::Move) || (core_.busy() && !core_.owned_by(*this)))
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
  // Without NOWAIT the channel takes no other command until this one is done (3-12). Under
  // a trigger other than AUTO that locks it in its wait state: "The MOVE and SUSTAIN
  // commands must specify the NOWAIT option for these trigger modes to work" (3-13 note 1);
  // "the SUSTAIN command will be locked into a wait state" (3-27 NOTE). Neither the SYNC
  // (SYS) nor channel 0 (CHAN0) starts it; only TRIG HOLD (the manual's DEVICE CLEAR
  // followed by TRIG HOLD) cancels it.
  blocking_ = !nowait;
  locked_ = !nowait && trig_ != TrigMode::Auto;
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
      armed_ = locked_ = false;
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
  if (armed_ && !locked_ && trig_ == TrigMode::Sys) fire(now);
}

void Channel::chan0_triggered(Tick now) {
  if (armed_ && !locked_ && trig_ == TrigMode::Chan0) fire(now);
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
  // STANDBY ON in pulse output: "When a MOVE or SUSTAIN command is executed and triggered,
  // the STBYn output goes low" (3-29, HI sense). A stepper's command under STANDBY ON is
  // refused (error 94, when given or at its start) and leaves the motor unpowered; the mode
  // is the one the command was given under (Channel::profile).
  if (standby_ == StandbyMode::On) powered_ = profile_.mode == ProfileMode::Width;
  if (on_triggered) on_triggered(at);
  start_at_ = at + delay_ticks();  // DELAY: "all triggers are delayed" (3-14)
  if (*start_at_ <= at) start(at);
}

void Channel::start(Tick at) {
  start_at_.reset();
  Pending p = pending_;
  pending_ = Pending{};
  // Checked when given, and again now that it would move the motor: STANDBY ON and the
  // TEST jumper may have changed while it waited for its trigger (the jumper also during
  // the DELAY). STANDBY ON is accepted then ("ON = remove power", 3-6; nothing moves while
  // a command waits); error 94 is the move's: "Motor cannot move when powered down by
  // STANDBY in the ON mode" (3-3), so it applies when the motor would move. The jumper is
  // an input: "Will not execute a MOVE or SUSTAIN command when test jumper is in the TEST
  // position" (93). The command is dropped with its error number (0x2n19); DONE? keeps the
  // last move's code, as for a command refused when given. (92 cannot arise here: the mode
  // does not change under a waiting command, Channel::profile.) SUSTAIN 0 only stops.
  const bool moves = p.action == Action::Move || (p.action == Action::Sustain && p.rate != 0);
  if (moves)
    if (Error e = check_can_move(p.action == Action::Sustain); e != Error::None)
      return (void)accept(e);
  if (p.action == Action::Move) return start_move_steps(p.steps, at);
  if (p.action == Action::Sustain) return start_sustain_rate(p.rate, at);
}

}  // namespace stepnode::motion::hp
