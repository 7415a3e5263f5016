// The Horner front end's commands (SPM30 section 4, STP100 5.3, STP113 C1.3): the command
// bits' edges and their filter (SPM30 3.2), and each command's rules; FIND HOME is in
// node/motion/axis_homing.cpp, the steps' rules in node/motion/axis_motion.cpp.
#include <algorithm>
#include <bit>
#include <cstdlib>
#include <stdexcept>

#include "node/motion/axis.hpp"

namespace stepnode::motion {

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

bool Axis::start_motion(const RampSpec& ramp, int direction, std::optional<int64_t> distance,
                        Tick now) {
  job_direction_ = direction;
  // DIR is set at the start of every move (STP100 5.3.5), by the core.
  const Tick dir_setup = (config_.direction_setup_us * kClockHz + 999'999) / 1'000'000;  // at least
  if (!core_.start(*this, ramp, direction, distance, now, dir_setup)) {
    job_ = Job::None;  // another front end's job: the command filter keeps this from happening
    return false;
  }
  // A move's steps are the generator's from here (move_done_steps()); the steps of its
  // earlier motions are in move_done_steps_ (the job's end settles each one).
  move_stepping_ = job_ == Job::Move;
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
    move_stepping_ = false;
  }
  index_was_active_ = inputs().index();  // an index already on was received before the window
  if (!resume && !ends_in_range(distance, indexed)) {
    job_ = Job::None;
    return latch(status::kIllegalMove, now);  // beyond the positions the module can hold
  }
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
      core_.set_dir_output(direction > 0, now);
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
  // Whichever front end's job runs (README: the front ends' arbitration). "If the motor was
  // moving" (SPM30 4 IMMEDIATE STOP, STP100 5.3.10) %I9 goes off: steps were going out, as
  // the e-stop's rule has it (AxisCore::emergency_stop); a limit-started move still waiting
  // for its limit's release sent none (STP100 5.3.4), so the position is still known.
  if (core_.moving()) position_valid_ = false;
  core_.abort(this, now);
  waiting_for_limit_release_ = false;
  end_job(now);
}

void Axis::decelerate_and_stop(Tick now) {
  if (waiting_for_limit_release_) {
    waiting_for_limit_release_ = false;
    core_.end_wait(*this);                    // the job ends (motion_ended) at the next advance
    resumable_ = preempted_move_resumable();  // nothing moved yet: all of it is left
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
  // The position words end at -8,388,608 and +8,388,607 (SPM30 3.3): a jog runs to the bound
  // at most and decelerates to stop on it; at the bound there is no jog further.
  int64_t to_bound = direction > 0 ? int64_t{kPositionMax} - core_.position()
                                   : int64_t{core_.position()} - kPositionMin;
  if (to_bound <= 0) return latch(status::kIllegalMove, now);
  job_ = Job::Jog;
  move_ramp_ = *ramp;
  const int64_t ramp_down =
      static_cast<int64_t>(ramp->decel_phase(ramp->run_level) / ramp->phase_per_step) + 2;
  jog_end_from_.reset();
  if (to_bound <= ramp_down) {
    start_motion(*ramp, direction, to_bound, now);
    return;
  }
  const int64_t bound = direction > 0 ? kPositionMax : kPositionMin;
  jog_end_from_ = static_cast<int32_t>(bound - direction * ramp_down);
  start_motion(*ramp, direction, std::nullopt, now);
}

bool Axis::ends_in_range(int64_t distance, bool indexed) const {
  const int64_t from = core_.position(), length = std::llabs(distance);
  int64_t furthest = length;
  if (indexed) {
    // An index counts while the window is open: from %AQ11 up to %AQ13 and the deceleration
    // point (before the end); the move then ends %AQ8 past the step it came at.
    int64_t last_index_step = std::min<int64_t>(index_window_close_, length) - 1;
    if (last_index_step >= int64_t{index_window_open_})
      furthest = std::max(furthest, last_index_step + int64_t{index_destination_});
  }
  const int64_t end = distance >= 0 ? from + furthest : from - furthest;
  return end >= kPositionMin && end <= kPositionMax;
}

bool Axis::index_words_legal() const {
  // SPM30 C1.3.4 (STP113): 0..+8,388,607; STP100 table 4.1: 1..16,777,215.
  const bool stp100 = config_.module == AxisConfig::Module::Stp100;
  const uint32_t low = stp100 ? 1 : 0, high = stp100 ? 16'777'215 : kPositionMax;
  for (uint32_t word :
       {words_.index_destination, words_.index_window_open, words_.index_window_close})
    if (word < low || word > high) return false;
  return true;
}

void Axis::move(uint16_t bit, Tick now) {
  if (words_.destination < kPositionMin || words_.destination > kPositionMax)
    return latch(status::kIllegalMove, now);
  // MOVE ABSOLUTE needs a valid position (SPM30 3.3.1).
  if (bit == command::kMoveAbsolute && !position_valid_) return latch(status::kIllegalMove, now);
  auto ramp = ramp_from_words(now);
  if (!ramp) return;
  if (bit == command::kMoveIndexed) {
    if (!index_words_legal()) return latch(status::kIllegalMove, now);
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
  start_move((move_target_steps_ - move_done_steps_) * job_direction_, move_ramp_, now,
             move_indexed_,
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
  if (!config_.indexed_moves)
    candidates &= static_cast<uint16_t>(~command::kMoveIndexed);  // future use
  if (core_.motors() < 2)
    candidates &= static_cast<uint16_t>(~(command::kSelectAxis2 | command::kSelectAxis3));
  if (core_.motors() < 3) candidates &= static_cast<uint16_t>(~command::kSelectAxis3);
  // While an error is latched only Clear Errors and the two stops are obeyed (SPM30 4: their
  // "Status Bits Required: None"; a lost master's ramp, or another front end's job, can
  // still be stopped); while moving (any front end's job) only the stops.
  if (errors_) candidates &= command::kClearErrors | command::kDecelStop | command::kImmediateStop;
  else if (moving()) candidates &= command::kDecelStop | command::kImmediateStop;
  // Several at once: the highest *legal* %Q is obeyed and the others ignored (SPM30 3.2). A
  // command whose "Status Bits Required" are not met is not legal (MOVE ABSOLUTE needs %I9,
  // RESUME MOVE %I10), so it outranks no legal one; with no legal one beside it, it is still
  // obeyed as an Illegal Move (STP100 Table 4.2, %I4: "Previous commanded move was not
  // possible").
  uint16_t not_legal = 0;
  if (!position_valid_) not_legal |= command::kMoveAbsolute;
  if (!resumable_) not_legal |= command::kResumeMove;
  if (candidates & ~not_legal) candidates &= static_cast<uint16_t>(~not_legal);
  if (candidates) {
    uint16_t bit = std::bit_floor(candidates);
    // Any command but Resume (and the Decelerate-and-Stop that pre-empts) ends resumability
    // (SPM30 4 RESUME MOVE (3)). Selecting the selected axis is no command obeyed: SELECT AXIS
    // "(1) If requested new axis is the same as the old axis or is illegal, do nothing" (an
    // illegal one never got here; %Q1..%Q3 are bits 0..2).
    const bool same_axis = bit == static_cast<uint16_t>(command::kSelectAxis1 << core_.selected());
    if (bit != command::kResumeMove && !(bit == command::kDecelStop && job_ == Job::Move) &&
        !same_axis)
      resumable_ = false;
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
}  // namespace stepnode::motion
