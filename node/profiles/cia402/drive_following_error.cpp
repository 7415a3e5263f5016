// The following error of CSP and IP (CiA 402-2 "Position control function": 60F4h, 6065h,
// 6066h): the demand (6062h, the interpolated segment) minus the actual position; outside
// the window 6065h for longer than the time-out 6066h it is statusword bit 13 and a fault
// (8611h).
//
// Issue 13: the drive is not polled for it. Within a segment both positions are known
// functions of the tick: the demand is from + floor(d x / c) after x ticks of the cycle c
// (d steps to go), the actual position from + floor(n x / c) while the segment's n steps
// run (the engine gives step i at ceil(i c / n), drive_cyclic.cpp). So the tick at which
// the error first leaves the window is computed, not sampled: it is the drive's deadline.
// Whether it came back (at a step) is looked at when the node runs (a SYNC, a frame, the
// steps' wake-ups, the time-out), as before: a SYNC's segment starts again from the actual
// position, so the demand falls back each cycle, and looking at every step would let a
// lagging axis hide its lag in that fall.
#include <algorithm>
#include <cstdlib>
#include <limits>

#include "node/profiles/cia402/drive.hpp"

namespace stepnode::cia402 {

using motion::Tick;

namespace {

constexpr uint16_t kFollowingErrorCode = 0x8611;  // CiA 402: following error

// ceil(a / b) for a >= 0, b > 0, without overflow for a segment's sizes (a*c fits in 128).
Tick ceil_div(__int128 a, __int128 b) { return static_cast<Tick>((a + b - 1) / b); }

}  // namespace

bool Drive::following_position() const {
  // Not on the drive's own stop ramp (a halt's, a mode change's): the ramp is the demand.
  return machine_.operation_enabled() && !own_ramp_ &&
         (mode_display_ == Mode::CyclicSyncPosition || mode_display_ == Mode::InterpolatedPosition);
}

bool Drive::following_error_watched() const {
  return following_position() && parameters_.following_error_window != UINT32_MAX;
}

std::optional<Tick> Drive::following_error_exit(Tick after) const {
  if (!following_error_watched()) return std::nullopt;
  const int64_t w = parameters_.following_error_window;
  const int64_t d = std::llabs(seg_to_ - seg_from_);
  const int sign = seg_to_ < seg_from_ ? -1 : +1;
  const Tick c = seg_ticks_;
  const Tick x_min = std::max<Tick>(after + 1 - seg_start_, 0);
  // The first x in [lo, hi) at which the demand is w + 1 beyond an actual position j steps
  // into the segment: the demand reaches j + w + 1 at ceil((j + w + 1) c / d), and never
  // beyond d.
  const auto leaves = [&](int64_t j, Tick lo, Tick hi) -> std::optional<Tick> {
    if (j + w + 1 > d) return std::nullopt;
    const Tick x = std::max({lo, x_min, ceil_div(__int128{j + w + 1} * c, d)});
    if (x >= hi) return std::nullopt;
    return seg_start_ + x;
  };
  const int64_t n = seg_steps_;
  if (!(core_.owned_by(*this) && core_.moving()) || n <= 0) {
    // No step to come: the actual position stays where it is.
    const int64_t k = std::max<int64_t>((core_.position() - seg_from_) * sign, 0);
    return leaves(k, 0, std::numeric_limits<Tick>::max());
  }
  if (d <= n) return std::nullopt;  // the steps keep up: demand and actual stay equal
  // Position j holds from step j, at ceil(j c / n), to step j + 1; after the last: for ever.
  // Below j = floor(n w / (d - n)) the demand cannot get w + 1 ahead before step j + 1.
  const int64_t j_now = x_min >= c ? n : static_cast<int64_t>(__int128{n} * x_min / c);
  for (int64_t j = std::max<int64_t>(j_now, n * w / (d - n)); j <= n; ++j) {
    const Tick lo = ceil_div(__int128{j} * c, n);
    const Tick hi = j < n ? ceil_div(__int128{j + 1} * c, n) : std::numeric_limits<Tick>::max();
    if (const std::optional<Tick> at = leaves(j, lo, hi)) return at;
  }
  return std::nullopt;
}

void Drive::track_following_error(Tick at) {
  following_error_value_ =
      following_position() ? static_cast<int32_t>(cyclic_demand(at) - core_.position()) : 0;
  const bool outside =
      parameters_.following_error_window != UINT32_MAX &&
      std::llabs(int64_t{following_error_value_}) > int64_t{parameters_.following_error_window};
  if (!outside) {
    following_error_since_.reset();
    following_error_ = false;
  } else if (!following_error_since_) {
    // It left the window since the last check, at the tick the trajectory says.
    const std::optional<Tick> left = following_error_exit(following_error_checked_);
    following_error_since_ = left && *left <= at ? *left : at;
  }
  following_error_checked_ = at;
}

void Drive::check_following_error(Tick now) {
  track_following_error(now);
  // 60F4h beyond 6065h for longer than 6066h: bit 13, and a fault (8611h).
  const Tick timeout = Tick{parameters_.following_error_timeout_ms} * motion::kClockHz / 1000;
  if (following_error_since_ && !following_error_ && now - *following_error_since_ >= timeout) {
    following_error_ = true;
    carry_out(machine_.fault(kFollowingErrorCode), now);
  }
}

}  // namespace stepnode::cia402
