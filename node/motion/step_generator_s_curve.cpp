// The step generator running a jerk-limited profile (RampSpec::s_curve, CiA 402 6086h = 3):
// the motion is node/motion/s_curve's; the generator keeps the state its users read
// (phase, level, steps, marks) in step with it.
#include <algorithm>
#include <cmath>

#include "node/motion/step_generator.hpp"

namespace stepnode::motion {
namespace {

// max(0, llround(x)) without the library call (once per step): half away from zero, the
// fraction of a double below 2^52 is exact.
int64_t level_of(double x) {
  if (!(x > 0)) return 0;
  if (x >= 0x1p52) return std::llround(x);
  const auto whole = static_cast<int64_t>(x);
  return whole + (x - static_cast<double>(whole) >= 0.5 ? 1 : 0);
}

}  // namespace

double StepGenerator::slope_of(Rational z) const {
  // Ticks per level on this grid -> steps/s^2: kClockHz^2 / (z * phase_per_step).
  const double hz = static_cast<double>(kClockHz);
  return hz * hz * static_cast<double>(z.den) /
         (static_cast<double>(z.num) * static_cast<double>(ramp_.phase_per_step));
}

JerkLimits StepGenerator::jerk_limits(const RampSpec& r) const {
  JerkLimits l;
  l.velocity = r.velocity_of(r.run_level);
  l.acceleration = slope_of(r.accel_ticks_per_level);
  l.deceleration = slope_of(r.decel_ticks_per_level);
  l.begin_accel_jerk = r.jerk[0];
  l.begin_decel_jerk = r.jerk[1];
  l.end_accel_jerk = r.jerk[2];
  l.end_decel_jerk = r.jerk[3];
  return l;
}

void StepGenerator::s_start(const RampSpec& ramp, Tick start, std::optional<int64_t> distance) {
  ramp_ = ramp;
  scurve_ = true;
  distance_ = distance;
  steps_done_ = 0;
  acc_ = 0;
  t_ = start;
  stopping_ = holding_ = false;
  then_.reset();
  marks_ = Marks{};
  marks_.start = start;
  level_ = 0;
  s_level_lazy_ = s_at_target_ = false;
  s_peak_slope_ = 0;
  if (!s_.p) s_.p = std::make_unique<SCurve>();
  if (distance && *distance <= 0) {
    phase_ = MotionPhase::Idle;
    marks_.end = start;
    return;
  }
  s_.p->start(jerk_limits(ramp), start, distance);
  phase_ = MotionPhase::Accelerating;
}

void StepGenerator::s_follow() {
  // The phase the motion shows after a change or a step in another segment (a step by the
  // quick search stays in its segment: the same phase). The level is s_level()'s.
  const SCurve& s = *s_.p;
  using K = SCurve::Kind;
  switch (s.kind()) {
    case K::Accelerating: phase_ = MotionPhase::Accelerating; break;
    case K::Decelerating: phase_ = MotionPhase::Decelerating; break;
    case K::Creep: phase_ = MotionPhase::Creeping; break;
    default: phase_ = MotionPhase::Running; break;
  }
  s_level_lazy_ = true;
  s_at_target_ = s.at_target_velocity();
  if (s_at_target_) {
    marks_.peak_level = std::max(marks_.peak_level, s_level());
  } else {
    s_track_peak();
  }
}

void StepGenerator::s_fold_peak() {
  marks_.peak_level = marks().peak_level;
  s_peak_slope_ = 0;
}

int64_t StepGenerator::s_level() const {
  // Holding a velocity: exactly its level (the phases on whole ticks leave it within a few
  // millionths); otherwise the velocity at the last step. The S-curve's state is the one
  // the last step or change left (peek() does not move it).
  const SCurve& s = *s_.p;
  if (s.at_target_velocity()) return s_level_at(s.target_velocity());
  if (batch_.pos > 0) return s_level_at(SCurve::velocity_of(s.slope_at(t_)));  // batch's
  return s_level_at(s.velocity());
}

int64_t StepGenerator::s_level_at(double velocity) const {
  const double lph = static_cast<double>(ramp_.phase_per_step) / static_cast<double>(kClockHz);
  return level_of(velocity * lph);
}

bool StepGenerator::s_take_known(Step& out) {
  if (s_.p->next_is_steady()) return s_take_steady(out);
  peeked_ = kUnpeeked;  // the next step may move
  return s_next(out);
}

bool StepGenerator::s_take_steady(Step& out) {
  // A cruise's step at the velocity of the step before: phase, level and peak stay.
  SCurve& s = *s_.p;
  t_ = s.take_even();
  ++steps_done_;
  out = Step{t_, direction_};
  if (s.ended()) [[unlikely]] {
    s_end_at_last_step();
  } else {
    peeked_ = s.peek().value_or(kNoStep);  // take_even() peeked it (or the search does)
  }
  return true;
}

void StepGenerator::s_end_at_last_step() {
  s_follow();
  level_ = s_level();  // kept while idle (a start without steps leaves it)
  s_level_lazy_ = false;
  phase_ = MotionPhase::Idle;
  marks_.end = t_;
  peeked_ = kUnpeeked;
}

bool StepGenerator::s_next(Step& out) {
  if (phase_ == MotionPhase::Idle) return false;
  SCurve& s = *s_.p;
  const std::optional<Tick> t = s.next_step();
  if (!t) {
    phase_ = MotionPhase::Idle;
    t_ = std::max(t_, s.end());
    marks_.end = t_;
    level_ = 0;
    s_level_lazy_ = false;
    return false;
  }
  t_ = *t;
  ++steps_done_;
  out = Step{t_, direction_};
  if (s.ended()) {
    s_end_at_last_step();
  } else if (!s.last_step_quick()) {
    s_follow();
  } else if (!s_at_target_) {
    s_track_peak();
  }
  if (phase_ != MotionPhase::Idle) s_peek_after_step();
  return true;
}

void StepGenerator::s_peek_after_step() {
  // The steps after this one, here (the axes peek after every step): a batch of those in
  // its segment (next() takes them inline, sync_batch() moves the S-curve on to the last
  // taken), or the next one alone, which next() takes through s_take_known().
  SCurve& s = *s_.p;
  const int n = walked_ ? 0 : s.batch(batch_.step, StepBatch::kSize);
  if (n > 0) {
    batch_.step[n] = kUnpeeked;
    batch_.count = n;
    batch_.pos = 0;
    batch_.kept = StepBatch::Kept::Times;
    peeked_ = batch_.step[0];
    return;
  }
  peeked_ = s.peek().value_or(kNoStep);
}

void StepGenerator::s_batch_state() {
  // The S-curve moved on to the batch's last step taken; the peak of those steps kept.
  s_peak_slope_ = s_peak_slope();
  s_.p->take_batch(batch_.step, batch_.pos);
}

void StepGenerator::leave_s_curve(Tick at) {
  // A cyclic mode takes over a jerk-limited motion: the trapezoid's state at its velocity,
  // the phase accumulator empty (at most a fraction of a step late).
  if (!scurve_) return;
  s_fold_peak();  // the trapezoid's grid from here on may differ
  level_ = std::max<int64_t>(level(), 1);
  s_level_lazy_ = false;
  scurve_ = false;
  t_ = std::max(t_, at);
  acc_ = 0;
  phase_ = MotionPhase::Running;
  holding_ = stopping_ = false;
  decel_tick_ = -1;
  distance_.reset();
}

double StepGenerator::steps_to_stop() const {
  if (phase_ == MotionPhase::Idle) return 0;
  if (scurve_) return s_.p->steps_to_stop(t_);
  const auto levels =  // the ramp down's whole steps, far inside int64
      static_cast<int64_t>(ramp_.decel_phase(trapezoid_level()) / ramp_.phase_per_step);
  return static_cast<double>(levels);
}

}  // namespace stepnode::motion
