// hp::Channel: construction, the power-on state, the set-up commands (PROFILE, PSCALE,
// STANDBY, HALT mode), POS, the end of a command (DONE?, interrupts).
#include "node/motion/hp_channel.hpp"

#include <cmath>

#include "node/motion/hp_self_test.hpp"

namespace stepnode::motion::hp {

Channel::Channel(AxisCore& core) : core_(core) {
  core_.listen(*this);
  core_.watch_inputs(*this, true);  // HALT acts whatever runs
  power_up(0);
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
  armed_ = locked_ = blocking_ = false;
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
  Error e = (blocking_ || run_ != Run::Idle || start_at_ || core_.busy()) ? Error::AccessoryBusy
                                                                          : Error::None;
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
  // The mode cannot change under a MOVE or SUSTAIN waiting for its trigger (DONE? -3): it
  // was given under the mode in effect, and the mode is what it means. A waiting MOVE would
  // become one that "cannot be executed when the PROFILE command is in the width mode"
  // (error 92, 3-3); a waiting SUSTAIN's value is "The frequency of pulses in Hz (PROFILE in
  // FREQ mode)" or "The pulse width in seconds (PROFILE in WIDTH mode)" (3-12), and would
  // run read in the other unit. The PROFILE is refused, as parameters "which conflict"
  // (3-9, 3-26), rather than the waiting command at its trigger: the manual has no error a
  // SUSTAIN could get for its units, and the refusal comes with the command that made the
  // conflict. TRIG HOLD cancels the waiting command first (3-13 NOTE).
  if (last_conflict_ == Conflict::None && armed_ && hz.mode != profile_.mode)
    last_conflict_ = Conflict::ModeVersusWaitingCommand;
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
  // Power off under a move (or its DELAY: DONE? -2); but in pulse output STBY follows the
  // pulse train (3-29). A command waiting for its trigger (DONE? -3) is not under way: the
  // power goes, and the command meets error 94 when its trigger would start it (start()).
  if (mode == StandbyMode::On && moving && !pulse_train()) return accept(Error::AccessoryBusy);
  standby_ = mode;
  standby_high_ = sense_high;
  if (mode == StandbyMode::Off) powered_ = true;               // OFF = apply power
  else if (mode == StandbyMode::On) powered_ = pulse_train();  // ON = remove power
  else if (!moving && powered_) idle_since_ = now;             // AUTO: off a second after idle
  return accept(Error::None);
}

void Channel::halt_mode(HaltMode mode, Tick now) {
  halt_mode_ = mode;
  if (halt_active() && (run_ != Run::Idle || start_at_)) {
    core_.halt(*this, now);
    end(Done::Halted, intr::kHaltSwitch, now);
  }
}

// ---------------------------------------------------------------- what the master reads

void Channel::end(Done how, uint8_t event, Tick at) {
  run_ = Run::Idle;
  start_at_.reset();
  outcome_ = how;
  blocking_ = false;
  awaiting_first_step_ = false;
  idle_since_ = at;
  // STANDBY ON in pulse output: "After all pulses are sent, the STBYn output goes high" (3-29).
  if (standby_ == StandbyMode::On) powered_ = false;
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

Done Channel::done() const {
  if (armed_) return Done::WaitingForTrigger;
  if (start_at_ || run_ == Run::Move || run_ == Run::SustainStopping) return Done::Running;
  if (run_ == Run::Sustain) return sustain_reached_ ? Done::SustainRunning : Done::Running;
  if (core_.busy()) return Done::Running;  // a Horner job on the same axis
  return outcome_;
}

Error Channel::test(uint8_t& failed) {
  // Not while pulses go out or a command waits for its trigger (error 89, "A move is in
  // progress"): a self test is of an idle module.
  if (blocking_ || armed_ || run_ != Run::Idle || start_at_ || core_.busy())
    return accept(Error::AccessoryBusy);
  failed = run_self_test();
  return accept(Error::None);
}

Error Channel::pos(double units) {
  if (blocking_ || run_ != Run::Idle || core_.busy()) return accept(Error::AccessoryBusy);
  position_.load(units, core_.position());
  return accept(Error::None);
}

}  // namespace stepnode::motion::hp
