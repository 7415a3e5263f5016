#include "node/motion/step_generator.hpp"

#include <algorithm>
#include <cassert>

namespace stepnode::motion {

Tick StepGenerator::interval_length(Rational z, int64_t k) {
  // Bresenham over a fractional Z: the interval ends fall on floor(k * num / den); the
  // cursor walks them with additions (ramp_intervals.hpp). With Z < 1 some are 0 long: the
  // velocity rises by several levels at one tick, so every slope is honoured (issue 13;
  // before, each level took at least a tick: the slope was capped at one level per tick).
  return cursor_.length(z, k);
}

void StepGenerator::skip_empty_intervals(int64_t most) {
  // A run of 0-long intervals after this one: their levels all come at this tick, passed
  // at once (up to `most` levels, where the ramp ends or holds).
  if (interval_end_ != t_ || most <= 0) return;
  const int64_t m = std::min(cursor_.zeros_after(), most);
  cursor_.skip_zeros(m);
  interval_index_ += m;
  level_ += phase_ == MotionPhase::Accelerating ? m : -m;
}

void StepGenerator::start(const RampSpec& ramp, Tick start, int direction,
                          std::optional<int64_t> distance) {
  begin_change();
  if (ramp.s_curve) {
    direction_ = direction >= 0 ? +1 : -1;
    return s_start(ramp, start, distance);
  }
  if (scurve_) level_ = level();  // an S-curve's level is computed when read: kept here
  scurve_ = false;
  s_peak_slope_ = 0;  // the S-curve's peak goes with its marks
  ramp_ = ramp;
  direction_ = direction >= 0 ? +1 : -1;
  distance_ = distance;
  steps_done_ = 0;
  acc_ = 0;
  t_ = start;
  last_span_ = 0;
  stopping_ = false;
  marks_ = Marks{};
  marks_.start = start;
  decel_tick_ = -1;
  decel_check_after_ = -1;
  decel_floor_ = ramp.base_level;
  holding_ = false;
  then_.reset();
  if (distance && *distance <= 0) {
    phase_ = MotionPhase::Idle;
    marks_.end = start;
    return;
  }
  peak_level_ = distance ? ramp.peak_level_for(*distance) : ramp.run_level;
  marks_.peak_level = std::max(peak_level_, ramp.base_level);
  if (peak_level_ <= ramp.base_level) {
    phase_ = MotionPhase::Creeping;  // too short to ramp at all: the whole move at base
    level_ =
        std::max<int64_t>(ramp.base_level, ramp.min_creep_level);  // a 0 Hz base still has to move
    marks_.decel_start = marks_.decel_end = start;
    return;
  }
  // Acceleration intervals run at base+1 .. peak, Z_A ticks each (STPCALC B1.3.7/B1.3.11).
  phase_ = MotionPhase::Accelerating;
  level_ = ramp.base_level + 1;
  interval_index_ = 0;
  interval_end_ = t_ + interval_length(ramp.accel_ticks_per_level, 0);
  if (distance) decel_check_after_ = steps_before_decel_check(*distance);
}

int64_t StepGenerator::steps_before_decel_check(int64_t distance) const {
  // The ramp up never passes peak_level_, so the ramp down adds at most decel_phase(peak)
  // and the accumulator holds less than d: with k >= decel_phase(peak)/d + 2 steps left,
  // k·d > decel_phase(level) + acc and decel_needed() is false. In doubles with room to
  // spare (a 128-bit division here cost a short move more than its steps saved; asking the
  // exact test a step or two early changes nothing).
  const double span = static_cast<double>(peak_level_ - ramp_.base_level);
  const double levels = span * static_cast<double>(peak_level_ + ramp_.base_level + 1) / 2;
  const Rational z = ramp_.decel_ticks_per_level;
  const double k = levels * static_cast<double>(z.num) / static_cast<double>(z.den) /
                       static_cast<double>(ramp_.phase_per_step) * (1 + 1e-9) +
                   3;
  return k < static_cast<double>(distance) ? distance - static_cast<int64_t>(k) : -1;
}

std::optional<int64_t> StepGenerator::remaining() const {
  if (!distance_) return std::nullopt;
  return *distance_ - steps_done_;
}

bool StepGenerator::decel_needed() const {
  // Steps the deceleration ramp yields from here: the phase it adds plus what is already
  // accumulated, in whole steps. Far from the turn (every step but the last few of a ramp
  // up) an estimate in doubles decides; near it, the exact 128-bit phase.
  const double left = static_cast<double>(*remaining()) * static_cast<double>(ramp_.phase_per_step);
  const double span = static_cast<double>(level_ - ramp_.base_level);
  const double sum = span * static_cast<double>(level_ + ramp_.base_level + 1) / 2;
  const Rational z = ramp_.decel_ticks_per_level;
  const double estimate =
      sum * static_cast<double>(z.num) / static_cast<double>(z.den) + static_cast<double>(acc_);
  if (left > estimate * (1 + 1e-9) + 2) return false;
  __int128 phase = ramp_.decel_phase(level_) + acc_;
  return static_cast<__int128>(*remaining()) * ramp_.phase_per_step <= phase;
}

void StepGenerator::plan_decel() {
  // The deceleration starts on the exact tick where the phase still to come equals what
  // the ramp down adds, not on the next step, so running and total times match STPCALC
  // to a tick even at a few pulses per second.
  decel_tick_ = -1;
  if (!distance_ || stopping_) return;
  const int64_t d = ramp_.phase_per_step;
  __int128 target = static_cast<__int128>(*distance_) * d - ramp_.decel_phase(level_);
  __int128 current = static_cast<__int128>(steps_done_) * d + acc_;
  decel_tick_ =
      current >= target ? t_ : t_ + static_cast<Tick>((target - current + level_ - 1) / level_);
}

void StepGenerator::begin_decel() {
  marks_.decel_start = t_;
  if (phase_ == MotionPhase::Accelerating) marks_.peak_level = level_;
  if (level_ <= ramp_.base_level) {
    phase_ = stopping_ ? MotionPhase::Idle : MotionPhase::Creeping;
    marks_.decel_end = t_;
    if (phase_ == MotionPhase::Idle) marks_.end = t_;
    return;
  }
  // Deceleration intervals run at the current level down to base+1, Z_D ticks each.
  phase_ = MotionPhase::Decelerating;
  interval_index_ = 0;
  interval_end_ = t_ + interval_length(ramp_.decel_ticks_per_level, 0);
}

void StepGenerator::end_interval() {
  if (phase_ == MotionPhase::Accelerating) {
    if (level_ >= peak_level_) {
      phase_ = MotionPhase::Running;
      marks_.run_start = t_;
      plan_decel();
      reached_velocity();
      return;
    }
    ++level_;
    ++interval_index_;
    interval_end_ = t_ + interval_length(ramp_.accel_ticks_per_level, interval_index_);
    skip_empty_intervals(peak_level_ - level_);
    return;
  }
  // Decelerating: to a lower running velocity, or to base.
  if (holding_ && !stopping_ && level_ <= decel_floor_ + 1) {
    level_ = decel_floor_;
    phase_ = MotionPhase::Running;
    marks_.decel_end = t_;
    if (distance_) {
      holding_ = false;  // a move to a target ramps down to it from the lower velocity
      plan_decel();
    }
    reached_velocity();
    return;
  }
  if (level_ <= ramp_.base_level + 1) {
    level_ = ramp_.base_level;
    marks_.decel_end = t_;
    // A move with steps left finishes them at the base velocity (the phase accumulator may
    // leave one short of the target); a stop ends here.
    if (stopping_ || !distance_ || *remaining() <= 0) {
      phase_ = MotionPhase::Idle;
      marks_.end = t_;
    } else {
      phase_ = MotionPhase::Creeping;
      level_ = std::max<int64_t>(level_, ramp_.min_creep_level);
    }
    return;
  }
  --level_;
  ++interval_index_;
  interval_end_ = t_ + interval_length(ramp_.decel_ticks_per_level, interval_index_);
  const int64_t floor =
      std::max(ramp_.base_level, holding_ && !stopping_ ? decel_floor_ : int64_t{0}) + 1;
  skip_empty_intervals(level_ - floor);
}

[[gnu::always_inline]] inline Tick StepGenerator::peek_plain() {
  // In a ramp, most steps fall in an interval reached by plain level changes (one up or
  // down, the phase unchanged): the step next() takes, found without copying the
  // generator. Anything else first (the ramp's end, its top): kUnpeeked. The steps from
  // here solved in a batch where peek_batch() can (every ramp of the profiles and the
  // Horner module on their usual grids); else the one step: in this interval here,
  // inlined; one further on peek_beyond()'s or peek_solved()'s.
  ahead_.valid = false;
  const int64_t left = ramp_.phase_per_step - acc_;  // the phase still to come
  // This interval's phase: far inside int64 where no step falls, below one step's phase.
  const int64_t phase = level_ * (interval_end_ - t_);
  if (!walked_) {
    const Tick batched = peek_batch(left, phase);
    if (batched != kUnpeeked) return batched;
  }
  if (phase >= left) return t_ + (left + level_ - 1) / level_;
  return last_span_ >= kSolveFrom ? peek_solved(left, phase) : peek_beyond(left, phase);
}

// Inlined in both callers: a call more per step costs ~15 % in a run (6.5 ns a step).
[[gnu::always_inline]] inline bool StepGenerator::took_step(Step& out) {
  // The step at t_ is taken: counted, and what follows it decided.
  ++steps_done_;
  ++phase_steps(marks_);
  out = Step{t_, direction_};
  if (distance_ && steps_done_ >= *distance_) {
    phase_ = MotionPhase::Idle;
    marks_.end = t_;
    if (marks_.decel_end < 0) marks_.decel_end = t_;
  } else if (phase_ == MotionPhase::Accelerating && steps_done_ > decel_check_after_ && distance_ &&
             !stopping_ && decel_needed()) {
    // A move too short for the running velocity turns where the ramps meet.
    begin_decel();
  } else if (phase_ == MotionPhase::Running || phase_ == MotionPhase::Creeping) {
    // The step after this one, here, where the state is at hand: the axes peek after
    // every step, and at a constant level that answer is all a peek would compute.
    peeked_ = peek_run();
  } else {
    peeked_ = peek_plain();  // in a ramp: the same, through its plain level changes
  }
  return true;
}

// take_known(), next_unknown() and (step_generator_ramp_peek.cpp) peek_beyond() and
// peek_solved() on 64-byte boundaries: their loops run at
// a very high rate of instructions per cycle, and where a merge elsewhere in the file moved
// them, the same code took 5-9 % more user time (Horner's ramps in ramp_cost_bench; README
// "Figures").
[[gnu::aligned(64)]] bool StepGenerator::take_known(Step& out) {
  // The step peek_plain() or run_step_after() found alone (not in a batch), in this
  // interval (or ahead_'s) and before any turn: taken without the loop's tests and
  // division. (An S-curve's, which s_next() peeked: s_take_known().)
  if (ahead_.valid) ahead_.restore(*this);
  const Tick at = peeked_;
  acc_ += level_ * (at - t_) - ramp_.phase_per_step;
  t_ = at;
  peeked_ = kUnpeeked;  // the next step may move
  return took_step(out);
}

[[gnu::aligned(64)]] bool StepGenerator::next_unknown(Step& out) {
  ramp_known_.valid = false;  // the motion may change on the way
  sync_batch();
  if (scurve_) {
    peeked_ = kUnpeeked;  // the next step may move
    return s_next(out);
  }
  // A peek() that walked plain ramp intervals left where it got to: start from there.
  if (ahead_.valid && peeked_ != kUnpeeked) ahead_.restore(*this);
  peeked_ = kUnpeeked;  // the next step may move
  for (;;) {
    if (phase_ == MotionPhase::Idle) return false;
    // Read each turn: reaching a velocity may move the motion to another grid (adopt).
    const int64_t d = ramp_.phase_per_step;
    // The invariants every front end's input must keep (checked in the sanitizer build): a
    // moving level (the next step's time divides by it) and a phase inside one step.
    assert(level_ >= 1 && acc_ >= 0 && acc_ < d);
    bool ramping = phase_ == MotionPhase::Accelerating || phase_ == MotionPhase::Decelerating;
    // A ramp interval whose whole phase stays below d has no step (the same test as the
    // ticks the step needs against the interval's end, without the division; level times
    // an interval's length is of the order of the ramp's ticks, far inside int64).
    if (ramping && level_ * (interval_end_ - t_) < d - acc_) {
      // At the step's interval or the ramp's last plain one, solved (levels at one tick,
      // or many before the step: the end of a ramp down on a fine grid, where peek() finds
      // the step beyond its room and a copy of the generator comes here).
      if (!walked_ && solve_ramp()) continue;
      acc_ += level_ * (interval_end_ - t_);
      t_ = interval_end_;
      end_interval();
      continue;
    }
    Tick need = (d - acc_ + level_ - 1) / level_;  // ticks until the accumulator passes d
    if (phase_ == MotionPhase::Running && decel_tick_ >= 0 && t_ + need > decel_tick_) {
      acc_ += level_ * (decel_tick_ - t_);
      t_ = decel_tick_;
      begin_decel();
      continue;
    }
    t_ += need;
    acc_ += level_ * need - d;
    return took_step(out);
  }
}

std::optional<Tick> StepGenerator::peek_unknown() {
  ramp_known_.valid = false;  // a change may have come since the last step
  sync_batch();
  // Cached until the motion changes: the axes peek on every tick, and reaching the next
  // step may walk thousands of ramp intervals (a slow ramp from 0 Hz, HP PROFILE FREQ).
  if (scurve_) return phase_ == MotionPhase::Idle ? std::nullopt : s_.p->peek();
  if (peeked_ == kUnpeeked && phase_ != MotionPhase::Idle) {
    if (phase_ == MotionPhase::Accelerating || phase_ == MotionPhase::Decelerating) {
      peeked_ = peek_plain();
    } else {
      peeked_ = peek_run();
    }
  }
  if (peeked_ == kUnpeeked) {
    // Found by a copy: not in this interval, so kept apart from peeked_ (next()'s known step).
    StepGenerator copy = *this;
    Step s;
    copied_ = copy.next(s) ? s.time : kNoStep;
    peeked_ = kCopied;
  }
  const Tick at = peeked_ == kCopied ? copied_ : peeked_;
  return at == kNoStep ? std::nullopt : std::optional<Tick>(at);
}

Tick StepGenerator::peek_run() {
  // At a constant level (a run, a creep), the next steps in a batch, up to the
  // deceleration point or the batch's room (not with walk_ramps(): the reference).
  ahead_.valid = false;
  // The first batch at the top of a ramp short: a motion is often changed as it reaches
  // its velocity (a stop at the top, the next set-point), and would leave the rest untaken.
  int64_t most = walked_ ? 0 : batch_room();
  if (phase_ == MotionPhase::Running && marks_.run_steps <= 1) most = std::min<int64_t>(most, 4);
  if (most <= 0) return run_step_after();
  const int64_t d = ramp_.phase_per_step, level = level_;
  const Tick until = phase_ == MotionPhase::Running && decel_tick_ >= 0 ? decel_tick_ : kNever;
  Tick s = t_;
  int64_t acc = acc_;
  int n = 0;
  // After the first step the accumulator stays below the level (a step falls on the first
  // tick that passes d), so each step is d / level ticks after the one before, or one more
  // where the accumulator is below d % level: a Bresenham line, no division on the chain
  // from step to step.
  Tick need = (d - acc + level - 1) / level;
  const int64_t qs = d / level, rs = d % level;
  for (; n < most && s + need <= until; ++n) {
    s += need;
    acc += level * need - d;
    batch_.step[n] = s, batch_.acc[n] = acc, batch_.level[n] = level;
    need = qs + (acc < rs ? 1 : 0);
  }
  if (n == 0) return kUnpeeked;  // the deceleration point first: next_unknown() turns there
  batch_.step[n] = kUnpeeked;
  batch_.count = n;
  batch_.level0 = level;
  batch_.kept = StepBatch::Kept::Solved;
  return batch_.step[0];
}

Tick StepGenerator::run_step_after() const {
  // In a run or a creep: the step next() takes, unless the deceleration point comes first.
  const int64_t d = ramp_.phase_per_step;
  const Tick at = t_ + (d - acc_ + level_ - 1) / level_;
  return phase_ == MotionPhase::Running && decel_tick_ >= 0 && at > decel_tick_ ? kUnpeeked : at;
}

bool StepGenerator::solve_ramp(Tick until) {
  // The walk to the step or the ramp's last plain level (for advance_to(), to the tick
  // `until` if that comes first), solved (ramp_step.hpp), not one loop turn per interval:
  // at Z < 1 (a CiA 402 acceleration above 4.9 M steps/s^2), or with kWalked levels or more
  // to go (a fine grid near rest: thousands of levels in a step; fewer are faster walked).
  const bool up = phase_ == MotionPhase::Accelerating;
  const Rational z = up ? ramp_.accel_ticks_per_level : ramp_.decel_ticks_per_level;
  if (!cursor_.at(z, interval_index_)) return false;  // Z changed mid-ramp (a quick stop)
  const int64_t room = plain_levels();
  const bool steep = cursor_.steep();
  if (room <= 0 || (!steep && room < kWalked)) return false;
  const int64_t d = ramp_.phase_per_step;
  RampWalk w{t_, interval_end_, level_, d - acc_, 0, cursor_.remainder()};
  if (until == kNever) walk_to_step(w, cursor_.grid(), up ? 1 : -1, room);
  else walk_until(w, cursor_.grid(), up ? 1 : -1, room, until);
  t_ = w.t, acc_ = d - w.left, level_ = w.level;
  interval_index_ += w.passed, interval_end_ = w.end;
  cursor_.advance(w.passed, w.rem);
  return true;
}

void StepGenerator::batch_state() {
  if (scurve_) return s_batch_state();
  // The time, accumulator and level are the last step's. In a ramp the interval and the
  // cursor stood where the batch began (at the level before its first step's): each of
  // its intervals moves the level by one, so the p levels passed since are p intervals
  // on, of which floor((rem + p·rho)/den) carried (ramp_intervals.hpp). At a constant
  // level (a run, a creep) p is 0.
  level_ = batch_.level[batch_.pos - 1];
  if (batch_.kept == StepBatch::Kept::Bounded) {
    bounded_batch_state();
  } else {
    acc_ = batch_.acc[batch_.pos - 1];
  }
  const int64_t start = batch_.level0;
  const int64_t p = phase_ == MotionPhase::Accelerating ? level_ - start : start - level_;
  if (p > 0) {
    const IntervalGrid g = cursor_.grid();
    int64_t reached = 0, carries = 0, rem = 0;
    if (!__builtin_mul_overflow(p, g.rho, &reached) &&
        !__builtin_add_overflow(reached, cursor_.remainder(), &reached)) {
      carries = reached / g.den, rem = reached % g.den;
    } else {  // in 128 bits: a den near 2^63
      const __int128 wide = cursor_.remainder() + static_cast<__int128>(p) * g.rho;
      carries = static_cast<int64_t>(wide / g.den), rem = static_cast<int64_t>(wide % g.den);
    }
    interval_index_ += p, interval_end_ += g.q * p + carries;
    cursor_.advance(p, rem);
  }
  count_batch_steps(marks_);
}

void StepGenerator::Ahead::restore(StepGenerator& g) const {
  g.t_ = t, g.acc_ = acc, g.level_ = level;
  g.interval_index_ += passed, g.interval_end_ = end;
  g.cursor_.advance(passed, rem);
}

void StepGenerator::advance_to(Tick at) {
  // Moves time forward to `at` without taking a step (the caller has taken every step
  // due before `at`); ramp intervals that end on the way are processed.
  while (phase_ != MotionPhase::Idle && t_ < at) {
    const int64_t d = ramp_.phase_per_step;  // each turn: see next()
    Tick need = (d - acc_ + level_ - 1) / level_;
    Tick limit = std::min(at, t_ + need - 1);
    bool ramping = phase_ == MotionPhase::Accelerating || phase_ == MotionPhase::Decelerating;
    if (ramping && interval_end_ <= limit) {
      // The intervals up to `at` (or the step, or the ramp's last plain level) solved as
      // next() solves them (levels at one tick, or many), not passed one at a time.
      if (!walked_ && solve_ramp(at)) continue;
      acc_ += level_ * (interval_end_ - t_);
      t_ = interval_end_;
      end_interval();
      continue;
    }
    if (phase_ == MotionPhase::Running && decel_tick_ >= 0 && decel_tick_ <= limit) {
      // The ramp down to the target began on its tick, as next() begins it: a change that
      // comes after it (and before the next step) finds the motion ramping down.
      acc_ += level_ * (decel_tick_ - t_);
      t_ = decel_tick_;
      begin_decel();
      continue;
    }
    acc_ += level_ * (limit - t_);
    t_ = limit;
    break;
  }
}

void StepGenerator::stop(Tick at) {
  begin_change();
  if (phase_ == MotionPhase::Idle) return;
  if (scurve_) {
    stopping_ = true;
    s_.p->stop(at);
    return s_follow();
  }
  advance_to(at);
  stopping_ = true;
  then_.reset();
  if (phase_ == MotionPhase::Creeping) {
    phase_ = MotionPhase::Idle;  // already at base velocity: stop now
    marks_.end = t_;
  } else if (phase_ != MotionPhase::Decelerating) {
    begin_decel();
  }
}

void StepGenerator::stop(Tick at, Rational decel) {
  begin_change();
  if (phase_ == MotionPhase::Idle) return;
  if (scurve_) {
    stopping_ = true;
    distance_.reset();
    s_.p->stop(at, slope_of(decel));
    return s_follow();
  }
  advance_to(at);
  ramp_.decel_ticks_per_level = decel;
  if (phase_ == MotionPhase::Decelerating) {
    // Already ramping down (to a target or a lower velocity): the rest at the new rate.
    distance_.reset();
    holding_ = false;
    decel_floor_ = ramp_.base_level;
  }
  stop(at);
}

void StepGenerator::halt(Tick at) {
  begin_change();
  if (phase_ == MotionPhase::Idle) return;
  t_ = std::max(t_, at);
  phase_ = MotionPhase::Idle;
  marks_.end = t_;
}

}  // namespace stepnode::motion
