// The clocks the node benchmarks read: CLOCK_MONOTONIC for wall time and the process's
// CPU time (user + system), both as the node counts time (microseconds, seconds).
#pragma once
#include <sys/resource.h>
#include <time.h>

#include <cstdint>

namespace stepnode::bench {

inline uint64_t now_us() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1'000'000u + static_cast<uint64_t>(ts.tv_nsec) / 1000;
}

inline double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec) / 1e6;
}

}  // namespace stepnode::bench
