// The software position limits 607Dh in the velocity modes (CiA 402-2: "These parameters
// define the absolute position limits for the position demand value and the position
// actual value"). PP and CSP keep their targets inside them (clamp_to_limits); PV and CSV
// have no target, so a motion toward a limit is given the step at which its stop must
// begin to end on or before the limit with the quick stop deceleration 6085h (the brake
// point: a step rule of the core, no per-step cost before it), and after that the limit
// itself, on which the motion ends whatever is left of the ramp (no step goes past it). A
// motion that could not stop before the limit does not start. The stop ramps of the cyclic
// modes (CSP's quick stop, halt, mode change) are watched the same way.
//
// The brake point is worked out for the highest velocity the motion may reach before it:
// the target, or less where a ramp up (6083h) toward a near limit must turn to leave room
// for the stop. Until the next change of velocity (PV's 60FFh, CSV's SYNC) the axis is no
// faster there, so a stop begun there ends in time.
#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "node/profiles/cia402/drive.hpp"

namespace stepnode::cia402 {

using motion::Tick;

std::optional<int64_t> Drive::limit_ahead(int direction) const {
  // As for PP's targets: the limits are in effect while min < max.
  const int64_t low = parameters_.min_position_limit, high = parameters_.max_position_limit;
  if (low >= high) return std::nullopt;
  return direction > 0 ? high : low;
}

bool Drive::jerk_limited_stop() const {
  // PV's quick stop keeps 6086h's ramp; the cyclic modes' stop ramps are trapezoids.
  return mode_display_ == Mode::ProfileVelocity &&
         parameters_.motion_profile_type == kJerkLimitedRamp;
}

double Drive::stop_steps(double v, bool accelerating) const {
  // A trapezoid on the grid from level v·g to 0 at 6085h = q: v²/2q + v/2qg steps of phase
  // and the accumulator's step; a step more for the roundings of the velocity and the slope
  // to the grid.
  const double q = std::max<uint32_t>(parameters_.quick_stop_deceleration, 1);
  if (!jerk_limited_stop()) return v * v / (2 * q) + v / q + 2;
  // PV's jerk-limited quick stop (60A4h, 0: not limited): while accelerating (at most
  // 6083h = a) the acceleration is taken down first at the end acceleration jerk, the
  // velocity rising by a·t1/2 meanwhile; then the deceleration builds up to q in t2 (begin
  // deceleration jerk) and tapers off in t3 (end deceleration jerk): v²/2q + v·t2/2 -
  // q·t2²/24 + 5q·t3²/24 when q is reached, no more than v·(t2 + t3) when it is not.
  const auto phase = [](double rate, uint32_t jerk) { return jerk ? rate / jerk : 0.0; };
  const double a = std::max<uint32_t>(parameters_.acceleration, 1);
  const double t1 = accelerating ? phase(a, parameters_.jerk[2]) : 0.0;
  const double top = v + a * t1 / 2;
  const double t2 = phase(q, parameters_.jerk[1]), t3 = phase(q, parameters_.jerk[3]);
  const double ramp = top * top / (2 * q) + top * (t2 + t3) / 2 + q * t3 * t3 / 4;
  return top * t1 + std::max(ramp, top * (t2 + t3)) + top / q + 2;
}

double Drive::reachable(int direction, double from, double to) const {
  // Accelerating from `from` at a (6083h) over x steps, then stopping at q (6085h): the
  // velocity peaks at v² = from² + 2ax with v²/2q = d - x, so v² = (2aqd + q·from²)/(a + q).
  const std::optional<int64_t> limit = limit_ahead(direction);
  if (!limit || to <= from) return std::max(from, to);
  const double d = static_cast<double>((*limit - core_.position()) * direction);
  const double a = std::max<uint32_t>(parameters_.acceleration, 1);
  const double q = std::max<uint32_t>(parameters_.quick_stop_deceleration, 1);
  const double fit = (2 * a * q * d + q * from * from) / (a + q);
  return std::clamp(fit > 0 ? std::sqrt(fit) : 0.0, from, to);
}

std::optional<int64_t> Drive::brake_point(int direction, double from, double v) const {
  const std::optional<int64_t> limit = limit_ahead(direction);
  if (!limit) return std::nullopt;
  double steps = stop_steps(v, false);
  if (jerk_limited_stop() && from < v) {
    // Still in the ramp up (from `from` to v: (v² - from²)/2a, and at most v for the time
    // of its jerk phases) when it gets there: the stop first takes the acceleration down.
    const auto phase = [](double rate, uint32_t jerk) { return jerk ? rate / jerk : 0.0; };
    const double a = std::max<uint32_t>(parameters_.acceleration, 1);
    const double ramp_up = (v * v - from * from) / (2 * a) +
                           v * (phase(a, parameters_.jerk[0]) + phase(a, parameters_.jerk[2]));
    const double room = static_cast<double>((*limit - core_.position()) * direction) - steps;
    if (room < ramp_up) steps = stop_steps(v, true);
  }
  return *limit - direction * static_cast<int64_t>(std::ceil(steps));
}

bool Drive::room_to_stop(int direction, double from, double v) const {
  const std::optional<int64_t> b = brake_point(direction, from, v);
  return !b || (*b - core_.position()) * direction >= 1;
}

void Drive::watch_limit(int direction, double from, double v, Tick now) {
  limit_rule_.reset();
  limit_braking_ = false;
  limit_direction_ = direction;
  if (const std::optional<int64_t> b = brake_point(direction, from, v)) {
    if ((*b - core_.position()) * direction < 1) return brake_for_limit(direction, now);
    limit_rule_ = static_cast<int32_t>(std::clamp<int64_t>(*b, INT32_MIN, INT32_MAX));
  }
  core_.hooks_changed(*this);
}

void Drive::brake_for_limit(int direction, Tick at) {
  // The 6085h stop (a cyclic job carried over to a ramp first), then the limit as the rule:
  // the motion ends on it if the ramp has not ended before.
  internal_limit_ = true;
  limit_braking_ = true;
  limit_direction_ = direction;
  const int64_t limit = *limit_ahead(direction);
  if ((limit - core_.position()) * direction <= 0) {
    limit_rule_.reset();
    core_.halt_motion(at);  // on (or beyond) the limit already: not a step further
    return;
  }
  ramp_from_cyclic(at);
  core_.stop(at, quick_stop_slope());
  limit_rule_ = static_cast<int32_t>(limit);
  core_.hooks_changed(*this);
}

[[gnu::noinline]] void Drive::at_limit_rule(Tick at) {
  if (!limit_braking_) return brake_for_limit(limit_direction_, at);
  limit_rule_.reset();
  core_.halt_motion(at);  // on the limit, the ramp not yet ended
}

void Drive::job_halted(const motion::FrontEnd& owner, Tick when) {
  (void)when;
  if (&owner == this) limit_rule_.reset();  // the job is over: its rule with it
}

}  // namespace stepnode::cia402
