// The node's CPU share while three axes each run at 245,730 steps/s in real time: the real
// device (node/device.*, as node/main.cpp builds it), ticked every
// 1 ms on CLOCK_MONOTONIC exactly as the process does (no CAN socket: frames go to a
// counter). Prints the figures; asserts nothing.
//   build/node/node_cpu_bench [--seconds 10] [--tick-us 1000] [--virtual SECONDS]
#include <sys/resource.h>
#include <time.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "node/bench/bench_clock.hpp"
#include "node/device.hpp"
#include "node/profiles/horner/objects.hpp"
#include "node/profiles/sim/objects.hpp"

using namespace stepnode;

namespace {

using bench::cpu_seconds;
using bench::now_us;

void write(od::Dictionary& od, uint16_t index, uint8_t sub, od::Bytes v) {
  if (od.write(index, sub, v) != od::SdoAbort::None) {
    std::fprintf(stderr, "write %04X:%02X refused\n", index, sub);
    std::exit(1);
  }
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 10;
  // --virtual N: the same node ticked through N seconds of virtual time as fast as it
  // goes: deterministic, so `valgrind --tool=callgrind` counts the same instructions.
  double virtual_seconds = 0;
  uint64_t tick_us = 1000;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--seconds")) seconds = std::atof(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--tick-us")) tick_us = std::strtoull(argv[i + 1], nullptr, 10);
    else if (!std::strcmp(argv[i], "--virtual")) virtual_seconds = std::atof(argv[i + 1]);
  }
  node::NodeOptions options;
  options.layout.axes = 3;
  options.state_dir = std::filesystem::temp_directory_path() / "stepnode-bench";
  uint64_t frames = 0;
  node::Device device(options, {}, [&frames](const od::CanFrame&) { ++frames; });
  uint64_t t0 = now_us();
  device.start(t0);
  device.on_frame(od::CanFrame(0, {0x01, 0}), t0);  // NMT start: TPDOs flow as on a bus

  od::Dictionary& od = device.dictionary();
  using namespace horner::obj;
  for (unsigned a = 0; a < 3; ++a) {
    uint16_t p = index(a, kProfile);
    write(od, p, horner::profile_sub::kVelocityDivisor,
          od::encode<uint16_t>(20));  // 30 steps/s units
    write(od, p, horner::profile_sub::kBaseVelocity, od::encode<uint16_t>(1));
    write(od, p, horner::profile_sub::kRunningVelocity,
          od::encode<uint16_t>(8191));  // 245,730 steps/s
    write(od, p, horner::profile_sub::kAcceleration, od::encode<uint16_t>(100));
    write(od, sim::obj::index(a, sim::obj::kSwitches), sim::switches_sub::kLowerLimitEnabled, {0});
    write(od, sim::obj::index(a, sim::obj::kSwitches), sim::switches_sub::kUpperLimitEnabled, {0});
    write(od, index(a, kCommandBits), 0, od::encode<uint16_t>(1u << 13));  // clear errors
    write(od, index(a, kCommandBits), 0, od::encode<uint16_t>(0));
    write(od, index(a, kCommandBits), 0,
          od::encode<uint16_t>(1u << 5));  // jog up: runs until released
  }

  if (virtual_seconds > 0) {
    uint64_t t = t0, end = t0 + static_cast<uint64_t>(virtual_seconds * 1e6);
    while (t < end) device.on_tick(t += tick_us);
    int64_t steps = 0;
    for (unsigned a = 0; a < 3; ++a) steps += device.axes().axis(a).motor_position();
    std::printf(
        "virtual time         %.2f s\nsteps generated      %lld\nframes sent          %llu\n",
        virtual_seconds, static_cast<long long>(steps), static_cast<unsigned long long>(frames));
    return 0;
  }
  uint64_t start = now_us();
  double cpu0 = cpu_seconds();
  timespec next;
  clock_gettime(CLOCK_MONOTONIC, &next);
  uint64_t ticks = 0;
  while (now_us() - start < static_cast<uint64_t>(seconds * 1e6)) {
    next.tv_nsec += static_cast<long>(tick_us * 1000);
    while (next.tv_nsec >= 1'000'000'000) {
      next.tv_nsec -= 1'000'000'000;
      ++next.tv_sec;
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
    device.on_tick(now_us());
    ++ticks;
  }
  double wall = static_cast<double>(now_us() - start) / 1e6;
  double cpu = cpu_seconds() - cpu0;
  int64_t steps = 0;
  for (unsigned a = 0; a < 3; ++a) steps += device.axes().axis(a).motor_position();
  std::printf("axes                 3 (jogging at %.0f steps/s each)\n",
              device.axes().axis(0).velocity());
  std::printf("wall time            %.2f s, %llu ticks of %llu us\n", wall,
              static_cast<unsigned long long>(ticks), static_cast<unsigned long long>(tick_us));
  std::printf("steps generated      %lld (%.0f steps/s in total)\n", static_cast<long long>(steps),
              static_cast<double>(steps) / wall);
  std::printf("frames sent          %llu\n", static_cast<unsigned long long>(frames));
  std::printf("cpu_share_percent    %.1f  (of one core)\n", 100.0 * cpu / wall);
  return 0;
}
