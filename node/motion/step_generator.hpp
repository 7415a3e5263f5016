// The pulse engine's core: turns a ramp and a distance into the exact tick of every step.
// Integer arithmetic only: a phase accumulator adds the velocity level every tick and a
// step falls when it passes phase_per_step. Steps are computed in closed form per
// constant-velocity interval, so the cost is O(1) per step at any rate.
#pragma once
#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <optional>

#include "node/motion/ramp.hpp"
#include "node/motion/ramp_intervals.hpp"
#include "node/motion/ramp_spread.hpp"
#include "node/motion/s_curve.hpp"
#include "node/motion/timebase.hpp"

namespace stepnode::motion {

enum class MotionPhase { Idle, Accelerating, Running, Decelerating, Creeping };

struct Step {
  Tick time = 0;
  int direction = +1;  // +1 up, -1 down
};

class StepGenerator {
 public:
  // Starts a move at `start` in `direction` (+1/-1). With a distance (> 0) the move ends
  // exactly there; without one it runs until stop() (jog, find home).
  void start(const RampSpec& ramp, Tick start, int direction, std::optional<int64_t> distance);
  // Computes the next step. Returns false when the move has ended (Idle).
  bool next(Step& out) {
    if (peeked_ < 0) return next_unknown(out);
    if (batch_.pos < batch_.count) return take_batched(out);
    return scurve_ ? s_take_known(out) : take_known(out);
  }
  // From now on every ramp interval walked one loop turn at a time, none solved (levels at
  // one tick, or many levels before a step), in next() and in the changes of a running
  // motion (the reference in the tests; peek() still solves what it finds, one step at a
  // time: no batch of them, nor of an S-curve's steps).
  void walk_ramps(bool on) { walked_ = on; }
  // The time the next step would fall, without taking it (nullopt when idle).
  std::optional<Tick> peek() {
    if (peeked_ >= 0) return peeked_;  // known (next() finds the one after each step)
    return peek_unknown();
  }

  // Decelerate to the base velocity from time `at` and end there (SPM30 %Q15); with
  // `decel`, at that deceleration (ticks per level) instead of the ramp's (CiA 402 quick stop).
  void stop(Tick at);
  void stop(Tick at, Rational decel);
  // End at once, no ramp (immediate stop, limits, e-stop).
  void halt(Tick at);
  // From time `at`, ramp to a new velocity level and hold it (continuous motion without a
  // destination: HP SUSTAIN, velocity modes). Up with the acceleration, down with the
  // deceleration of the ramp; never below the base level.
  // With `then`, the motion moves to that ramp's grid at its run level once `level` is
  // reached (regrid): a rate the current grid cannot hold to 0.01 % is approached on the
  // current grid, then held exactly on one made for it.
  // A move to a target keeps it: the new velocity is held until the ramp down to the
  // target; a move already in that ramp keeps it unless the velocity is higher (CiA 402
  // change on set-point: the next set-point's velocity from the first target on); `then`
  // is for motions without a destination only.
  void change_velocity(Tick at, int64_t level, std::optional<RampSpec> then = std::nullopt);
  // From time `at`, carries a motion without a destination over to `ramp`'s level grid:
  // the velocity to the nearest level of the new grid (at least 1), the phase accumulator
  // keeps its fraction of a step, the motion runs on at that level. For velocity changes
  // the current grid cannot express: an HP SUSTAIN from a few µHz (levels of µHz) up to
  // kHz would take one level per tick, hundreds of millions of them.
  void regrid(Tick at, const RampSpec& ramp);
  // From time `at`, run at `level` (>= 1) on the same grid at once, no ramp, the phase
  // accumulator keeping its fraction of a step (CiA 402 cyclic velocity: a new velocity
  // every SYNC, no step gained or lost at the change).
  void set_level(Tick at, int64_t level);
  // From time `at`, end the move `steps` steps from here and decelerate with `ramp`'s
  // deceleration (indexed move: the index input moved the end point). The velocity and
  // phase carry on; if the new end is too close to ramp down, the ramp starts at once.
  void retarget(Tick at, int64_t steps, const RampSpec& ramp);

  // Steps from here to standstill with the deceleration ramp (a change of target closer
  // than this overshoots).
  double steps_to_stop() const;

  MotionPhase phase() const { return phase_; }
  bool moving() const { return phase_ != MotionPhase::Idle; }
  bool stopping() const { return moving() && stopping_; }  // stop(): ramping down to end
  // An S-curve's level is computed when read (s_level()), not at every step.
  int64_t level() const { return scurve_ && s_level_lazy_ ? s_level() : trapezoid_level(); }
  double velocity() const { return phase_ == MotionPhase::Idle ? 0.0 : ramp_.velocity_of(level()); }
  int64_t steps_done() const { return steps_done_; }
  std::optional<int64_t> remaining() const;
  int direction() const { return direction_; }
  const RampSpec& ramp() const { return ramp_; }
  Tick time() const { return t_; }

  // Ticks at which the phases changed during the last move (for STPCALC comparisons).
  struct Marks {
    Tick start = 0, run_start = -1, decel_start = -1, decel_end = -1, end = -1;
    int64_t accel_steps = 0, run_steps = 0, decel_steps = 0, creep_steps = 0;
    int64_t peak_level = 0;
  };
  // An S-curve's peak is folded in when read: its steps keep only the highest slope.
  Marks marks() const {
    Marks m = marks_;
    if (scurve_) {
      const __int128 peak = s_peak_slope();
      if (peak > 0) m.peak_level = std::max(m.peak_level, s_level_at(SCurve::velocity_of(peak)));
    } else if (batch_.count > 0) {
      count_batch_steps(m);
    }
    return m;
  }

 private:
  // The level of a trapezoid's last step: a batch's steps leave level_ behind (sync_batch).
  int64_t trapezoid_level() const { return batch_.pos > 0 ? batch_.level[batch_.pos - 1] : level_; }
  // A batch's step: its time and count alone (its accumulator and level follow in
  // sync_batch, on the way in of the next peek() after the batch or change).
  bool take_batched(Step& out) {
    const int i = batch_.pos++;
    t_ = batch_.step[i];
    peeked_ = batch_.step[i + 1];
    ++steps_done_;
    out = Step{t_, direction_};
    return true;
  }
  void begin_decel();
  void adopt(const RampSpec& ramp, int64_t level);
  void reached_velocity();
  void advance_to(Tick at);
  void end_interval();
  Tick interval_length(Rational z, int64_t k);
  void skip_empty_intervals(int64_t most);
  bool decel_needed() const;
  int64_t steps_before_decel_check(int64_t distance) const;
  bool take_known(Step& out);
  bool next_unknown(Step& out);
  bool took_step(Step& out);
  std::optional<Tick> peek_unknown();
  // The plain level changes (one up or down, the phase unchanged) before end_interval()'s
  // other cases: the ramp's top, or the level a ramp down ends or holds at.
  int64_t plain_levels() const {
    if (phase_ == MotionPhase::Accelerating) return peak_level_ - level_;
    return level_ - std::max(ramp_.base_level, holding_ && !stopping_ ? decel_floor_ : int64_t{0}) -
           1;
  }
  bool solve_ramp(Tick until = kNever);
  Tick peek_plain();
  Tick peek_beyond(int64_t left, int64_t phase);
  Tick run_step_after() const;
  Tick peek_run();
  // Levels peek_plain() walks one at a time before it solves the rest: a few are faster
  // walked (the solve's divisions and square root cost more cycles than ~30 additions),
  // many far faster solved. Measured with ramp_cost_bench (README "Figures").
  static constexpr int64_t kWalked = 32;
  Tick peek_far(int64_t dir, int64_t plain);
  // A step kSolveFrom or more levels on after one as far (a continuous-slope ramp: ~10-20
  // levels a step on the grids the profiles make), solved with the last step's span as the
  // guess: fewer instructions than the walk, and less time (a guess from the square root,
  // a chain of divisions, took 2.3x the walk's time; README "Figures").
  Tick peek_solved(int64_t left, int64_t phase);
  Tick peek_batch(int64_t left, int64_t phase);
  template <int Dir>
  Tick solve_batch(int64_t left, int64_t phase, int64_t last, int64_t most);
  // A ramp's steps found without its carries, each proven by their spread (ramp_spread.hpp;
  // step_generator_bounded_batch.cpp); kUnpeeked where none is.
  template <int Dir>
  Tick bounded_batch(int64_t last, int64_t most);
  // The sparsest carries bounded_batch is asked for: one every 16 intervals (README
  // "Figures": on HP's grid, one in 24, the walk took 0.26 s of user time where the bounded
  // batch took 0.36 s, on CiA 402's, one in 6.6, the bounded batch was the faster).
  static constexpr int64_t kBoundedCarries = 16;
  void bounded_batch_state();
  int64_t batch_room() const;
  // Fills ramp_known_ if it is not; false where the cursor is not on the ramp's Z.
  bool know_ramp();
  // Hands the walk's or solve's state `w` over to next() (ahead_) and answers its step.
  Tick step_found(const RampWalk& w);
  static constexpr int64_t kSolveFrom = 4;
  void plan_decel();
  void count_step();
  // The jerk-limited profile (ramp.s_curve): step_generator_s_curve.cpp.
  void s_start(const RampSpec& ramp, Tick start, std::optional<int64_t> distance);
  bool s_next(Step& out);
  bool s_take_known(Step& out);
  bool s_take_steady(Step& out);
  void s_end_at_last_step();
  void s_follow();
  // The peak of the levels at every step, without the level of each: level_of(), the
  // conversions and the scale all rise with the slope, so the peak is the highest slope's
  // level (not holding the target: the level is the slope's), found when marks() is read.
  void s_track_peak() { s_peak_slope_ = std::max(s_peak_slope_, s_.p->slope()); }
  // With the steps taken from a batch (SCurve::batch: in one segment, its slope at each
  // computed when read).
  __int128 s_peak_slope() const {
    if (batch_.pos == 0 || s_at_target_) return s_peak_slope_;
    return std::max(s_peak_slope_, s_.p->peak_slope(batch_.step, batch_.pos));
  }
  void s_peek_after_step();
  void s_batch_state();
  int64_t s_level() const;
  int64_t s_level_at(double velocity) const;
  void s_fold_peak();
  void leave_s_curve(Tick at);
  JerkLimits jerk_limits(const RampSpec& ramp) const;
  double slope_of(Rational z) const;

  RampSpec ramp_;
  MotionPhase phase_ = MotionPhase::Idle;
  int direction_ = +1;
  std::optional<int64_t> distance_;
  int64_t peak_level_ = 0;
  Tick t_ = 0;  // time of the last event (step or level change)
  // peek()'s answer until the motion changes (a plain tick: the hot path copies the
  // generator for every step): a step time, or one of these. next() sets it after each
  // step; every other change of the motion resets it. A time here is the step next()
  // takes in the current interval (or ahead_'s), without the division (an S-curve's: the
  // one its own peek found); the answer a copy of the generator found is copied_ (kCopied
  // here).
  static constexpr Tick kUnpeeked = -2, kNoStep = -1, kCopied = -3;
  static constexpr Tick kNever = INT64_MAX;  // solve_ramp(): no tick to stop at
  Tick peeked_ = kUnpeeked;
  Tick copied_ = kNoStep;
  int64_t acc_ = 0;  // phase accumulator, 0 <= acc_ < phase_per_step
  int64_t level_ = 0;
  Tick interval_end_ = 0;  // end of the current ramp interval
  int64_t interval_index_ = 0;
  IntervalCursor cursor_;  // the interval lengths, walked without divisions
  // Where peek() got to through plain level changes, for next() to go on from.
  // The cursor's grid stays as it is on the way: only its place (passed, rem) moves.
  struct Ahead {
    bool valid = false;
    Tick t = 0;
    int64_t acc = 0, level = 0, passed = 0;
    Tick end = 0;
    int64_t rem = 0;
    void restore(StepGenerator& g) const;
  };
  Ahead ahead_;
  // The next steps of a trapezoid, up to kSize of them solved together: in a ramp by
  // solve_batch (the set-up, the checks of the ramp and the walk's state in registers once
  // for them all), at a constant level by peek_run. (Or an S-curve's in one segment, by
  // SCurve::batch: their times alone, the S-curve moved on in s_batch_state.) next() takes them one
  // after another (take_batched: the time and the count alone). The motion right after each (its
  // accumulator and level, and in a ramp the interval's place, from the level alone: each
  // interval moves it by one) follows when anything else needs it (sync_batch, on the
  // ways in after any change and after the batch's last step). Copied with the generator:
  // a planner's copy goes on from the same steps.
  struct StepBatch {
    static constexpr int kSize = 32;
    // No initializers: only the entries in use are read, or copied. step[count] is
    // kUnpeeked: after the last, the next peek() comes in by peek_unknown().
    Tick step[kSize + 1];
    int64_t acc[kSize], level[kSize];
    int64_t level0 = 0;      // the level the batch began at
    int pos = 0, count = 0;  // count > 0: step[pos] is the next step (peeked_)
    // What it keeps of each step besides the time: its accumulator and level (solved: the
    // walk's, peek_run's), its level alone (bounded: bounded_batch's, whose accumulator
    // follows from where it began: the tick t0 of the step before it, and the accumulator,
    // interval end and cursor the generator keeps until sync_batch), or nothing (an
    // S-curve's).
    enum class Kept : uint8_t { Solved, Bounded, Times };
    Kept kept = Kept::Solved;
    Tick t0 = 0;
    // A copy takes the entries in use alone: the hot path copies the generator (peek_unknown's
    // copy, a planner), most often with none.
    StepBatch() = default;
    StepBatch(const StepBatch& o) { *this = o; }
    StepBatch& operator=(const StepBatch& o) {
      if (this == &o) return *this;
      level0 = o.level0, pos = o.pos, count = o.count;
      if (count == 0) return *this;
      kept = o.kept, t0 = o.t0;
      std::copy(o.step, o.step + o.count + 1, step);
      if (kept == Kept::Solved) std::copy(o.acc, o.acc + o.count, acc);
      if (kept != Kept::Times) std::copy(o.level, o.level + o.count, level);
      return *this;
    }
  };
  StepBatch batch_;
  // The spreads of the ramp up's and the ramp down's grids (bounded_batch), each counted
  // once for as long as its grid stays.
  std::array<CarrySpread, 2> spreads_;
  // The motion to the last step taken from batch_, its steps counted in marks_, batch_
  // emptied (batch_state(), at the next peek() after its last step or a change).
  void sync_batch() {
    if (batch_.count == 0) return;
    if (batch_.pos > 0) batch_state();
    batch_.pos = batch_.count = 0;
  }
  void batch_state();
  // A change of the motion (start, stop, halt, a new velocity, level, grid or end): made
  // to its state at the last step taken, and the next step may move.
  void begin_change() {
    sync_batch();
    peeked_ = kUnpeeked;
  }
  // The count in `m` of the steps taken in the current phase.
  int64_t& phase_steps(Marks& m) const {
    switch (phase_) {
      case MotionPhase::Accelerating: return m.accel_steps;
      case MotionPhase::Running: return m.run_steps;
      case MotionPhase::Decelerating: return m.decel_steps;
      default: return m.creep_steps;
    }
  }
  // Adds the steps taken from batch_ to its phase's count in `m`.
  void count_batch_steps(Marks& m) const { phase_steps(m) += batch_.pos; }
  bool walked_ = false;  // walk_ramps(): every ramp interval walked
  // The levels the last peek's walk or solve passed to its step: a ramp's next step spans
  // nearly as many (the solve's first guess), and from kSolveFrom on it is solved.
  int64_t last_span_ = 0;
  // What know_ramp() found of the ramp for the steps next() takes one after another from
  // known steps (take_known: the same ramp phase, levels moving within its plain ones):
  // whether its Z is below 1 (steep), its direction and last plain level. next_unknown()
  // and peek_unknown(), the ways in after any change (each resets peeked_), clear it.
  struct KnownRamp {
    bool valid = false, steep = false;
    int64_t dir = 0, last = 0;
  };
  KnownRamp ramp_known_;
  bool stopping_ = false;         // stop(): no creep after the ramp
  Tick decel_tick_ = -1;          // while running to a target: the tick deceleration begins
  bool holding_ = false;          // change_velocity() down: run on at decel_floor_
  int64_t decel_floor_ = 0;       // the level a deceleration ends at (base, or a lower velocity)
  std::optional<RampSpec> then_;  // change_velocity(): the grid to move to once there
  // A ramp up to a target asks decel_needed() only after this many steps: until then the
  // steps left cover the whole ramp down from the peak (start() sets it; a change that may
  // raise the peak, bring the end nearer or change the ramp down sets -1: ask every step).
  int64_t decel_check_after_ = -1;
  int64_t steps_done_ = 0;
  Marks marks_;
  // The S-curve's state, on the heap (the hot path copies the generator; a trapezoid
  // copies only the empty pointer), deep-copied with the generator.
  struct SCurveSlot {
    std::unique_ptr<SCurve> p;
    SCurveSlot() = default;
    SCurveSlot(const SCurveSlot& o) : p(o.p ? std::make_unique<SCurve>(*o.p) : nullptr) {}
    SCurveSlot& operator=(const SCurveSlot& o) {
      if (this != &o) p = o.p ? std::make_unique<SCurve>(*o.p) : nullptr;
      return *this;
    }
    SCurveSlot(SCurveSlot&&) = default;
    SCurveSlot& operator=(SCurveSlot&&) = default;
  };
  SCurveSlot s_;
  bool scurve_ = false;  // the running motion is s_'s
  // The S-curve's level is s_level()'s, from its state at the last step or change (level_
  // is not kept); leave_s_curve() writes it into level_.
  bool s_level_lazy_ = false;
  bool s_at_target_ = false;  // it holds its target velocity: the level is the target's
  // The highest slope at a step of the running S-curve, whose level marks() counts in the
  // peak (0: none; leave_s_curve() folds it into marks_).
  __int128 s_peak_slope_ = 0;
};

}  // namespace stepnode::motion
