// The cyclic modes of the CiA 402 drive (CiA 402-2 "Cyclic synchronous position mode",
// "Cyclic synchronous velocity mode", "Interpolated position mode"): a set-point every SYNC.
//
// Interpolation (CSP, IP sub-mode 0): linear. The set-point a SYNC brings is reached one
// cycle later: the axis moves from where it is to it at a constant rate, its n steps at
// the exact ticks start + ceil(i * cycle / n) (the engine's phase accumulator with one step
// = `cycle` phase units and n units a tick). A set-point a SYNC does not bring (a missed
// SYNC) leaves the axis at the last one: no extrapolation, no jump. A SYNC before the
// previous segment is done (jitter) folds its remaining steps into the new one. CSV: the
// velocity changes at once at the SYNC, keeping the phase (no step gained or lost).
//
// Stops: the master's set-points are the trajectory, so a cyclic job runs at one velocity
// with nothing to ramp (base level = run level). A stop the drive makes itself (the option
// codes' ramps, a mode change) first carries the job over to a profile ramp from standstill
// at the velocity it runs (ramp_from_cyclic), which the stop then ramps down as in PV.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>

#include "node/profiles/cia402/drive.hpp"

namespace stepnode::cia402 {

using motion::Tick;

namespace {

int sign(int64_t v) { return v < 0 ? -1 : +1; }

int64_t saturated(int64_t v) { return std::clamp<int64_t>(v, INT32_MIN, INT32_MAX); }

}  // namespace

void Drive::measure_cycle(Tick arrival) {
  // The cycle is the SYNC period as received (the master's 60C2h may not be written),
  // starting from 60C2h. One odd interval changes nothing: two SYNCs read out of a queued
  // socket arrive microseconds apart, a missed SYNC leaves a double one. An interval within
  // half a cycle of the cycle is averaged in (jitter); one nearer a whole multiple of two or
  // more is missed SYNCs, and odd (averaged in up to twice the cycle, one lost SYNC in a 1 ms
  // stream made the cycle 1.25 ms, every set-point after it reached late: found in review).
  // Eight odd ones in a row that agree with each other to a quarter are a new period, and
  // it is taken (a stalled process reads a few long intervals in a row: not a new period).
  if (cycle_ <= 0) cycle_ = std::max<Tick>(parameters_.interpolation_period, 1);
  if (last_sync_) {
    const Tick d = arrival - *last_sync_;
    if (d > 0 && 2 * d >= cycle_ && 2 * d < 3 * cycle_) {
      cycle_ = (3 * cycle_ + d) / 4;
      odd_intervals_ = 0;
    } else if (d > 0) {
      const bool agrees =
          odd_intervals_ > 0 && 4 * d >= 3 * odd_interval_ && 4 * d <= 5 * odd_interval_;
      odd_interval_ = agrees ? (odd_interval_ + d) / 2 : d;
      odd_intervals_ = agrees ? odd_intervals_ + 1 : 1;
      if (odd_intervals_ >= 8) {
        cycle_ = odd_interval_;
        odd_intervals_ = 0;
      }
    }
  }
  last_sync_ = arrival;
}

void Drive::sync(Tick now, Tick arrival) {
  measure_cycle(arrival);
  // Not while the drive stops on its own ramp: halted, a state machine's stop (not
  // operation enabled) or a mode change waiting for the motion's end.
  if (!machine_.operation_enabled() || halted_ || !cyclic(mode_display_) || mode_ != mode_display_)
    return;
  core_.advance_to(now);
  switch (mode_display_) {
    // CSP's input is 607Ah + 60B0h, CSV's 60FFh + 60B1h, each sum held to INTEGER32.
    case Mode::CyclicSyncPosition:
      cyclic_position(saturated(int64_t{target_position_} + position_offset_), now);
      break;
    case Mode::InterpolatedPosition:
      if (controlword_ & kEnableIp) cyclic_position(ip_set_point_, now);
      break;
    case Mode::CyclicSyncVelocity:
      cyclic_velocity(saturated(int64_t{target_velocity_} + velocity_offset_), now);
      break;
    default: break;
  }
  notify();
}

void Drive::cyclic_position(int64_t target, Tick now) {
  if (core_.busy() && !core_.owned_by(*this)) return;  // another front end's job
  target = clamp_to_limits(target);
  csv_running_ = false;
  own_ramp_ = false;
  limit_rule_.reset();  // the segment ends inside 607Dh (a stop ramp's rule is over)
  const int64_t from = core_.position();
  seg_from_ = from;
  seg_to_ = target;
  seg_start_ = now;
  seg_ticks_ = std::max<Tick>(cycle_, 1);
  seg_steps_ = 0;
  int64_t steps = std::llabs(target - from);
  if (steps == 0) {
    if (core_.owned_by(*this)) core_.halt(*this, now);
    return;
  }
  // No faster than 607Fh, and no more than a step a tick: beyond, the axis lags and the
  // following error shows it.
  const int64_t most =
      std::max<int64_t>(1, int64_t{parameters_.max_velocity} * seg_ticks_ / motion::kClockHz);
  steps = std::min({steps, most, seg_ticks_});
  seg_steps_ = steps;
  motion::RampSpec r;
  r.phase_per_step = seg_ticks_;
  r.base_level = r.run_level = r.min_creep_level = steps;
  r.accel_ticks_per_level = r.decel_ticks_per_level = motion::Rational{1, 1};
  core_.start(*this, r, sign(target - from), steps, now);
}

void Drive::cyclic_velocity(int64_t velocity, Tick now) {
  if (core_.busy() && !core_.owned_by(*this)) return;
  velocity =
      std::clamp<int64_t>(velocity, -int64_t{parameters_.max_velocity}, parameters_.max_velocity);
  const motion::StepGenerator& g = core_.generator();
  const bool on_the_way = core_.owned_by(*this) && g.moving() && g.direction() == sign(velocity);
  // 607Dh: toward a limit the axis could not stop before from this velocity, a motion on
  // its way there stops now (6085h), none starts (drive_limits.cpp; CSV ran past them:
  // found in review).
  internal_limit_ =
      velocity != 0 && !room_to_stop(sign(velocity), 0, static_cast<double>(std::llabs(velocity)));
  if (internal_limit_) {
    if (on_the_way) {
      if (!g.stopping()) brake_for_limit(sign(velocity), now);
      return;
    }
    velocity = 0;
  }
  if (velocity == 0) {
    if (core_.owned_by(*this)) core_.halt(*this, now);
    csv_running_ = false;
    return;
  }
  if (csv_running_ && on_the_way) {
    core_.set_level(now, std::llabs(velocity));
    watch_limit(sign(velocity), 0, static_cast<double>(std::llabs(velocity)), now);
    return;
  }
  if (core_.owned_by(*this)) core_.halt(*this, now);  // a reversal: at once, the master's ramp
  own_ramp_ = false;
  motion::RampSpec r;  // one level a step/s: every whole velocity exact
  r.phase_per_step = motion::kClockHz;
  r.base_level = r.run_level = r.min_creep_level = std::llabs(velocity);
  r.accel_ticks_per_level = r.decel_ticks_per_level = motion::Rational{1, 1};
  csv_running_ = core_.start(*this, r, sign(velocity), std::nullopt, now);
  if (csv_running_) watch_limit(sign(velocity), 0, static_cast<double>(std::llabs(velocity)), now);
}

void Drive::ramp_from_cyclic(Tick now) {
  if (!cyclic(mode_display_) || !core_.owned_by(*this) || !core_.moving()) return;
  const motion::StepGenerator& g = core_.generator();
  if (own_ramp_ || g.stopping()) return;  // already on a stop ramp, on its profile's grid
  // The job at its velocity without an end (CSP's segment end given up), then on PV's grid:
  // the velocity to 1/grid_ step/s, the phase kept (no step gained or lost), and 6084h as
  // the ramp down (6085h: quick_stop_slope() on the same grid). A trapezoid: the cyclic
  // modes keep theirs (6086h is PP's and PV's).
  core_.set_level(now, g.level());
  const int64_t acc = std::max<uint32_t>(parameters_.acceleration, 1);
  const int64_t dec = std::max<uint32_t>(parameters_.deceleration, 1);
  grid_ = motion::profile_levels_per_hz(std::max(acc, dec));
  const int64_t v = std::max<int64_t>(std::llround(g.velocity()), 1);
  core_.regrid(now, motion::profile_ramp(v, acc, dec, grid_));
  csv_running_ = false;
  own_ramp_ = true;
  // The ramp ends on or before 607Dh (CSP's targets are inside, its ramp may overrun them).
  watch_limit(g.direction(), 0, static_cast<double>(v), now);
}

int64_t Drive::cyclic_demand(Tick now) const {
  // Where the interpolated trajectory is at `now` (6062h in CSP and IP).
  if (now >= seg_start_ + seg_ticks_) return seg_to_;
  if (now <= seg_start_) return seg_from_;
  const __int128 done = static_cast<__int128>(seg_to_ - seg_from_) * (now - seg_start_);
  return seg_from_ + static_cast<int64_t>(done / seg_ticks_);
}

}  // namespace stepnode::cia402
