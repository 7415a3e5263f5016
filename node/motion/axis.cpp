#include "node/motion/axis.hpp"

#include <algorithm>
#include <bit>
#include <cstdlib>
#include <stdexcept>

namespace stepnode::motion {
namespace {

constexpr Tick kOriginDwellTicks = kClockHz / 20;  // 50 ms (SPM30 4 FIND HOME step 5)

int64_t floor_div(int64_t a, int64_t b) {
  int64_t q = a / b;
  return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

bool is_set(uint16_t bits, uint16_t bit) { return (bits & bit) != 0; }

}  // namespace

Axis::Axis(AxisConfig config, std::vector<MotorPort*> motors, const bool* estop)
    : config_(config), motors_(std::move(motors)), estop_(estop) {
  if (motors_.empty()) throw std::invalid_argument("an axis needs at least one motor");
  saved_.resize(motors_.size());
  power_up(0);
}

void Axis::power_up(Tick now) {
  generator_.halt(now);
  job_ = Job::None;
  errors_ = status::kPowerUp;  // SPM30 3.1: every bit off except %I8
  position_valid_ = false;
  resumable_ = false;
  waiting_for_limit_release_ = false;
  selected_ = 0;
  motor_position_ = 0;
  encoder_offset_ = 0;
  encoder_offset_ = -encoder_position();  // encoder position 0 at power-up
  for (auto& s : saved_) s = Saved{};
  previous_commands_ = commands_;
  last_status_ = status();
}

bool Axis::origin_active() const {
  return config_.origin_source == AxisConfig::OriginSource::Marker ? motor().marker() : motor().home();
}

int32_t Axis::encoder_position() const {
  // The encoder belongs to the first motor (SPM30 3.3.2: axis 1's, whatever is selected).
  if (config_.encoder == EncoderKind::None) return selected_ == 0 ? motor_position_ : saved_[0].position;
  int64_t steps = floor_div(motors_[0]->encoder_count() * config_.encoder_multiplier,
                            std::max<int64_t>(config_.encoder_divisor, 1));
  return static_cast<int32_t>(encoder_offset_ + steps);
}

uint16_t Axis::status() const {
  uint16_t s = errors_;
  if (position_valid_) s |= status::kPositionValid;
  if (resumable_) s |= status::kResumable;
  if (selected_ == 1) s |= status::kAxis2Selected;
  if (selected_ == 2) s |= status::kAxis3Selected;
  if (origin_active()) s |= status::kAtHome;
  switch (generator_.phase()) {
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

std::optional<Tick> Axis::next_step_time() { return generator_.peek(); }

void Axis::latch(uint16_t error_bits, Tick now) {
  // Errors stop motion at once (the heartbeat loss decelerates: see master_lost).
  if (generator_.moving()) {
    generator_.halt(now);
    position_valid_ = false;  // SPM30 3.3.1: a sudden stop invalidates the position
  }
  if (job_ == Job::External) end_external(ExternalEnd::Aborted, now);
  job_ = Job::None;
  waiting_for_limit_release_ = false;
  resumable_ = false;
  errors_ |= error_bits;
  notify(AxisEvent::Error, error_bits);
}

std::optional<RampSpec> Axis::ramp_from_words(Tick now, bool index_decel) {
  try {
    uint16_t decel = words_.deceleration_ms;
    if (index_decel && words_.index_deceleration_ms != 0) decel = words_.index_deceleration_ms;
    return horner_ramp(words_.velocity_divisor, words_.base_velocity, words_.running_velocity,
                       words_.acceleration_ms, decel);
  } catch (const std::invalid_argument&) {
    latch(status::kIllegalMove, now);  // the words do not describe a possible move
    return std::nullopt;
  }
}

void Axis::start_motion(const RampSpec& ramp, int direction, std::optional<int64_t> distance, Tick now) {
  job_direction_ = direction;
  dir_high_ = direction > 0;  // DIR set at the start of every move (STP100 5.3.5)
  generator_.start(ramp, now, direction, distance);
  stall_window_steps_ = 0;
  stall_window_encoder_start_ = encoder_position();
}

void Axis::start_base_run(int direction, Tick now) {
  RampSpec base = move_ramp_;
  base.run_level = base.base_level;  // constant base velocity, no ramp
  base.horner_triangle_rule = false;
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
  index_was_active_ = motor().index();  // an index already on was received before the window
  if (distance == 0) {
    job_ = Job::None;
    notify(AxisEvent::MoveDone);
    return;
  }
  int direction = distance > 0 ? +1 : -1;
  job_direction_ = direction;
  if (estop_ && *estop_) {
    latch(status::kEmergencyStop, now);
    return;
  }
  bool toward_limit = direction > 0 ? motor().upper_limit() : motor().lower_limit();
  if (toward_limit) {
    if (config_.limit_started_moves) {
      // STP100 5.3.4: the move starts when the limit input is released.
      waiting_for_limit_release_ = true;
      dir_high_ = direction > 0;
      return;
    }
    latch(direction > 0 ? status::kUpperLimit : status::kLowerLimit, now);
    return;
  }
  start_motion(ramp, direction, std::llabs(distance), now);
}

void Axis::select(unsigned index, Tick now) {
  (void)now;
  if (index == selected_ || index >= motors_.size()) return;  // same or illegal: nothing
  saved_[selected_] = Saved{motor_position_, position_valid_, origin_active()};
  selected_ = index;
  const Saved& s = saved_[selected_];
  motor_position_ = s.position;
  position_valid_ = s.valid;
  // SPM30 SELECT AXIS step 5: if at-home changed since last selected, the position is
  // no longer trusted.
  if (origin_active() != s.at_home) position_valid_ = false;
}

void Axis::execute(uint16_t bit, Tick now) {
  const bool moving = generator_.moving() || waiting_for_limit_release_;
  switch (bit) {
    case command::kClearErrors: errors_ = 0; break;
    case command::kImmediateStop:
      if (moving) {
        generator_.halt(now);
        position_valid_ = false;  // SPM30 IMMEDIATE STOP
      }
      waiting_for_limit_release_ = false;
      if (job_ == Job::External) end_external(ExternalEnd::Aborted, now);
      job_ = Job::None;
      break;
    case command::kDecelStop:
      if (waiting_for_limit_release_) {
        waiting_for_limit_release_ = false;
        resumable_ = true;  // nothing moved yet: the whole move can be resumed
      } else if (moving) {
        generator_.stop(now);
        // SPM30 4 DECELERATE AND STOP: decelerate to base and stop. A Find Home ends there;
        // it must not go on to steps 4-7 when the origin passes during the ramp down.
        if (job_ == Job::Home) job_ = Job::None;
      }
      break;
    case command::kSetPosition:
      // SPM30 3.4 / 3.4.1: DESTINATION POSITION is -8,388,608..+8,388,607; outside it the
      // command is not possible (Illegal Move) rather than a position the module cannot hold.
      if (words_.destination < kPositionMin || words_.destination > kPositionMax)
        return latch(status::kIllegalMove, now);
      motor_position_ = words_.destination;
      // SPM30 4 SET CURRENT POSITION: "(and into ENCODER POSITION if axis 1 is selected)".
      if (selected_ == 0) encoder_offset_ += words_.destination - encoder_position();
      position_valid_ = true;
      break;
    case command::kSelectAxis1: select(0, now); break;
    case command::kSelectAxis2: select(1, now); break;
    case command::kSelectAxis3: select(2, now); break;
    case command::kFindHomeUp:
    case command::kFindHomeDown: {
      // SPM30 3.4.1: the destination is loaded into MOTOR POSITION at the end; one the module
      // cannot hold makes the command impossible (Illegal Move), checked before any motion.
      if (words_.destination < kPositionMin || words_.destination > kPositionMax)
        return latch(status::kIllegalMove, now);
      auto ramp = ramp_from_words(now);
      if (!ramp) return;
      position_valid_ = false;  // FIND HOME step 1
      job_ = Job::Home;
      home_stage_ = HomeStage::Seek;
      move_ramp_ = *ramp;
      origin_inactive_since_.reset();
      int direction = bit == command::kFindHomeUp ? +1 : -1;
      if (estop_ && *estop_) return latch(status::kEmergencyStop, now);
      // SPM30 3.3.1 / 4: an active end limit blocks motion in its direction, so the search
      // takes no step into it: a limit error, or (limit-switch-qualified, STP100 5.3.2 step 3)
      // the limit is already reached and the search goes on from step 4.
      if (direction > 0 ? motor().upper_limit() : motor().lower_limit()) {
        if (!config_.limit_qualified_home)
          return latch(direction > 0 ? status::kUpperLimit : status::kLowerLimit, now);
        job_direction_ = direction;
        dir_high_ = direction > 0;
        home_event(now, /*at_limit=*/true);
        break;
      }
      start_motion(*ramp, direction, std::nullopt, now);
      break;
    }
    case command::kJogUp:
    case command::kJogDown: {
      auto ramp = ramp_from_words(now);
      if (!ramp) return;
      int direction = bit == command::kJogUp ? +1 : -1;
      if (estop_ && *estop_) return latch(status::kEmergencyStop, now);
      if (direction > 0 ? motor().upper_limit() : motor().lower_limit())
        return latch(direction > 0 ? status::kUpperLimit : status::kLowerLimit, now);
      job_ = Job::Jog;
      move_ramp_ = *ramp;
      start_motion(*ramp, direction, std::nullopt, now);
      break;
    }
    case command::kMoveRelative:
    case command::kMoveAbsolute:
    case command::kMoveIndexed: {
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
      int64_t distance = bit == command::kMoveAbsolute
                             ? int64_t{words_.destination} - motor_position_
                             : int64_t{words_.destination};
      move_repeatable_ = bit != command::kMoveAbsolute;  // STP100 5.3.6
      repeat_distance_ = distance;
      start_move(distance, *ramp, now, bit == command::kMoveIndexed);
      break;
    }
    case command::kResumeMove: {
      if (!resumable_) return latch(status::kIllegalMove, now);
      resumable_ = false;
      // From where it left off, toward the original target, with the original ramp.
      start_move((move_target_steps_ - move_done_steps_) * job_direction_, move_ramp_, now,
                 move_indexed_, /*resume=*/true);
      break;
    }
    default: break;
  }
}

void Axis::write_commands(uint16_t bits, Tick now) {
  advance_to(now);
  uint16_t rising = bits & ~previous_commands_;
  uint16_t falling = previous_commands_ & ~bits;
  previous_commands_ = commands_ = bits;

  // Jog is level-sensitive: releasing the bit decelerates and stops (SPM30 JOG).
  if (job_ == Job::Jog && generator_.moving() &&
      ((job_direction_ > 0 && is_set(falling, command::kJogUp)) ||
       (job_direction_ < 0 && is_set(falling, command::kJogDown))))
    generator_.stop(now);

  uint16_t candidates = rising & static_cast<uint16_t>(~command::kRepeatMove);  // %Q12 is a level
  if (!config_.indexed_moves) candidates &= static_cast<uint16_t>(~command::kMoveIndexed);  // future use
  if (motors_.size() < 2) candidates &= static_cast<uint16_t>(~(command::kSelectAxis2 | command::kSelectAxis3));
  if (motors_.size() < 3) candidates &= static_cast<uint16_t>(~command::kSelectAxis3);
  // While an error is latched only Clear Errors is obeyed; while moving only the stops.
  if (errors_) candidates &= command::kClearErrors;
  else if (generator_.moving() || waiting_for_limit_release_)
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
  if (generator_.moving()) generator_.stop(now);
  if (job_ == Job::Home) job_ = Job::None;  // ramp down and stop: the search does not go on
  waiting_for_limit_release_ = false;
  resumable_ = false;
  errors_ |= status::kPowerUp;
  notify(AxisEvent::Error, status::kPowerUp);
}

void Axis::check_position_valid() {
  if (config_.encoder == EncoderKind::None || config_.encoder_tolerance <= 0 || selected_ != 0) return;
  if (std::llabs(int64_t{motor_position_} - encoder_position()) >= config_.encoder_tolerance)
    position_valid_ = false;  // SPM30 5.4: when the difference reaches the tolerance
}

void Axis::check_stall(const Step& step) {
  if (!config_.stall_detection || config_.encoder == EncoderKind::None || selected_ != 0) return;
  // Over a window of commanded steps, the encoder must show at least 10% of the motion
  // (STP100 6.3.3). The window spans several encoder counts, so resolution is no issue.
  int64_t steps_per_count = (config_.encoder_multiplier + config_.encoder_divisor - 1) /
                            std::max<int64_t>(config_.encoder_divisor, 1);
  int64_t window = std::max<int64_t>(32, 20 * steps_per_count);
  if (++stall_window_steps_ < window) return;
  int64_t moved = std::llabs(int64_t{encoder_position()} - stall_window_encoder_start_);
  stall_window_steps_ = 0;
  stall_window_encoder_start_ = encoder_position();
  if (moved * 10 < window) latch(status::kMotorStalled, step.time);
}

void Axis::on_step(const Step& step) {
  if (job_ == Job::External && external_pulse) motor().output_pulse(step.time, external_pulse(step));
  else motor().step(step.time, step.direction);  // the step sink
  motor_position_ += step.direction;
  if (job_ == Job::Move) ++move_done_steps_;
  if (on_any_step) on_any_step(step);
}

void Axis::start_external(const RampSpec& ramp, int direction, std::optional<int64_t> steps, Tick now) {
  advance_to(now);
  job_ = Job::External;
  resumable_ = false;
  start_motion(ramp, direction, steps, now);
  notify(AxisEvent::StatusChanged);
}

void Axis::external_halt(Tick now) {
  if (job_ != Job::External) return;
  generator_.halt(now);
  job_ = Job::None;
  notify(AxisEvent::StatusChanged);
}

void Axis::end_external(ExternalEnd how, Tick now) {
  job_ = Job::None;
  if (on_external_end) on_external_end(how, now);
}

void Axis::home_event(Tick now, bool at_limit) {
  bool origin = origin_active();
  switch (home_stage_) {
    case HomeStage::Seek:
      // Step 3: stop at once on the origin, or (limit-switch-qualified, STP100 3.2.3) on
      // the end limit of the direction of travel.
      if (config_.limit_qualified_home ? !at_limit : !origin) return;
      generator_.halt(now);
      break;
    case HomeStage::BackToOrigin:
      if (origin) {
        home_stage_ = HomeStage::Clear;  // step 5: keep going till inactive for 50 ms
        origin_inactive_since_.reset();
      }
      return;
    case HomeStage::Clear:
      if (origin) origin_inactive_since_.reset();
      else if (!origin_inactive_since_) origin_inactive_since_ = now;
      return;
    case HomeStage::Approach:
      if (!origin) return;
      generator_.halt(now);  // step 7: precisely at home
      break;
  }
  // Here after a halt in Seek (origin, or limit when qualified) or at the end of Approach.
  if (home_stage_ == HomeStage::Seek && config_.home_method == AxisConfig::HomeMethod::Normal) {
    // Step 4: back at base velocity till the origin is active again. Whether it still is
    // active is decided as each step of that run is due (advance_to), not here at the stop:
    // a load that coasted past the origin ("just in case we shot right past home", SPM30 4
    // FIND HOME step 4) must come back to it; one still on it goes straight on to step 5.
    home_stage_ = HomeStage::BackToOrigin;
    origin_inactive_since_.reset();
    start_base_run(-job_direction_, now);
    job_direction_ = generator_.direction();
    return;
  }
  // Step 8: the destination becomes motor position, and encoder position "if axis 1 is
  // selected" (SPM30 4 FIND HOME step 7).
  motor_position_ = words_.destination;
  if (selected_ == 0) encoder_offset_ += words_.destination - encoder_position();
  position_valid_ = true;
  job_ = Job::None;
  notify(AxisEvent::MoveDone);
}

void Axis::after_step(const Step& step) {
  Tick t = step.time;
  if (estop_ && *estop_) return latch(status::kEmergencyStop, t);
  if (job_ == Job::External) {
    check_position_valid();
    if (on_external_step) on_external_step(step);
    return;
  }
  if (step.direction < 0 && motor().lower_limit()) {
    if (job_ == Job::Home && home_stage_ == HomeStage::Seek && config_.limit_qualified_home) {
      return home_event(t, /*at_limit=*/true);
    }
    return latch(status::kLowerLimit, t);
  }
  if (step.direction > 0 && motor().upper_limit()) {
    if (job_ == Job::Home && home_stage_ == HomeStage::Seek && config_.limit_qualified_home) {
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
    bool index = motor().index();
    bool became_active = index && !index_was_active_;
    index_was_active_ = index;
    bool window = generator_.phase() == MotionPhase::Running && generator_.level() >= move_ramp_.run_level &&
                  move_done_steps_ >= int64_t{index_window_open_} &&
                  move_done_steps_ < int64_t{index_window_close_};
    if (window && became_active) {
      index_taken_ = true;
      RampSpec alternate = move_ramp_;
      alternate.decel_ticks_per_level = index_ramp_.decel_ticks_per_level;
      generator_.retarget(t, index_destination_, alternate);
      move_target_steps_ = move_done_steps_ + index_destination_;
    }
  }
}

void Axis::finish(Tick now) {
  Job job = job_;
  job_ = Job::None;
  if (job == Job::External) {
    end_external(ExternalEnd::Completed, now);
    return notify(AxisEvent::StatusChanged);
  }
  if (job == Job::Home) return notify(AxisEvent::StatusChanged);  // stopped before home
  if (job == Job::Move) {
    if (move_done_steps_ >= move_target_steps_) {
      if (move_indexed_) dir_high_ = false;  // DIR as move-in-progress (STP100 5.3.5)
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

void Axis::advance_to(Tick now) {
  for (;;) {
    // SPM30 3.3.1 / STP100 4.2.1: the e-stop input stops motion at once. It is not a function
    // of the position, so it is looked at before every step (and while a limit-started move
    // waits): no step goes out once it is active, and %I1 shows as soon as the axis is told.
    if (estop_ && *estop_ && (generator_.moving() || waiting_for_limit_release_)) {
      latch(status::kEmergencyStop, now);
      continue;
    }
    if (waiting_for_limit_release_) {
      bool still = job_direction_ > 0 ? motor().upper_limit() : motor().lower_limit();
      if (still) break;
      waiting_for_limit_release_ = false;
      start_motion(move_ramp_, job_direction_, move_target_steps_ - move_done_steps_, now);
    }
    // The 50 ms dwell of FIND HOME step 5 ends between steps at base velocity.
    std::optional<Tick> deadline;
    if (job_ == Job::Home && home_stage_ == HomeStage::Clear && origin_inactive_since_)
      deadline = *origin_inactive_since_ + kOriginDwellTicks;
    std::optional<Tick> next = generator_.peek();
    if (!next && generator_.moving()) {
      // The ramp ends between steps (a stop at base velocity): go idle when it ends.
      StepGenerator ahead = generator_;
      Step none;
      ahead.next(none);
      if (ahead.marks().end > now) break;
      generator_.next(none);
      continue;
    }
    if (deadline && *deadline <= now && (!next || *next > *deadline)) {
      generator_.halt(*deadline);
      home_stage_ = HomeStage::Approach;  // step 6: reverse, base velocity, to the origin
      origin_inactive_since_.reset();
      start_base_run(-job_direction_, *deadline);
      job_direction_ = generator_.direction();
      continue;
    }
    if (!next || *next > now) {
      if (!generator_.moving() && job_ != Job::None && !waiting_for_limit_release_) {
        finish(generator_.time());
        continue;
      }
      break;
    }
    // FIND HOME step 4 ends when the origin is active again; that includes before the first
    // step back (still on it after the stop) and after the load was moved by hand.
    if (job_ == Job::Home && home_stage_ == HomeStage::BackToOrigin && origin_active()) {
      home_stage_ = HomeStage::Clear;
      origin_inactive_since_.reset();
    }
    Step step;
    generator_.next(step);
    on_step(step);
    after_step(step);
  }
  // STP100 6.3.2: motor and encoder positions are compared continuously, so an external force
  // on a standing motor (SPM30 5.4 item 6) turns %I9 off too, not only a step.
  check_position_valid();
  notify(AxisEvent::StatusChanged);
}

}  // namespace stepnode::motion
