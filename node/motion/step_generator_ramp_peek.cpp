// The step after a ramp step, beyond the interval it falls in (StepGenerator::peek_plain()
// finds one inside it): walked a few levels on, solved further (ramp_step.hpp). Apart from
// step_generator.cpp, whose loop and changes these do not touch.
#include <algorithm>

#include "node/motion/ramp_carry_walk.hpp"
#include "node/motion/ramp_step.hpp"
#include "node/motion/step_generator.hpp"

namespace stepnode::motion {

[[gnu::always_inline]] inline bool StepGenerator::know_ramp() {
  // The ramp's direction, last plain level and steepness, and that the cursor follows its
  // Z (not a quick stop's mid-ramp change): once for the steps taken one after another.
  if (ramp_known_.valid) return true;
  const bool up = phase_ == MotionPhase::Accelerating;
  const Rational z = up ? ramp_.accel_ticks_per_level : ramp_.decel_ticks_per_level;
  if (!cursor_.at(z, interval_index_)) return false;
  const int64_t dir = up ? 1 : -1;
  ramp_known_ = KnownRamp{true, cursor_.steep(), dir, level_ + dir * plain_levels()};
  return true;
}

[[gnu::always_inline]] inline Tick StepGenerator::step_found(const RampWalk& w) {
  // The walk's state for next() to go on from (ahead_), its span the next step's guess.
  last_span_ = w.passed;
  ahead_ = Ahead{true, w.t, ramp_.phase_per_step - w.left, w.level, w.passed, w.end, w.rem};
  return w.t + (w.left + w.level - 1) / w.level;
}

// On a 64-byte boundary: see StepGenerator::next_unknown() (step_generator.cpp).
[[gnu::aligned(64)]] Tick StepGenerator::peek_beyond(int64_t left, int64_t phase) {
  // The rest of peek_plain(): the step lies beyond this interval (`phase` < `left`).
  if (!know_ramp()) return kUnpeeked;
  const int64_t dir = ramp_known_.dir;
  const int64_t plain = dir * (ramp_known_.last - level_);
  if (plain <= 0) return kUnpeeked;
  int64_t level = level_;
  Tick len = interval_end_ - t_, end = interval_end_;
  // A step beyond the next kWalked intervals (a slow start, a fine grid; they add at most
  // (q + 1)·kWalked·(L + kWalked)), or several levels at one tick (Z < 1): solved at once
  // (ramp_step.hpp), not walked.
  const IntervalGrid g = cursor_.grid();
  const double most = static_cast<double>(g.q + 1) * static_cast<double>(kWalked) *
                      static_cast<double>(level + kWalked);
  if (ramp_known_.steep || most < static_cast<double>(left - phase)) return peek_far(dir, plain);
  // The walk with the cursor's additions (ramp_intervals.hpp) in registers: the interval
  // lengths are q or q + 1 (q >= 1 here), the phase of each its level times its length.
  int64_t rem = cursor_.remainder();
  const auto pass = [&] {
    left -= phase;
    level += dir;
    len = g.next_length(rem);
    end += len;
    phase = level * len;
  };
  // Every interval is at least q long: where the next n levels (the room's, at most
  // 2·kWalked) add at least the phase to come, the walk ends within the room, unchecked
  // (the products stay below 4·most, far inside int64).
  const int64_t n = std::min(plain, 2 * kWalked);
  if (g.q * (n * level + dir * (n * (n + 1) / 2)) >= left - phase) {
    do pass();
    while (phase < left);
  } else {
    const int64_t last = level + dir * plain;  // the ramp's last plain level
    do {
      if (level == last) return kUnpeeked;
      pass();
    } while (phase < left);
  }
  // next() goes on from there.
  return step_found(RampWalk{end - len, end, level, left, (level - level_) * dir, rem});
}

// On a 64-byte boundary: see StepGenerator::next_unknown() (step_generator.cpp).
[[gnu::aligned(64)]] Tick StepGenerator::peek_solved(int64_t left, int64_t phase) {
  // peek_beyond() for a step several levels on: the interval that holds it, solved inline
  // (ramp_step.hpp solve_to_step; anything else is peek_far()'s), with the steps after it.
  if (!know_ramp()) return kUnpeeked;
  const int64_t dir = ramp_known_.dir;
  const int64_t plain = dir * (ramp_known_.last - level_);
  if (plain <= 0) return kUnpeeked;
  const IntervalGrid g = cursor_.grid();
  if (ramp_known_.steep) return peek_far(dir, plain);  // levels at one tick (Z < 1)
  const int64_t after = left - phase;
  if (!solves_in_64(after, level_, g)) return peek_far(dir, plain);  // walk_to_step's
  RampWalk w{t_, interval_end_, level_, 0, 0, cursor_.remainder()};
  if (!solve_to_step(w, g, cursor_.z(), dir, plain, after, last_span_)) return kUnpeeked;
  return step_found(w);
}

Tick StepGenerator::peek_batch(int64_t left, int64_t phase) {
  // The next steps of a ramp in a batch, where its conditions hold: the cursor on the
  // ramp's Z, not steep, and every level the batch passes (between this one and the last
  // plain one) keeping the solve in 64 bits with a phase to come below a step's. Else
  // kUnpeeked: the step is found alone.
  if (!know_ramp() || ramp_known_.steep) return kUnpeeked;
  const int64_t last = ramp_known_.last;
  const IntervalGrid g = cursor_.grid();
  if (!solves_in_64(ramp_.phase_per_step, std::max(level_, last), g)) return kUnpeeked;
  const int64_t most = batch_room();
  if (most <= 0) return kUnpeeked;
  // Without its carries on a grid that carries at least every kBoundedCarries intervals
  // (CiA 402's usual grids: two or three in each step's span). Fewer (HP's usual grid, a
  // carry every 24 intervals; a whole Z, Horner's, none): solve_batch's walk, whose
  // additions take less time than the bounded step's square root and division.
  if (g.rho > 0 && g.den <= kBoundedCarries * g.rho) {
    const Tick bounded =
        ramp_known_.dir > 0 ? bounded_batch<1>(last, most) : bounded_batch<-1>(last, most);
    if (bounded != kUnpeeked) return bounded;
  }
  return ramp_known_.dir > 0 ? solve_batch<1>(left, phase, last, most)
                             : solve_batch<-1>(left, phase, last, most);
}

int64_t StepGenerator::batch_room() const {
  // A batch's steps are taken without took_step()'s tests (take_batched): neither the
  // move's last step nor a ramp up's steps that ask decel_needed() may be in it.
  int64_t most = StepBatch::kSize;
  if (distance_) most = std::min(most, *distance_ - steps_done_ - 1);
  if (phase_ == MotionPhase::Accelerating && distance_ && !stopping_)
    most = std::min(most, decel_check_after_ - steps_done_);
  return most;
}

template <int Dir>
Tick StepGenerator::solve_batch(int64_t left, int64_t phase, int64_t last, int64_t most) {
  // The steps from here on, each in its interval or found beyond it, until `most` are in
  // (batch_room) or the ramp's last plain level comes before a step.
  // Beyond: walked from the span of the step before with the next carry passed on
  // (ramp_carry_walk.hpp), where that span holds a few carries at most; else solved
  // (solve_to_step, the span as its guess).
  const int64_t d = ramp_.phase_per_step;
  const IntervalGrid g = cursor_.grid();
  const CarryGrid cg(g);
  // A few carries in the span at most (4·den/rho levels; a large den is left unmultiplied).
  const int64_t walked_most = g.rho > 0 && g.den / g.rho < kHintedMost
                                  ? std::min(kHintedMost, 4 * g.den / g.rho)
                                  : kHintedMost;
  int n = 0;
  Tick s = t_, end = interval_end_;
  int64_t level = level_, acc = acc_, span = last_span_;
  NextCarry carry = NextCarry::after(g, cursor_.remainder());
  for (; n < most; ++n) {
    if (phase >= left) {  // in this interval
      const Tick at = s + (left + level - 1) / level;
      acc += level * (at - s) - d;
      s = at;
    } else {
      RampWalk w{s, end, level, 0, 0, 0};
      const int64_t room = Dir * (last - level);
      if (room <= 0) break;  // the ramp's top or end first: next_unknown() turns there
      const int64_t guess = std::max<int64_t>(span, 1);
      if (span > walked_most || !walk_from_guess<Dir>(w, carry, cg, room, left - phase, guess))
          [[unlikely]] {
        w.rem = remainder_before(carry, g);
        if (!solve_to_step(w, g, cursor_.z(), Dir, room, left - phase, span)) break;
        carry = NextCarry::after(g, w.rem);
      }
      span = w.passed, level = w.level, end = w.end;
      s = w.t + (w.left + level - 1) / level;
      acc = level * (s - w.t) - w.left;
    }
    batch_.step[n] = s, batch_.acc[n] = acc, batch_.level[n] = level;
    left = d - acc;
    phase = level * (end - s);
  }
  if (n == 0) return kUnpeeked;
  last_span_ = span;
  batch_.step[n] = kUnpeeked;
  batch_.count = n;
  batch_.level0 = level_;
  batch_.kept = StepBatch::Kept::Solved;
  return batch_.step[0];
}

Tick StepGenerator::peek_far(int64_t dir, int64_t plain) {
  // peek_plain() for a step many levels on: the interval that holds it, solved.
  RampWalk w{t_, interval_end_, level_, ramp_.phase_per_step - acc_, 0, cursor_.remainder()};
  if (!walk_to_step(w, cursor_.grid(), dir, plain)) return kUnpeeked;
  return step_found(w);
}

}  // namespace stepnode::motion
