#include "canio/arrival_clock.hpp"

#include <ctime>

namespace stepnode::canio {
namespace {

int64_t ns_of(clockid_t clock) {
  timespec ts{};
  ::clock_gettime(clock, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

ClockReading read_system_clocks() {
  ClockReading r;
  r.mono_before_ns = ns_of(CLOCK_MONOTONIC);
  r.real_ns = ns_of(CLOCK_REALTIME);
  r.mono_after_ns = ns_of(CLOCK_MONOTONIC);
  return r;
}

}  // namespace

int64_t realtime_offset_ns(const std::function<ClockReading()>& read) {
  ClockReading best;
  int64_t best_width = INT64_MAX;
  for (int i = 0; i < kClockTries && best_width > kTightBracketNs; ++i) {
    const ClockReading r = read ? read() : read_system_clocks();
    const int64_t width = r.mono_after_ns - r.mono_before_ns;
    if (width < best_width) best = r, best_width = width;
  }
  // The realtime read lies somewhere in the bracket: its middle errs by half its width.
  return best.real_ns - (best.mono_before_ns + best_width / 2);
}

uint64_t arrival_us(uint64_t kernel_time_ns, int64_t offset_ns, uint64_t now_us) {
  if (kernel_time_ns == 0) return now_us;
  const int64_t mono_ns = static_cast<int64_t>(kernel_time_ns) - offset_ns;
  if (mono_ns < 0) return now_us;
  const uint64_t at = static_cast<uint64_t>(mono_ns) / 1000;
  if (at > now_us || now_us - at > kOldestArrivalUs) return now_us;  // the wall clock stepped
  return at;
}

}  // namespace stepnode::canio
