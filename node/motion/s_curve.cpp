// The S-curve's plans: the segments of a motion from its current state (s_curve.hpp).
#include "node/motion/s_curve.hpp"

#include <algorithm>
#include <cmath>

#include "node/motion/s_curve_phases.hpp"

namespace stepnode::motion {
namespace {

constexpr double kT = static_cast<double>(kClockHz);
// The scales of the integer coefficients: S p, 6 T^2 v (c1), 3 T a (c2).
constexpr __int128 kS = static_cast<__int128>(6) * kClockHz * kClockHz * kClockHz;
constexpr double kV = 6.0 * kT * kT, kA = 3.0 * kT;

Tick ticks(double seconds) { return static_cast<Tick>(std::llround(seconds * kT)); }

}  // namespace

void SCurve::push(const Segment& s) {
  if (count_ >= kMaxSegments) return;
  segs_[count_] = s;
  if (s.len != kOpen) segs_[count_].end = s.at(s.len);
  ++count_;
}

SCurve::State SCurve::state_at(Tick at) const {
  // The segment that runs at `at` (the last one's end when the plan has run out).
  for (int k = seg_; k < count_; ++k) {
    const Segment& g = segs_[k];
    if (at < g.start + g.len || k == count_ - 1) {
      const Tick tau = std::clamp<Tick>(at - g.start, 0, g.len);
      return State{g.at(tau), g.slope(tau), g.c2 + 3 * static_cast<__int128>(g.c3) * tau};
    }
  }
  return State{};
}

void SCurve::add_transition(Tick& t, State& s, double v1, double decel) {
  // The three phases on whole ticks; phase 2's acceleration is set exactly (a jump of less
  // than one tick of jerk where phase 1 ended), velocity and position carry on.
  const double v0 = static_cast<double>(s.v) / kV, a0 = static_cast<double>(s.a) / kA;
  const scurve::Phases ph = scurve::transition(v0, a0, v1, limits_, decel);
  const Kind kind = ph.sign > 0 ? Kind::Accelerating : Kind::Decelerating;
  const double peak = ph.sign * ph.peak;
  auto phase = [&](Tick n, int64_t jerk) {
    if (n <= 0) return;
    Segment g{t, n, s.p, s.v, s.a, jerk, kind};
    push(g);
    s = State{g.at(n), g.slope(n), g.c2 + 3 * static_cast<__int128>(jerk) * n};
    t += n;
  };
  phase(ticks(ph.t1), (peak > a0 ? 1 : -1) * static_cast<int64_t>(ph.j1));
  s.a = static_cast<__int128>(std::llround(peak * kA));
  phase(ticks(ph.t2), 0);
  phase(ticks(ph.t3), -ph.sign * static_cast<int64_t>(ph.j3));
  s.a = 0;
  if (s.v < 0) s.v = 0;
}

void SCurve::add_open(Tick t, const State& s, Kind kind) {
  push(Segment{t, kOpen, s.p, s.v, 0, 0, kind});
}

void SCurve::add_position_goal(Tick t, State s, int64_t distance, double vp) {
  add_transition(t, s, vp, limits_.deceleration);
  // The ramp down, built forwards from standstill (its mirror image), then laid backwards
  // from the target: it ends there with velocity 0 on a tick.
  const scurve::Phases ph = scurve::ramp_down_mirror(vp, limits_, limits_.deceleration);
  std::array<Segment, 3> up{};
  int n_up = 0;
  State q;
  auto phase = [&](Tick n, int64_t jerk) {
    if (n <= 0) return;
    Segment g{0, n, q.p, q.v, q.a, jerk, Kind::Decelerating};
    up[n_up++] = g;
    q = State{g.at(n), g.slope(n), g.c2 + 3 * static_cast<__int128>(jerk) * n};
  };
  phase(ticks(ph.t1), ph.j1);
  q.a = static_cast<__int128>(std::llround(ph.peak * kA));
  phase(ticks(ph.t2), 0);
  phase(ticks(ph.t3), -static_cast<int64_t>(ph.j3));
  const __int128 end = static_cast<__int128>(distance) * kS;
  // The cruise between: whole ticks at the velocity reached (the position it leaves over,
  // less than half a tick's travel, is where the ramp down takes over).
  const __int128 gap = end - q.p - s.p;
  const Tick cruise = s.v > 0 && gap > 0 ? static_cast<Tick>((gap + s.v / 2) / s.v) : 0;
  if (cruise > 0) push(Segment{t, cruise, s.p, s.v, 0, 0, Kind::Cruise});
  t += cruise;
  for (int k = n_up - 1; k >= 0; --k) {
    const Segment& g = up[k];
    const Tick n = g.len;
    push(Segment{t, n, end - g.at(n), g.slope(n), -(g.c2 + 3 * static_cast<__int128>(g.c3) * n),
                 g.c3, Kind::Decelerating});
    t += n;
  }
  // Never reached when the plan fits; after a ramp that could not (a target too close to
  // stop for), the rest at the velocity one step from standstill reaches.
  const double creep = std::max(1.0, std::sqrt(2 * limits_.deceleration));
  add_open(t, State{end, static_cast<__int128>(creep * kV), 0}, Kind::Creep);
}

void SCurve::replan(Tick at, std::optional<int64_t> distance, double velocity,
                    std::optional<double> decel) {
  peeked_.reset();
  local_[cur_].seg = -1;  // the segments change: the next step by the full search
  even_.seg = -1;
  even_.ready = false;
  const State now = state_at(at);
  const double v0 = static_cast<double>(now.v) / kV, a0 = static_cast<double>(now.a) / kA;
  count_ = seg_ = 0;
  Tick t = at;
  State s = now;
  if (!distance) {
    add_transition(t, s, velocity, decel.value_or(limits_.deceleration));
    if (velocity > 0 && s.v > 0) add_open(t, s, Kind::Hold);
    end_ = t;
    return;
  }
  // The highest velocity (up to the cruise velocity) whose change and ramp down fit the
  // steps left; none fits: ramp down at once (the move ends on its last step).
  const double left =
      static_cast<double>(static_cast<__int128>(*distance) * kS - now.p) / static_cast<double>(kS);
  auto needs = [&](double vp) {
    const scurve::Kinematics k =
        scurve::run({0, v0, a0}, scurve::transition(v0, a0, vp, limits_, limits_.deceleration));
    return k.p + scurve::run({}, scurve::ramp_down_mirror(vp, limits_, limits_.deceleration)).p;
  };
  double vp = velocity;
  if (needs(vp) > left) {
    double lo = 0, hi = vp;
    if (needs(0) > left) hi = 0;
    for (int i = 0; i < 60 && hi - lo > 1e-9 * std::max(1.0, hi); ++i) {
      const double mid = (lo + hi) / 2;
      (needs(mid) <= left ? lo : hi) = mid;
    }
    vp = lo;
  }
  add_position_goal(t, s, *distance, vp);
}

void SCurve::start(const JerkLimits& limits, Tick start, std::optional<int64_t> distance) {
  limits_ = limits;
  segs_[0] = Segment{start, 0, 0, 0, 0, 0, Kind::Accelerating};
  count_ = 1;
  seg_ = 0;
  last_ = start;
  steps_ = 0;
  distance_ = distance;
  still_ = true;
  ended_ = false;
  hold_velocity_ = distance ? -1 : limits.velocity;
  replan(start, distance, limits.velocity, std::nullopt);
}

void SCurve::stop(Tick at, std::optional<double> decel) {
  if (ended_) return;
  if (decel) limits_.deceleration = *decel;
  hold_velocity_ = -1;
  distance_.reset();
  replan(at, std::nullopt, 0, decel);
}

void SCurve::change_velocity(Tick at, double velocity) {
  if (ended_) return;
  limits_.velocity = velocity;
  if (!distance_) hold_velocity_ = velocity;
  replan(at, distance_, velocity, std::nullopt);
}

void SCurve::retarget(Tick at, int64_t distance) {
  if (ended_) return;
  distance_ = distance;
  hold_velocity_ = -1;
  replan(at, distance_, limits_.velocity, std::nullopt);
}

double SCurve::steps_to_stop(Tick at) const {
  if (ended_) return 0;
  const State now = state_at(at);
  const double v0 = static_cast<double>(now.v) / kV, a0 = static_cast<double>(now.a) / kA;
  return scurve::run({0, v0, a0}, scurve::transition(v0, a0, 0, limits_, limits_.deceleration)).p;
}

}  // namespace stepnode::motion
