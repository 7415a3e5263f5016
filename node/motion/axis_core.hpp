// The motion core of one axis: the pulse engine, the motor position, the motor(s) it steps
// and the e-stop guard, and the one rule of which job runs. The Horner registers
// (node/motion/axis.*), the HP 44714A channel (node/motion/hp_channel.*) and the CiA 402
// drive are front ends: a front end asks the core for a job and applies its own rules to
// the job's steps; every front end may listen to every job's events.
//
// Arbitration (the README's "HP 44714A channels" and "CiA 402" sections say it to users):
//   - one job at a time: a front end can start a job only while the axis is idle (no job,
//     no motion); `busy()` tells a front end to refuse with its own error (HP error 89);
//   - any front end may stop the axis whatever runs: `stop` decelerates (Horner %Q15, a
//     lost master), `abort` ends at once (Horner %Q16, a latched Horner error); the owner
//     of an aborted job is told (`FrontEnd::aborted`);
//   - the e-stop input ends every job before its next step; the owner is told, then every
//     listener (`AxisListener::emergency_stop`).
//
// Steps and inputs go through the motor's ports (node/motion/step_port.hpp, input_port.hpp).
// With a horizon (StepPort::horizon) a second generator, the planner, runs ahead and queues
// the steps up to that far ahead; the core itself takes each step when its time comes,
// applies the input edges that fell before it, and runs the front ends' rules. A rule that
// changes course takes the queued steps back (StepPort::cancel_after) and plans again from
// the core's state, so the steps that go out are the same at any horizon.
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include "node/motion/motor_port.hpp"
#include "node/motion/step_generator.hpp"

namespace stepnode::motion {

class AxisCore;

// The rules of one command set for the jobs it starts. The core calls the owner of the
// running job only.
class FrontEnd {
 public:
  virtual ~FrontEnd() = default;
  // Which of the optional hooks below the motion about to start uses; asked once per
  // motion (`AxisCore::start`), so a job pays per step only for what it uses.
  struct Hooks {
    bool pulse = false;        // pulse(): the job's steps are output signals
    bool deadline = false;     // deadline()/at_deadline(): a time between steps matters
    bool before_step = false;  // before_step()
    // after_step() at every step, or (false) only at a step after which one of the inputs
    // in `step_rule_inputs` (a set of Input bits) is active: a rule that acts only at a
    // limit switch costs the other steps nothing. A job whose rule comes to need every
    // step says so (`AxisCore::hooks_changed`).
    bool every_step = true;
    uint8_t step_rule_inputs = 0;
    // after_step() also at the step after which the motor position is this one (a rule of
    // a position: the Horner jog's end set on the bound of the position words).
    std::optional<int32_t> step_rule_position = std::nullopt;
  };
  virtual Hooks hooks() const { return {}; }
  // How the job's step leaves the outputs (HP PULSE SD|SS). It may be asked ahead of the
  // step's time (a port with a horizon) and for steps that are taken back: no side effects.
  virtual OutputPulse pulse(const Step& step) const {
    return OutputPulse{
        .step_direction = true, .ndir_level = step.direction > 0, .ndir_positive_level = true};
  }
  // The step went out as pulse(step) said (when its time came).
  virtual void pulse_sent(const Step& step) { (void)step; }
  // A job that has not begun to step yet (STP100 5.3.4: a move toward an active limit
  // waits for its release; `AxisCore::claim`): the axis is busy, the e-stop ends it. While
  // it waits, `poll` runs before anything else in each round of `advance_to` and may start
  // the motion (or give the job up: `AxisCore::release`).
  virtual void poll(Tick now) { (void)now; }
  // A time between steps at which the job changes course (FIND HOME step 5's dwell), and
  // what happens then.
  virtual std::optional<Tick> deadline() const { return std::nullopt; }
  virtual void at_deadline(Tick when) { (void)when; }
  // Just before a step of the job is taken, and after the motor took it.
  virtual void before_step() {}
  virtual void after_step(const Step& step) = 0;
  // The motion ended by itself (the distance is done, a stop ramp ran out, a halt from
  // after_step). The job is over; the front end may start the next one from here.
  virtual void motion_ended(Tick when) = 0;
  // Another front end, or the e-stop, ended the job at once: no motion_ended follows.
  virtual void aborted(Tick when) { (void)when; }
};

// Everyone interested in every job, whoever runs it.
class AxisListener {
 public:
  virtual ~AxisListener() = default;
  // Every step of any job but the listener's own (see `listen`), after the motor took it and
  // before the owner's after_step, while the listener watches steps (`watch_steps`).
  virtual void step_taken(const Step& step) { (void)step; }
  // A job began (its first motion or, for a waiting job, its claim).
  virtual void job_started(const FrontEnd& owner, Tick when) {
    (void)owner;
    (void)when;
  }
  // A front end halted its own job (no ramp, no motion_ended).
  virtual void job_halted(const FrontEnd& owner, Tick when) {
    (void)owner;
    (void)when;
  }
  // The e-stop ended the motion (`was_moving`: steps were going out).
  virtual void emergency_stop(Tick when, bool was_moving) {
    (void)when;
    (void)was_moving;
  }
  // An input of motor `motor` changed (the port's edge, applied in time order between the
  // steps it fell between), while the listener watches inputs (`watch_inputs`).
  virtual void input_changed(unsigned motor, const InputEdge& edge) {
    (void)motor;
    (void)edge;
  }
  // The end of every advance_to (statuses that follow the motion are published here).
  virtual void advanced(Tick now) { (void)now; }
};

class AxisCore {
 public:
  // `motors`: one, or three for an SPM30 multiplexed axis (one stepped at a time). The
  // e-stop is an input of the motors' ports (the selected motor's is obeyed).
  explicit AxisCore(const std::vector<MotorPort*>& motors);
  // The core keeps a pointer to its selected motor: it stays where it was made.
  AxisCore(const AxisCore&) = delete;
  AxisCore& operator=(const AxisCore&) = delete;

  // Power-up: no job, no motion, position 0, the first motor selected. Owners are not told
  // (every front end has its own power-up).
  void power_up(Tick now);

  // Takes every step due up to `now`, with the owner's rules and the input edges in time
  // order, queues the steps up to the port's horizon, then tells the listeners.
  void advance_to(Tick now);

  // --- Jobs ----------------------------------------------------------------------------
  bool busy() const { return owner_ != nullptr || generator_.moving(); }
  const FrontEnd* owner() const { return owner_; }
  bool owned_by(const FrontEnd& f) const { return owner_ == &f; }
  // The owner's next motion: the first of a job (refused with false while another front
  // end's job runs) or the next of the same job (homing's back-off, a repeated move).
  // `dir_setup`: the first step falls at least that long after the DIR output last changed
  // (the Horner modules' direction output setup time); the motion begins later if needed.
  bool start(FrontEnd& by, const RampSpec& ramp, int direction, std::optional<int64_t> steps,
             Tick now, Tick dir_setup = 0);
  // A job that waits before its first motion (FrontEnd::poll); `start` ends the wait.
  bool claim(FrontEnd& by, Tick now);
  bool waiting() const { return waiting_; }
  // The owner ends its wait without a motion: the job ends (motion_ended) at the next
  // advance.
  void end_wait(const FrontEnd& by) {
    if (owner_ == &by) waiting_ = false;
    update_rounds();
  }
  // The owner's hooks() answer changed within its motion (a rule needs every step now).
  void hooks_changed(const FrontEnd& by) {
    if (owner_ != &by) return;
    hooks_ = by.hooks();
    update_rounds();
  }
  // The owner gives its job up without a motion_ended (the job ended in its rules).
  void release(const FrontEnd& by);
  // Decelerate whatever runs to the base velocity and stop (any front end may).
  void stop(Tick at) {
    generator_.stop(at);
    replan(at);
  }
  // The same at another deceleration (ticks per level of the running grid).
  void stop(Tick at, Rational decel) {
    generator_.stop(at, decel);
    replan(at);
  }
  // End whatever runs at once; the owner, unless it is `by`, is told (FrontEnd::aborted).
  void abort(const FrontEnd* by, Tick at);
  // The owner stops its own job at once (no ramp, no motion_ended); listeners are told.
  void halt(const FrontEnd& by, Tick at);
  // Stop the generator at once but keep the job (homing's stop on the origin, in
  // after_step: the job goes on or motion_ended follows).
  void halt_motion(Tick at) {
    generator_.halt(at);
    replan(at);
  }
  // The running motion's velocity and grid (HP SUSTAIN) and end point (indexed move).
  void change_velocity(Tick at, int64_t level, std::optional<RampSpec> then = std::nullopt) {
    generator_.change_velocity(at, level, then);
    replan(at);
  }
  void regrid(Tick at, const RampSpec& ramp) {
    generator_.regrid(at, ramp);
    replan(at);
  }
  void set_level(Tick at, int64_t level) {
    generator_.set_level(at, level);
    replan(at);
  }
  void retarget(Tick at, int64_t steps, const RampSpec& ramp) {
    generator_.retarget(at, steps, ramp);
    replan(at);
  }

  // --- State ---------------------------------------------------------------------------
  const StepGenerator& generator() const { return generator_; }
  bool moving() const { return generator_.moving(); }
  std::optional<Tick> next_step_time() { return generator_.peek(); }
  int32_t position() const { return position_; }
  void set_position(int32_t p) { position_ = p; }
  // The DIR output's level: set at the start of every motion (STP100 5.3.5).
  bool dir_output_high() const { return dir_high_; }
  void set_dir_output(bool high, Tick now) {
    if (high != dir_high_) dir_changed_at_ = now;
    dir_high_ = high;
  }
  bool estop_active() const { return selected_motor_->levels.emergency_stop(); }

  // The inputs of the motor stepped and sensed, as of the last edge the core applied (at
  // every step, and at the start of every advance_to); `inputs(n)`: motor n's.
  const InputLevels& inputs() const { return selected_motor_->levels; }
  const InputLevels& inputs(unsigned n) const { return motors_.at(n).levels; }
  // The motor stepped and sensed (SPM30 3.2 SELECT AXIS picks one of three): its encoder.
  const MotorPort& motor() const { return *selected_motor_->port; }
  const MotorPort& motor(unsigned n) const { return *motors_.at(n).port; }
  unsigned motors() const { return static_cast<unsigned>(motors_.size()); }
  unsigned selected() const { return static_cast<unsigned>(selected_motor_ - motors_.data()); }
  void select(unsigned n) {
    selected_motor_ = &motors_[n];
    update_rounds();
    step_rounds_ = false;  // a rule's select: the next round looks at this motor's e-stop
  }

  // `self`: the front end the listener is (its own jobs' steps go to its after_step only).
  void listen(AxisListener& listener, const FrontEnd* self = nullptr) {
    listeners_.push_back({&listener, self});
  }
  // Whether `listener` is given every step (step_taken); off, a step costs it nothing.
  void watch_steps(const AxisListener& listener, bool on);
  // Whether `listener` is given every input edge (input_changed).
  void watch_inputs(const AxisListener& listener, bool on);

 private:
  void take(const Step& step);
  void send(const Step& step);
  void after_take(const Step& step);
  void take_due(Tick now);
  bool round(Tick now);
  void update_rounds();
  void read_inputs();
  void emergency_stop(Tick now);
  bool ramp_ends_later(Tick now);
  StepPort& port() { return *selected_motor_->port; }
  // The course changed at `at`: the steps queued after it are taken back and the planner
  // starts again from the core's state.
  void replan(Tick at);
  void plan();

  struct Motor {
    MotorPort* port;
    InputLevels levels;
  };
  std::vector<Motor> motors_;
  StepGenerator generator_;  // the job's state at the last step taken
  StepGenerator planner_;    // with a horizon: runs ahead of generator_, queuing steps
  Tick horizon_ = 0;
  Tick now_ = 0;  // the latest advance_to
  void set_owner(FrontEnd* owner);

  FrontEnd* owner_ = nullptr;
  FrontEnd::Hooks hooks_;
  bool waiting_ = false;
  struct Listener {
    AxisListener* listener;
    const FrontEnd* self;
    bool steps = false;
    bool inputs = false;
  };
  std::vector<Listener> listeners_;
  unsigned step_watchers_ = 0;
  unsigned input_watchers_ = 0;
  int32_t position_ = 0;
  bool dir_high_ = false;
  Tick dir_changed_at_ = -(Tick{1} << 60);  // long before any motion: DIR has been stable
  Motor* selected_motor_ = nullptr;         // the motor stepped and sensed, in motors_
  // What a step's round needs, worked out when the job, its hooks or the horizon change
  // rather than at every step: a step goes straight to the step sink (horizon 0, no pulse
  // hook); a round has nothing but the step (an owner, no wait, no deadline, no
  // before_step hook); the owner's after_step is called (every_step, or an input of its
  // step_rule_inputs active).
  bool direct_steps_ = true;
  bool step_rounds_ = false;
  bool step_rule_ = false;
  // The owner's step_rule_position, or one outside int32: a position the motor never has.
  static constexpr int64_t kNoPosition = int64_t{1} << 40;
  int64_t rule_position_ = kNoPosition;
};

}  // namespace stepnode::motion
