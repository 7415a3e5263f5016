// The jerk-limited (S-curve) profile, CiA 402 6086h = 3: the exact tick of every step of a
// motion whose acceleration changes at a limited rate (jerk, 60A4h).
//
// The motion is a chain of segments of constant jerk (+j, 0, -j) whose ends fall on ticks.
// In a segment the position is an exact cubic in the tick count τ, kept in integers scaled
// by S = 6 T^3 (T = kClockHz): S p(τ) = c0 + c1 τ + c2 τ^2 + c3 τ^3 with c1 = 6 T^2 v,
// c2 = 3 T a, c3 = j (steps, steps/s, steps/s^2, steps/s^3). Step n falls on the first tick
// at which S p reaches n S: a double-precision Newton estimate, checked and corrected
// with the exact integers. From one step to the next the cubic is kept moved to the last
// step's tick (s_curve_local.cpp), so a step costs a short Newton solve and two exact
// evaluations of a cubic at a small offset; the full search takes over where that does
// not decide (a segment's end, a replan, an estimate more than a tick off). The generator
// takes most of a ramp's steps in batches (s_curve_batch.cpp): found in doubles from one
// exact place, each proven by an error bound, no 128-bit product a step. At a constant
// velocity (a cruise, a held velocity, a creep) a step is a Bresenham line's instead
// (s_curve_even.cpp): two additions and a compare. Position and velocity
// are continuous; at a segment end the acceleration may jump by less than one tick of jerk (the
// phases are whole ticks long). A move to a target is planned backwards from the target (its ramp
// down ends there with v = 0 exactly), forwards from where the motion is; a cruise joins the two.
#pragma once
#include <array>
#include <cstdint>
#include <optional>

#include "node/motion/s_curve_scale.hpp"
#include "node/motion/timebase.hpp"

namespace stepnode::motion {

// The limits of an S-curve, in steps, steps/s, steps/s^2 and steps/s^3. A jerk of 0 is not
// limited (60A4h: "0: the jerk is not limited"): that phase takes no time.
struct JerkLimits {
  double velocity = 1;                                // the cruise velocity (6081h, 60FFh)
  double acceleration = 1;                            // 6083h
  double deceleration = 1;                            // 6084h (or 6085h for a quick stop)
  uint32_t begin_accel_jerk = 0, end_accel_jerk = 0;  // 60A4h:1, :3
  uint32_t begin_decel_jerk = 0, end_decel_jerk = 0;  // 60A4h:2, :4
};

class SCurve {
 public:
  enum class Kind : uint8_t { Accelerating, Cruise, Decelerating, Hold, Creep };

  // From standstill at `start`: to `distance` steps (> 0), or to the velocity and on.
  void start(const JerkLimits& limits, Tick start, std::optional<int64_t> distance);
  // The next step's tick after the last one; nullopt when the motion has ended (end()).
  std::optional<Tick> next_step();
  // The peeked step lies on a constant velocity the last step already had (a cruise's
  // second step on): taking it (take_even(), the step's tick) changes nothing but the step
  // count and time, and peeks the one after it.
  bool next_is_steady() const { return even_.ready && even_.entered; }
  Tick take_even();
  std::optional<Tick> peek() {
    if (!peeked_) peeked_ = search().value_or(-1);
    return *peeked_ < 0 ? std::nullopt : peeked_;
  }
  // For tests: every step by the full search (the reference the quick one must equal).
  void use_full_search() { full_search_only_ = true; }
  int64_t quick_steps() const { return quick_steps_; }  // steps the quick search found
  int64_t even_steps() const { return even_steps_; }    // of those, at a constant velocity
  // From `at`: ramp to velocity 0 and end (deceleration `decel`, or the limits' one).
  void stop(Tick at, std::optional<double> decel = std::nullopt);
  // From `at`: a new cruise velocity (a move keeps its target), or a new target
  // `distance` steps from the start (the velocity and acceleration carry on).
  void change_velocity(Tick at, double velocity);
  void retarget(Tick at, int64_t distance);

  bool ended() const { return ended_; }
  Tick end() const { return end_; }
  int64_t steps() const { return steps_; }
  std::optional<int64_t> distance() const { return distance_; }
  // At the last step (or change): the velocity in steps/s and what the motion does. The
  // velocity is the exact slope's (slope()), converted only when read.
  double velocity() const { return velocity_of(slope()); }
  // The velocity in steps/s at S dp/dtau = `slope`.
  static double velocity_of(__int128 slope) { return scurve::to_double(slope) / scurve::kV; }
  // S dp/dtau at the last step: 6 T^2 steps/s, 0 before the first step and after the end.
  __int128 slope() const { return still_ ? 0 : local_[cur_].b1; }
  // Right after next_step(): that step was the quick search's (in the last step's segment).
  bool last_step_quick() const { return pending_quick_; }
  Kind kind() const { return seg_ < count_ ? segs_[seg_].kind : Kind::Hold; }
  bool at_target_velocity() const {  // a velocity motion holds its velocity
    return !ended_ && hold_velocity_ >= 0 && kind() == Kind::Hold;
  }
  double target_velocity() const { return hold_velocity_; }
  // Steps from here to standstill with the deceleration ramp (the motion stops there).
  double steps_to_stop(Tick at) const;

  // A batch (s_curve_batch.cpp): up to `most` of the steps after the last one, those in
  // its segment while it has acceleration or jerk (the quick search's place), into `out`;
  // 0 where there is none. Never the motion's last step. The motion does not move until
  // take_batch() takes the first k of them (k >= 1, `steps` the batch's ticks).
  int batch(Tick* out, int most) const;
  void take_batch(const Tick* steps, int k);
  // S dp/dtau at a batched step's tick (its segment is the last step's), and the highest
  // at the first k of them.
  __int128 slope_at(Tick t) const {
    const Segment& g = segs_[seg_];
    return g.slope(t - g.start);
  }
  __int128 peak_slope(const Tick* steps, int k) const;

 private:
  struct Segment {
    Tick start = 0;
    Tick len = 0;  // kOpen: runs until changed
    __int128 c0 = 0, c1 = 0, c2 = 0;
    int64_t c3 = 0;
    Kind kind = Kind::Accelerating;
    __int128 end = 0;  // at(len), the position where it ends (push() sets it)
    __int128 at(Tick tau) const {
      return c0 + tau * (c1 + tau * (c2 + c3 * static_cast<__int128>(tau)));
    }
    __int128 slope(Tick tau) const {
      return c1 + tau * (2 * c2 + 3 * static_cast<__int128>(c3) * tau);
    }
  };
  struct State {
    __int128 p = 0, v = 0, a = 0;  // S p, S dp/dτ, S d2p/dτ2 / 2 (c0, c1, c2 of a segment here)
  };
  static constexpr Tick kOpen = INT64_MAX / 4;
  // The longest step the quick search and a batch take (2^40 ticks, 62 hours): the exact
  // rise stays far inside 128 bits in a segment without jerk (one with jerk is shorter).
  static constexpr Tick kLongestStep = Tick{1} << 40;
  static constexpr int kMaxSegments = 12;

  State state_at(Tick at) const;
  void replan(Tick at, std::optional<int64_t> distance, double velocity,
              std::optional<double> decel);
  void push(const Segment& s);
  void add_transition(Tick& t, State& s, double v1, double decel);
  void add_position_goal(Tick t, State s, int64_t distance, double vp);
  void add_open(Tick t, const State& s, Kind kind);
  static Tick find(const Segment& g, Tick lo, __int128 target);
  std::optional<Tick> compute(int& k) const;
  std::optional<Tick> search();
  // The quick search (s_curve_local.cpp): the cubic of the last step's segment moved to
  // its tick, S p(tau + d) = S p(tau) + d (b1 + d (b2 + d c3)), exact in the integers, and
  // in doubles for Newton (kept up by the same shifts).
  struct Local {
    int seg = -1;             // its segment; -1: none (the full search finds the next step)
    Tick tau = 0;             // the last step's tick in that segment
    __int128 gap = 0;         // (steps + 1) S - S p(tau): the next step's distance, > 0
    __int128 b1 = 0, b2 = 0;  // S dp/dtau, S d2p/dtau2 / 2 at tau
    __int128 left = 0;        // S p at the segment's end - S p(tau) (open: far above)
    double b1d = 0, b2d = 0, gapd = 0;
    double x = 0, w = 1, dw = 0;  // the last crossing - tau, the last interval, its change
  };
  std::optional<Tick> quick();
  static int try_step(const Local& l, const Segment& g, Tick d, Local& n);
  // A segment of constant velocity (c2 = c3 = 0: a cruise, a hold, a creep), kS = q c1 + r:
  // each step falls q or q + 1 ticks after the one before, as the overshoot past the step
  // (kS - gap, 0 <= it < c1) moves by -r modulo c1, a Bresenham line (s_curve_even.cpp).
  // No Newton, no cubic: most of a move's steps are its cruise's. While it runs, Local is
  // not kept up: the current one has the slope (c1) and no segment (seg -1), so once a step
  // falls beyond the segment the full search finds it.
  struct Even {
    int seg = -1;          // the segment q and r are for; -1: none
    bool ready = false;    // peeked_ is this path's step: take_even() takes it
    bool entered = false;  // local_[cur_] is this path's (c1, seg -1)
    Tick q = 0;
    Tick bound = 0;                    // the segment's last tick
    __int128 r = 0, c1 = 0, over = 0;  // over: the peeked step's overshoot, 0 <= over < c1
  };
  void seat_even(int seg, const Segment& g);
  std::optional<Tick> even_step(const Local& l, const Segment& g);
  void seat_local(Tick prev);

  JerkLimits limits_;
  std::array<Segment, kMaxSegments> segs_{};
  int count_ = 0, seg_ = 0;
  Tick last_ = 0;  // the last step's tick (or the start)
  int64_t steps_ = 0;
  std::optional<int64_t> distance_;
  bool still_ = true;          // no step yet, or ended: velocity 0
  double hold_velocity_ = -1;  // the velocity a velocity motion goes to
  bool ended_ = true;
  Tick end_ = 0;
  std::optional<Tick> peeked_;
  int peeked_seg_ = 0;
  std::array<Local, 2> local_{};  // at the last step, and after peek()'s quick one
  int cur_ = 0;                   // local_[cur_] is the last step's
  bool pending_quick_ = false;    // peek()'s step is local_[cur_ ^ 1]'s
  bool full_search_only_ = false;
  int64_t quick_steps_ = 0;
  Even even_;
  int64_t even_steps_ = 0;
};

}  // namespace stepnode::motion
