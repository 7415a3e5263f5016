#include "node/motion/axis.hpp"

#include <algorithm>
#include <bit>
#include <cstdlib>
#include <stdexcept>

namespace stepnode::motion {
namespace {

int64_t floor_div(int64_t a, int64_t b) {
  int64_t q = a / b;
  return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

bool is_set(uint16_t bits, uint16_t bit) { return (bits & bit) != 0; }

}  // namespace

Axis::Axis(AxisConfig config, AxisCore& core) : config_(config), core_(core) {
  saved_.resize(core_.motors());
  core_.listen(*this, this);
  set_config(config_);
  power_up(0);
}

Axis::Axis(AxisConfig config, std::vector<MotorPort*> motors)
    : config_(config), own_core_(std::make_unique<AxisCore>(std::move(motors))), core_(*own_core_) {
  saved_.resize(core_.motors());
  core_.listen(*this, this);
  set_config(config_);
  power_up(0);
}

Axis::Rules Axis::rules_of(const AxisConfig& c) {
  bool encoder = c.encoder != EncoderKind::None;
  if (c.module == AxisConfig::Module::Stp100)
    return Rules{.stall_detection = encoder && c.stall_detection,
                 .invalid_at_tolerance = false,
                 .marker_origin = c.origin_source == AxisConfig::OriginSource::Marker,
                 .limit_qualified = c.limit_qualified_home};
  // SPM30 5.4: "when ENCODER TOL is non-zero, the SPM30 uses the encoder feedback pulses to
  // verify motor velocity". SPM30 4 FIND HOME: with QUAD the marker is axis 1's home input
  // and step 3 stops on the end limit. The STP100 options still apply on top.
  bool quad = c.encoder == EncoderKind::Quadrature;
  return Rules{.stall_detection = encoder && c.encoder_tolerance > 0,
               .invalid_at_tolerance = true,
               .marker_origin = quad || c.origin_source == AxisConfig::OriginSource::Marker,
               .limit_qualified = quad || c.limit_qualified_home};
}

void Axis::set_config(const AxisConfig& config) {
  config_ = config;
  rules_ = rules_of(config_);
  // Another front end's steps matter to the module only for the position check.
  core_.watch_steps(*this, config_.encoder != EncoderKind::None && config_.encoder_tolerance > 0);
}

void Axis::power_up(Tick now) {
  if (own_core_) core_.power_up(now);
  job_ = Job::None;
  errors_ = status::kPowerUp;  // SPM30 3.1: every bit off except %I8
  position_valid_ = false;
  resumable_ = false;
  waiting_for_limit_release_ = false;
  encoder_offset_ = 0;
  encoder_offset_ = -encoder_position();  // encoder position 0 at power-up
  for (auto& s : saved_) s = Saved{};
  previous_commands_ = commands_;
  last_status_ = status();
}

bool Axis::origin_active() const {
  // The marker is wired to axis 1's home input (SPM30 4 FIND HOME, 5.1); the other motors
  // of a multiplexed axis keep their home switches.
  bool marker = rules_.marker_origin && core_.selected() == 0;
  return marker ? inputs().marker() : inputs().home();
}

int64_t Axis::encoder_counts() const {
  int64_t counts = core_.motor(0).encoder_count();
  if (config_.encoder == EncoderKind::UpDown) return counts;
  // A quadrature port counts every edge of A and B (4 per line); the module counts lines,
  // or 2 / 4 per line when its decoding doubles or quadruples the resolution.
  return floor_div(counts * std::clamp<int64_t>(config_.quadrature_decoding, 1, 4), 4);
}

int32_t Axis::encoder_position() const {
  // The encoder belongs to the first motor (SPM30 3.3.2: axis 1's, whatever is selected).
  if (config_.encoder == EncoderKind::None) return core_.selected() == 0 ? core_.position() : saved_[0].position;
  int64_t steps = floor_div(encoder_counts() * config_.encoder_multiplier,
                            std::max<int64_t>(config_.encoder_divisor, 1));
  return static_cast<int32_t>(encoder_offset_ + steps);
}

uint16_t Axis::status() const {
  uint16_t s = errors_;
  if (position_valid_) s |= status::kPositionValid;
  if (resumable_) s |= status::kResumable;
  if (core_.selected() == 1) s |= status::kAxis2Selected;
  if (core_.selected() == 2) s |= status::kAxis3Selected;
  if (origin_active()) s |= status::kAtHome;
  switch (core_.generator().phase()) {
    case MotionPhase::Accelerating: s |= status::kAccelerating | status::kMoving; break;
    case MotionPhase::Decelerating: s |= status::kDecelerating | status::kMoving; break;
    case MotionPhase::Running:
    case MotionPhase::Creeping: s |= status::kMoving; break;
    case MotionPhase::Idle: break;
  }
  if (waiting_for_limit_release_) s |= status::kMoving;  // the move is in progress
  return s;
}

void Axis::notify(AxisEvent::Kind kind, uint16_t error_bits) {
  uint16_t s = status();
  if (kind == AxisEvent::StatusChanged && s == last_status_) return;
  last_status_ = s;
  if (on_event) on_event(AxisEvent{kind, s, error_bits});
}

void Axis::latch(uint16_t error_bits, Tick now) {
  // Errors stop motion at once, whichever front end's job runs (the heartbeat loss
  // decelerates: see master_lost).
  const bool was_moving = core_.moving();
  core_.abort(this, now);
  latched(error_bits, was_moving);
}

void Axis::emergency_stop(Tick when, bool was_moving) {
  (void)when;
  latched(status::kEmergencyStop, was_moving);
}

void Axis::end_job() {
  // STP100 5.3.5 NOTE: "at the end of an Indexed Move, DIR+ and DIR- are always taken Low
  // and High": DIR is its move-in-progress output, whatever ended the move.
  if (job_ == Job::Move && move_indexed_) core_.set_dir_output(false);
  job_ = Job::None;
}

void Axis::latched(uint16_t error_bits, bool was_moving) {
  if (was_moving) position_valid_ = false;  // SPM30 3.3.1: a sudden stop invalidates the position
  end_job();
  waiting_for_limit_release_ = false;
  resumable_ = false;
  errors_ |= error_bits;
  notify(AxisEvent::Error, error_bits);
}

std::optional<RampSpec> Axis::ramp_from_words(Tick now, bool index_decel) {
  try {
    uint16_t decel = words_.deceleration_ms;
    if (index_decel && words_.index_deceleration_ms != 0) decel = words_.index_deceleration_ms;
    RampSpec r = horner_ramp(words_.velocity_divisor, words_.base_velocity, words_.running_velocity,
                             words_.acceleration_ms, decel);
    if (config_.stpcalc_peak_short_moves) r.short_move = RampSpec::ShortMove::StpcalcPeak;
    return r;
  } catch (const std::invalid_argument&) {
    latch(status::kIllegalMove, now);  // the words do not describe a possible move
    return std::nullopt;
  }
}

bool Axis::start_motion(const RampSpec& ramp, int direction, std::optional<int64_t> distance, Tick now) {
  job_direction_ = direction;
  // DIR is set at the start of every move (STP100 5.3.5), by the core.
  if (!core_.start(*this, ramp, direction, distance, now)) {
    job_ = Job::None;  // another front end's job: the command filter keeps this from happening
    return false;
  }
  restart_stall_windows(direction);
  return true;
}

void Axis::start_base_run(int direction, Tick now) {
  RampSpec base = move_ramp_;
  base.run_level = base.base_level;  // constant base velocity, no ramp
  base.short_move = RampSpec::ShortMove::Meet;
  start_motion(base, direction, std::nullopt, now);
}

void Axis::start_move(int64_t distance, const RampSpec& ramp, Tick now, bool indexed, bool resume) {
  job_ = Job::Move;
  move_ramp_ = ramp;
  move_indexed_ = indexed;
  if (!resume) {
    index_taken_ = false;
    move_target_steps_ = std::llabs(distance);
    move_done_steps_ = 0;
  }
  index_was_active_ = inputs().index();  // an index already on was received before the window
  if (distance == 0) {
    job_ = Job::None;
    notify(AxisEvent::MoveDone);
    return;
  }
  int direction = distance > 0 ? +1 : -1;
  job_direction_ = direction;
  if (core_.estop_active()) {
    latch(status::kEmergencyStop, now);
    return;
  }
  bool toward_limit = direction > 0 ? inputs().upper_limit() : inputs().lower_limit();
  if (toward_limit) {
    if (config_.limit_started_moves) {
      // STP100 5.3.4: the move starts when the limit input is released.
      waiting_for_limit_release_ = true;
      core_.claim(*this, now);
      core_.set_dir_output(direction > 0);
      return;
    }
    latch(direction > 0 ? status::kUpperLimit : status::kLowerLimit, now);
    return;
  }
  start_motion(ramp, direction, std::llabs(distance), now);
}

void Axis::select(unsigned index, Tick now) {
  (void)now;
  if (index == core_.selected() || index >= core_.motors()) return;  // same or illegal: nothing
  saved_[core_.selected()] = Saved{core_.position(), position_valid_, origin_active()};
  core_.select(index);
  const Saved& s = saved_[index];
  core_.set_position(s.position);
  position_valid_ = s.valid;
  // SPM30 SELECT AXIS step 5: if at-home changed since last selected, the position is
  // no longer trusted.
  if (origin_active() != s.at_home) position_valid_ = false;
}

void Axis::execute(uint16_t bit, Tick now) {
  switch (bit) {
    case command::kClearErrors: errors_ = 0; break;
    case command::kImmediateStop: immediate_stop(now); break;
    case command::kDecelStop: decelerate_and_stop(now); break;
    case command::kSetPosition: set_current_position(now); break;
    case command::kSelectAxis1: select(0, now); break;
    case command::kSelectAxis2: select(1, now); break;
    case command::kSelectAxis3: select(2, now); break;
    case command::kFindHomeUp: find_home(+1, now); break;
    case command::kFindHomeDown: find_home(-1, now); break;
    case command::kJogUp: jog(+1, now); break;
    case command::kJogDown: jog(-1, now); break;
    case command::kMoveRelative:
    case command::kMoveAbsolute:
    case command::kMoveIndexed: move(bit, now); break;
    case command::kResumeMove: resume_move(now); break;
    default: break;
  }
}

void Axis::immediate_stop(Tick now) {
  // Whichever front end's job runs (README: the front ends' arbitration).
  if (moving()) position_valid_ = false;  // SPM30 IMMEDIATE STOP
  core_.abort(this, now);
  waiting_for_limit_release_ = false;
  end_job();
}

void Axis::decelerate_and_stop(Tick now) {
  if (waiting_for_limit_release_) {
    waiting_for_limit_release_ = false;
    core_.end_wait(*this);  // the job ends (motion_ended) at the next advance
    resumable_ = true;      // nothing moved yet: the whole move can be resumed
  } else if (core_.moving()) {
    core_.stop(now);
    // SPM30 4 DECELERATE AND STOP: decelerate to base and stop. A Find Home ends there;
    // it must not go on to steps 4-7 when the origin passes during the ramp down.
    if (job_ == Job::Home) job_ = Job::None;
  }
}

void Axis::set_current_position(Tick now) {
  // SPM30 3.4 / 3.4.1: DESTINATION POSITION is -8,388,608..+8,388,607; outside it the
  // command is not possible (Illegal Move) rather than a position the module cannot hold.
  if (words_.destination < kPositionMin || words_.destination > kPositionMax)
    return latch(status::kIllegalMove, now);
  core_.set_position(words_.destination);
  // SPM30 4 SET CURRENT POSITION: "(and into ENCODER POSITION if axis 1 is selected)".
  if (core_.selected() == 0) encoder_offset_ += words_.destination - encoder_position();
  position_valid_ = true;
}

void Axis::jog(int direction, Tick now) {
  auto ramp = ramp_from_words(now);
  if (!ramp) return;
  if (core_.estop_active()) return latch(status::kEmergencyStop, now);
  if (direction > 0 ? inputs().upper_limit() : inputs().lower_limit())
    return latch(direction > 0 ? status::kUpperLimit : status::kLowerLimit, now);
  job_ = Job::Jog;
  move_ramp_ = *ramp;
  start_motion(*ramp, direction, std::nullopt, now);
}

void Axis::move(uint16_t bit, Tick now) {
  if (words_.destination < kPositionMin || words_.destination > kPositionMax)
    return latch(status::kIllegalMove, now);
  // MOVE ABSOLUTE needs a valid position (SPM30 3.3.1).
  if (bit == command::kMoveAbsolute && !position_valid_) return latch(status::kIllegalMove, now);
  auto ramp = ramp_from_words(now);
  if (!ramp) return;
  if (bit == command::kMoveIndexed) {
    // SPM30 3.4 / STP100 4.2.3: the words may be changed for the next command as soon as
    // this one started, so the index words (and the alternate deceleration, %AQ10) are
    // taken now, not when the index comes.
    auto index_ramp = ramp_from_words(now, /*index_decel=*/true);
    if (!index_ramp) return;
    index_ramp_ = *index_ramp;
    index_destination_ = words_.index_destination;
    index_window_open_ = words_.index_window_open;
    index_window_close_ = words_.index_window_close;
  }
  int64_t distance = bit == command::kMoveAbsolute ? int64_t{words_.destination} - core_.position()
                                                   : int64_t{words_.destination};
  move_repeatable_ = bit != command::kMoveAbsolute;  // STP100 5.3.6
  repeat_distance_ = distance;
  start_move(distance, *ramp, now, bit == command::kMoveIndexed);
}

void Axis::resume_move(Tick now) {
  if (!resumable_) return latch(status::kIllegalMove, now);
  resumable_ = false;
  // From where it left off, toward the original target, with the original ramp.
  start_move((move_target_steps_ - move_done_steps_) * job_direction_, move_ramp_, now, move_indexed_,
             /*resume=*/true);
}

void Axis::write_commands(uint16_t bits, Tick now) {
  advance_to(now);
  uint16_t rising = bits & ~previous_commands_;
  uint16_t falling = previous_commands_ & ~bits;
  previous_commands_ = commands_ = bits;

  // Jog is level-sensitive: releasing the bit decelerates and stops (SPM30 JOG).
  if (job_ == Job::Jog && core_.moving() &&
      ((job_direction_ > 0 && is_set(falling, command::kJogUp)) ||
       (job_direction_ < 0 && is_set(falling, command::kJogDown))))
    core_.stop(now);

  uint16_t candidates = rising & static_cast<uint16_t>(~command::kRepeatMove);  // %Q12 is a level
  if (!config_.indexed_moves) candidates &= static_cast<uint16_t>(~command::kMoveIndexed);  // future use
  if (core_.motors() < 2) candidates &= static_cast<uint16_t>(~(command::kSelectAxis2 | command::kSelectAxis3));
  if (core_.motors() < 3) candidates &= static_cast<uint16_t>(~command::kSelectAxis3);
  // While an error is latched only Clear Errors and the two stops are obeyed (SPM30 4: their
  // "Status Bits Required: None"; a lost master's ramp, or another front end's job, can
  // still be stopped); while moving (any front end's job) only the stops.
  if (errors_) candidates &= command::kClearErrors | command::kDecelStop | command::kImmediateStop;
  else if (moving())
    candidates &= command::kDecelStop | command::kImmediateStop;
  if (candidates) {
    // Several at once: the highest %Q wins (SPM30 3.2).
    uint16_t bit = std::bit_floor(candidates);
    // Any command but Resume (and the Decelerate-and-Stop that pre-empts) ends resumability.
    if (bit != command::kResumeMove && !(bit == command::kDecelStop && job_ == Job::Move)) resumable_ = false;
    execute(bit, now);
  }
  notify(AxisEvent::StatusChanged);
}

void Axis::master_lost(Tick now) {
  advance_to(now);
  // A lost master must never leave a motor running: ramp down, and latch %I8 so nothing
  // moves again until the master is back and clears it.
  if (core_.moving()) core_.stop(now);
  if (job_ == Job::Home) job_ = Job::None;  // ramp down and stop: the search does not go on
  waiting_for_limit_release_ = false;
  core_.end_wait(*this);
  resumable_ = false;
  errors_ |= status::kPowerUp;
  notify(AxisEvent::Error, status::kPowerUp);
}

void Axis::check_position_valid() {
  if (config_.encoder == EncoderKind::None || config_.encoder_tolerance <= 0 || core_.selected() != 0) return;
  int64_t difference = std::llabs(int64_t{core_.position()} - encoder_position());
  // SPM30 5.4: "reaches encoder tolerance"; STP100 6.3.2: "exceeds the configured Encoder
  // Tolerance value".
  if (rules_.invalid_at_tolerance ? difference >= config_.encoder_tolerance
                                  : difference > config_.encoder_tolerance)
    position_valid_ = false;
}

void Axis::restart_stall_windows(int direction) {
  int64_t counts = config_.encoder == EncoderKind::None ? 0 : encoder_counts();
  stall_short_ = stall_long_ = StallWindow{0, counts};
  stall_direction_ = direction;
}

bool Axis::stalled_over(StallWindow& window, int64_t counts_per_window) {
  // The window spans the commanded steps worth `counts_per_window` encoder counts.
  int64_t mlt = config_.encoder_multiplier, div = std::max<int64_t>(config_.encoder_divisor, 1);
  if (++window.steps * div < counts_per_window * mlt) return false;
  int64_t counts = encoder_counts();
  int64_t measured = std::llabs(counts - window.counts_start);
  int64_t commanded_steps = window.steps;
  window = StallWindow{0, counts};
  // STP100 6.3.3: a stall when the measured velocity is less than 10 % of the theoretical
  // one, here over the same commanded steps: measured counts < 10 % of steps * DIV / MLT.
  // The count difference of a moving encoder is at most one count short of its true
  // motion, so the test is on measured + 1: a motor at 10 % or more is never a stall.
  return (measured + 1) * 10 * mlt < commanded_steps * div;
}

void Axis::check_stall(const Step& step) {
  if (!rules_.stall_detection || core_.selected() != 0) return;
  // A reversal (FIND HOME's runs at base velocity) begins new windows: net motion across
  // it says nothing about velocity.
  if (step.direction != stall_direction_) restart_stall_windows(step.direction);
  // 20 counts: a jammed encoder (no count at all) is caught within them; 1000 counts: a
  // slipping motor is judged to within 0.1 % of the threshold.
  bool stalled = stalled_over(stall_short_, 20);
  stalled = stalled_over(stall_long_, 1000) || stalled;
  if (stalled) latch(status::kMotorStalled, step.time);
}

void Axis::step_taken(const Step& step) {
  (void)step;
  // Another front end's job (the core gives the Horner jobs' steps to after_step): its rules
  // are its own, but the position check (STP100 6.3.2) is the module's, whoever moves the motor.
  check_position_valid();
}

void Axis::job_started(const FrontEnd& owner, Tick when) {
  (void)when;
  if (&owner == this) return;
  resumable_ = false;  // another front end moved the axis: nothing left to resume
  notify(AxisEvent::StatusChanged);
}

void Axis::job_halted(const FrontEnd& owner, Tick when) {
  (void)owner;
  (void)when;
  notify(AxisEvent::StatusChanged);
}

void Axis::aborted(Tick when) {
  (void)when;
  end_job();  // the e-stop, or another front end's stop (emergency_stop latches %I1)
  waiting_for_limit_release_ = false;
}

void Axis::after_step(const Step& step) {
  Tick t = step.time;
  if (job_ == Job::Move) ++move_done_steps_;
  if (step.direction < 0 && inputs().lower_limit()) {
    if (job_ == Job::Home && home_stage_ == HomeStage::Seek && limit_qualified_home()) {
      return home_event(t, /*at_limit=*/true);
    }
    return latch(status::kLowerLimit, t);
  }
  if (step.direction > 0 && inputs().upper_limit()) {
    if (job_ == Job::Home && home_stage_ == HomeStage::Seek && limit_qualified_home()) {
      return home_event(t, /*at_limit=*/true);
    }
    return latch(status::kUpperLimit, t);
  }
  check_stall(step);
  if (errors_ & status::kMotorStalled) return;
  check_position_valid();
  if (job_ == Job::Home) return home_event(t);
  if (job_ == Job::Move && move_indexed_ && !index_taken_) {
    // STP113 C1.3.4 / STP100 5.3.5: the index input counts only inside the window, which
    // opens at the running velocity and closes at the deceleration point. "The motor must
    // attain Running Velocity": the engine may also cruise below it (a short move capped at
    // STPCALC's peak), which does not open the window. The index counts when it "becomes
    // active" there: one already on when the window opened was "received before" it.
    bool index = inputs().index();
    bool became_active = index && !index_was_active_;
    index_was_active_ = index;
    const StepGenerator& g = core_.generator();
    bool window = g.phase() == MotionPhase::Running && g.level() >= move_ramp_.run_level &&
                  move_done_steps_ >= int64_t{index_window_open_} &&
                  move_done_steps_ < int64_t{index_window_close_};
    if (window && became_active) {
      index_taken_ = true;
      RampSpec alternate = move_ramp_;
      alternate.decel_ticks_per_level = index_ramp_.decel_ticks_per_level;
      core_.retarget(t, index_destination_, alternate);
      move_target_steps_ = move_done_steps_ + index_destination_;
    }
  }
}

void Axis::finish(Tick now) {
  Job job = job_;
  end_job();
  if (job == Job::None) return;  // the Home a Decelerate and Stop ended (its ramp just ran out)
  if (job == Job::Home) return notify(AxisEvent::StatusChanged);  // stopped before home
  if (job == Job::Move) {
    if (move_done_steps_ >= move_target_steps_) {
      notify(AxisEvent::MoveDone);
      // STP100 5.3.6: a relative or indexed move repeats while %Q12 is on.
      if (move_repeatable_ && is_set(commands_, command::kRepeatMove) && !errors_)
        start_move(repeat_distance_, move_ramp_, now, move_indexed_);
      return;
    }
    // Stopped short by Decelerate and Stop: resumable unless an error came (SPM30 %Q15).
    if (!errors_) resumable_ = true;
  }
  notify(AxisEvent::MoveDone);
}

void Axis::poll(Tick now) {
  bool still = job_direction_ > 0 ? inputs().upper_limit() : inputs().lower_limit();
  if (still) return;
  waiting_for_limit_release_ = false;
  start_motion(move_ramp_, job_direction_, move_target_steps_ - move_done_steps_, now);
}

void Axis::advanced(Tick now) {
  (void)now;
  // STP100 6.3.2: motor and encoder positions are compared continuously, so an external force
  // on a standing motor (SPM30 5.4 item 6) turns %I9 off too, not only a step.
  check_position_valid();
  notify(AxisEvent::StatusChanged);
}

}  // namespace stepnode::motion
