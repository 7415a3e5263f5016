// A received frame's kernel timestamp (SO_TIMESTAMPNS, on CLOCK_REALTIME) on the loop's
// CLOCK_MONOTONIC: when the frame reached the socket, not when the process read it (issue
// 13: a SYNC samples every node on the bus at the same instant, a TRIG SYS starts every
// node's axes together).
//
// The two clocks are tied by one reading of both. A process preempted between the reads
// (another node's process handling the same SYNC, on a loaded host or in User-Mode Linux,
// where a clock read is a system call) would tie them wrongly by the time it was away and
// date every frame that much early. So the reading is bracketed by two reads of
// CLOCK_MONOTONIC and taken again when they lie far apart.
#pragma once
#include <cstdint>
#include <functional>

namespace stepnode::canio {

// CLOCK_MONOTONIC before, CLOCK_REALTIME, CLOCK_MONOTONIC after, in ns.
struct ClockReading {
  int64_t mono_before_ns = 0, real_ns = 0, mono_after_ns = 0;
};

// A bracket this narrow ties the clocks to within half of it, far below a tick (1 ms).
constexpr int64_t kTightBracketNs = 100'000;
// Readings tried for a tight bracket; then the tightest of them.
constexpr int kClockTries = 3;
// A stamp older than this is not a frame's age but a step of the wall clock: now.
constexpr uint64_t kOldestArrivalUs = 100'000;

// CLOCK_REALTIME - CLOCK_MONOTONIC in ns from `read` (the system clocks by default).
int64_t realtime_offset_ns(const std::function<ClockReading()>& read = {});

// `kernel_time_ns` (CLOCK_REALTIME) on CLOCK_MONOTONIC in us with `offset_ns` from
// realtime_offset_ns(); `now_us` where there is no stamp (0), or it is later than now or
// older than kOldestArrivalUs.
uint64_t arrival_us(uint64_t kernel_time_ns, int64_t offset_ns, uint64_t now_us);

}  // namespace stepnode::canio
