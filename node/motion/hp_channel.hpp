// One HP 44714A channel (HP 3852A HP 44714A manual, chapter 3) on one axis of the node: the
// manual's commands with their rules, DONE? codes, error numbers 89-94, triggers, DELAY,
// STANDBY, HALT/HARDLIM and the quadrature counter. It is a front end of the axis' motion
// core (node/motion/axis_core.hpp), the same generator, position and motor as the Horner
// registers; which semantics apply is decided by which front end a command came through.
// Pure and deterministic: time comes in as ticks.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>

#include "node/motion/axis_core.hpp"
#include "node/motion/hp_position.hpp"
#include "node/motion/hp_profile.hpp"
#include "node/motion/hp_pulse_output.hpp"
#include "node/motion/hp_settings.hpp"
#include "node/motion/motor_port.hpp"

namespace stepnode::motion::hp {

class Channel final : public FrontEnd, public AxisListener {
 public:
  // `core`: the axis this channel drives. `inputs`: its motor's inputs (limits, marker,
  // encoder counts) as the HP terminal module sees them.
  explicit Channel(AxisCore& core);
  Channel(const Channel&) = delete;
  Channel& operator=(const Channel&) = delete;

  // Power-on / reset state (3-2): every setting to its power-on value, interrupts disabled.
  void power_up(Tick now);

  // ---- set-up commands
  Conflict profile(const Profile& given, Tick now, Error* error = nullptr);
  Error pscale(double units_per_step);
  double pscale_value() const { return position_.scale(); }
  // A command that only sets a parameter (DELAY, PULSE, HARDLIM, QSCALE, QINDEX, ENABLE and
  // DISABLE INTR): error 89 while a MOVE or SUSTAIN without NOWAIT runs ("must complete the
  // MOVE or SUSTAIN command before the next command is recognized", 3-13 note 1), else
  // accepted (0x2n19 = 0). The caller carries it out only when accepted.
  Error setting_command() { return accept(blocking_ ? Error::AccessoryBusy : Error::None); }
  void delay(uint16_t ms) { delay_ms_ = ms; }
  Error standby(StandbyMode mode, bool sense_high, Tick now);
  void pulse(const PulseSetup& setup) { pulse_ = setup; }
  void hardlim(bool plim_high, bool nlim_high) { plim_high_ = plim_high, nlim_high_ = nlim_high; }
  void halt_mode(HaltMode mode, Tick now);
  // ---- output commands
  Error move(double distance, bool absolute, bool nowait, Tick now);
  Error sustain(double value, bool nowait, Tick now);
  Error trig(TrigMode mode, Tick now);
  void halt_sgl(Tick now);
  // ---- position and quadrature counter
  Error pos(double units);
  double pos_query() const { return position_.units(core_.position()); }
  void qscale(double units_per_count) { qscale_ = units_per_count; }
  void qindex(QIndexMode mode);
  int32_t quadrature_count() const;
  double qpos_query() const { return static_cast<double>(quadrature_count()) * qscale_; }
  // ---- TEST (Command Summary 4-3): the pass/fail self test (node/motion/hp_self_test.hpp).
  // Refused while a command is in progress or waits for its trigger (error 89); otherwise
  // `failed` gets the failed checks (0: passed). The settings stay as they were.
  Error test(uint8_t& failed);
  // ---- interrupts
  void enable_intr();  // clears, then enables (Command Summary: ENABLE INTR)
  void disable_intr() { intr_enabled_ = false; }

  // ---- inputs from outside the channel
  void sync(Tick now);             // the CANopen SYNC: TRIG SYS
  void chan0_triggered(Tick now);  // channel 0 of this node was triggered: TRIG CHAN0
  void set_test_jumper(bool set) { test_jumper_ = set; }
  // Starts what is due (DELAY, STANDBY AUTO power-off) and brings the axis to `now`.
  void advance_to(Tick now);
  // The earliest tick at which advance_to has timed work of the channel's own (issue 13):
  // a DELAY's end, a WIDTH-mode ramp reaching its width, STANDBY AUTO's power-off. The
  // job's steps are the core's (AxisCore::next_step_time); a trigger comes with a frame.
  // `now`: the latest advance.
  std::optional<Tick> next_event(Tick now) const;

  // ---- what the master reads
  Done done() const;
  Error last_error() const { return last_error_; }
  Conflict last_conflict() const { return last_conflict_; }
  uint8_t interrupt_events() const { return events_; }
  bool intr_enabled() const { return intr_enabled_; }
  // A MOVE or SUSTAIN without NOWAIT waits for a trigger it cannot get (3-13 note 1).
  bool locked_in_wait() const { return armed_ && locked_; }
  const Profile& active_profile() const { return profile_; }
  double scale() const { return position_.scale(); }
  TrigMode trig_mode() const { return trig_; }
  uint16_t delay_ms() const { return delay_ms_; }
  StandbyMode standby_mode() const { return standby_; }
  bool standby_sense_high() const { return standby_high_; }
  bool motor_powered() const { return powered_; }
  // Whether pulses reach a powered motor: STANDBY AUTO applies power before any pulse
  // (whichever front end moves the axis), so only STANDBY ON leaves the motor without
  // torque while it is pulsed, except for the channel's own WIDTH-mode pulse train, which
  // the STBY output follows (3-29).
  bool pulses_reach_powered_motor() const { return standby_ != StandbyMode::On || powered_; }
  bool stby_output_high() const { return !powered_ == standby_high_; }
  const PulseSetup& pulse_setup() const { return pulse_; }
  HaltMode halt_mode() const { return halt_mode_; }
  QIndexMode qindex_mode() const { return qindex_; }
  double qscale() const { return qscale_; }
  bool plim_sense_high() const { return plim_high_; }
  bool nlim_sense_high() const { return nlim_high_; }
  // The width of the pulses at the outputs now (s; the last pulse's, to 1 us): the PROFILE
  // FREQ pwidth, or the width a WIDTH-mode SUSTAIN has ramped to; 0 without a pulse train.
  double current_width() const;
  // The last triggered action: trigger tick and first step tick.
  std::optional<Tick> trigger_time() const { return trigger_time_; }
  std::optional<Tick> first_step_time() const { return first_step_; }
  uint64_t pulses(Output o) const { return pulse_count_[static_cast<unsigned>(o)]; }
  const Pulse& last_pulse() const { return last_pulse_; }

  // An interrupt condition occurred while enabled (bit of hp::intr); disabled until re-enabled.
  std::function<void(uint8_t event, Tick at)> on_interrupt;
  // This channel was triggered (the node fans channel 0's trigger out to TRIG CHAN0).
  std::function<void(Tick at)> on_triggered;

 private:
  enum class Action { None, Move, Sustain };
  struct Pending {
    Action action = Action::None;
    int64_t steps = 0;  // MOVE
    double rate = 0;    // SUSTAIN: steps/s (FREQ) or width s (WIDTH), signed
  };
  enum class Run { Idle, Move, Sustain, SustainStopping };

  Error accept(Error e);
  Error check_can_move(bool width_allowed) const;
  Error arm(const Pending& p, bool nowait, Tick now);
  void fire(Tick at);
  void start(Tick at);
  void start_move_steps(int64_t steps, Tick at);
  void start_sustain_rate(double rate, Tick at);
  void change_sustain_velocity(double target, Tick at);
  bool below_rate_resolution(double rate) const;
  double current_width_at(Tick t) const;
  uint32_t width_ns_at(Tick t) const;  // a pulse's width at the outputs at `t`, 1 us resolution
  void replan_widths(Tick at);
  void end(Done how, uint8_t event, Tick at);
  void interrupt(uint8_t event, Tick at);
  bool limit_active(int direction) const;
  bool halt_active() const;
  // A WIDTH-mode SUSTAIN triggered and not ended: general purpose pulse output (3-23).
  bool pulse_train() const {
    return profile_.mode == ProfileMode::Width && (run_ != Run::Idle || start_at_);
  }
  // The HALT input changed (its edge, input_changed): a halt when it now reads active.
  void halt_input_changed(Tick now);
  // FrontEnd: the channel's own jobs.
  Hooks hooks() const override { return {.pulse = true}; }
  OutputPulse pulse(const Step& step) const override;
  void pulse_sent(const Step& step) override;
  void after_step(const Step& step) override;
  void motion_ended(Tick when) override { ended(/*completed=*/true, when); }
  void aborted(Tick when) override { ended(/*completed=*/false, when); }
  void ended(bool completed, Tick at);
  // AxisListener: the HALT switch and the quadrature index watch (the marker's leading
  // edge, whoever moves the axis).
  void input_changed(unsigned motor, const InputEdge& edge) override;
  void start_job(const RampSpec& ramp, int direction, std::optional<int64_t> steps, Tick at);
  void check_sustain_reached(Tick at);
  void width_advance(Tick now);
  std::optional<Tick> width_reach() const;  // when a WIDTH-mode ramp reaches its target
  // STANDBY AUTO's idle: no job of any front end, none of this channel's waiting to start.
  bool standby_idle() const { return !core_.busy() && run_ == Run::Idle && !start_at_; }
  Tick delay_ticks() const;

  AxisCore& core_;
  // Settings.
  Profile profile_;
  PositionCounter position_;
  uint16_t delay_ms_ = 0;
  TrigMode trig_ = TrigMode::Auto;
  StandbyMode standby_ = StandbyMode::Auto;
  bool standby_high_ = true;
  PulseSetup pulse_;
  HaltMode halt_mode_ = HaltMode::Lo;
  bool plim_high_ = false, nlim_high_ = false;
  double qscale_ = 1.0;
  QIndexMode qindex_ = QIndexMode::Off;
  // Inputs.
  bool test_jumper_ = false;
  // State.
  Pending pending_;
  bool armed_ = false;            // a MOVE/SUSTAIN waits for its trigger
  bool locked_ = false;           // ...given without NOWAIT: no trigger reaches it (3-13)
  std::optional<Tick> start_at_;  // triggered, starting after DELAY
  bool blocking_ = false;         // a command without NOWAIT has not finished
  Run run_ = Run::Idle;
  int direction_ = +1;
  int64_t move_steps_ = 0, steps_taken_ = 0;
  double sustain_rate_ = 0;  // steps/s (FREQ) the SUSTAIN asked for, clamped
  bool sustain_reached_ = false;
  Done outcome_ = Done::Completed;
  Error last_error_ = Error::None;
  Conflict last_conflict_ = Conflict::None;
  bool intr_enabled_ = false;
  uint8_t events_ = 0;
  bool powered_ = false;            // motor power (STANDBY): AUTO starts unpowered
  std::optional<Tick> idle_since_;  // STANDBY AUTO: powered down 1 s after the last move
  std::optional<Tick> trigger_time_, first_step_;
  bool awaiting_first_step_ = false;
  // WIDTH mode: the width ramps from width_from_ at width_since_ toward width_target_.
  double width_from_ = 0, width_target_ = 0;
  Tick width_since_ = 0;
  // Quadrature counter: counts = encoder - q_offset_; QINDEX ONCE waits for the index.
  int64_t q_offset_ = 0;
  bool q_waiting_for_index_ = false, q_frozen_ = false;
  uint64_t pulse_count_[2] = {0, 0};
  Pulse last_pulse_;
};

}  // namespace stepnode::motion::hp
