// The pulse engine's fixed timebase: the 4.9152 MHz clock of the Horner modules. Every step
// time is an integer number of ticks; nothing is rounded per step, so nothing drifts.
#pragma once
#include <cstdint>

namespace stepnode::motion {

using Tick = int64_t;

constexpr int64_t kClockHz = 4'915'200;

// 1 tick = 1e9 / 4915200 ns = 1953125 / 9600 ns (exact rational).
constexpr int64_t ticks_to_ns(Tick t) { return (t * 1'953'125 + 4'800) / 9'600; }
constexpr Tick ns_to_ticks(int64_t ns) { return (ns * 9'600) / 1'953'125; }
constexpr double ticks_to_ms(Tick t) { return static_cast<double>(t) * 1000.0 / kClockHz; }

}  // namespace stepnode::motion
