// The node's wake-ups per second and CPU share (issue 13): the real device (node/device.*,
// as node/main.cpp builds it) on CLOCK_MONOTONIC, woken either every 1 ms as the process was
// before issue 13 (--mode tick) or at its own earliest deadline as node/main.cpp does now
// (--mode event, bounded by --tick-us). No CAN socket: frames go to a counter. Scenarios:
// idle with a 1000 ms heartbeat, idle without one, and three axes jogging at 81,910 steps/s
// each (245,730 steps/s in total), at the step port horizon --horizon-us. Prints figures;
// asserts nothing.
//   build/node/node_wakeup_bench [--mode event|tick] [--scenario idle-hb|idle|moving]
//                                [--seconds 5] [--tick-us 1000000] [--horizon-us 0]
#include <sys/resource.h>
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include "node/bench/bench_clock.hpp"
#include "node/device.hpp"
#include "node/profiles/horner/objects.hpp"
#include "node/profiles/sim/objects.hpp"

using namespace stepnode;

namespace {

using bench::cpu_seconds;
using bench::now_us;

void sleep_until(uint64_t at_us) {
  timespec ts{static_cast<time_t>(at_us / 1'000'000), static_cast<long>(at_us % 1'000'000 * 1000)};
  clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
}

void write(od::Dictionary& od, uint16_t index, uint8_t sub, od::Bytes v) {
  if (od.write(index, sub, v) != od::SdoAbort::None) {
    std::fprintf(stderr, "write %04X:%02X refused\n", index, sub);
    std::exit(1);
  }
}

// Three axes jogging up at 81,910 steps/s each (velocity 8191 units of 10 steps/s).
void start_jogs(od::Dictionary& od) {
  using namespace horner::obj;
  for (unsigned a = 0; a < 3; ++a) {
    const uint16_t p = index(a, kProfile);
    write(od, p, horner::profile_sub::kVelocityDivisor, od::encode<uint16_t>(60));
    write(od, p, horner::profile_sub::kBaseVelocity, od::encode<uint16_t>(1));
    write(od, p, horner::profile_sub::kRunningVelocity, od::encode<uint16_t>(8191));
    write(od, p, horner::profile_sub::kAcceleration, od::encode<uint16_t>(100));
    write(od, sim::obj::index(a, sim::obj::kSwitches), sim::switches_sub::kLowerLimitEnabled, {0});
    write(od, sim::obj::index(a, sim::obj::kSwitches), sim::switches_sub::kUpperLimitEnabled, {0});
    write(od, index(a, kCommandBits), 0, od::encode<uint16_t>(1u << 13));  // clear errors
    write(od, index(a, kCommandBits), 0, od::encode<uint16_t>(0));
    write(od, index(a, kCommandBits), 0, od::encode<uint16_t>(1u << 5));  // jog up
  }
}

struct Args {
  std::string mode = "event", scenario = "idle-hb";
  double seconds = 5;
  uint64_t tick_us = 1'000'000;
  uint32_t horizon_us = 0;
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--mode")) a.mode = argv[i + 1];
    else if (!std::strcmp(argv[i], "--scenario")) a.scenario = argv[i + 1];
    else if (!std::strcmp(argv[i], "--seconds")) a.seconds = std::atof(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--tick-us"))
      a.tick_us = std::strtoull(argv[i + 1], nullptr, 10);
    else if (!std::strcmp(argv[i], "--horizon-us"))
      a.horizon_us = static_cast<uint32_t>(std::atoi(argv[i + 1]));
  }
  return a;
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse(argc, argv);
  node::NodeOptions options;
  options.layout.axes = 3;
  options.layout.step_horizon_us = args.horizon_us;
  options.state_dir = std::filesystem::temp_directory_path() / "stepnode-wakeup-bench";
  uint64_t frames = 0;
  node::Device device(options, {}, [&frames](const od::CanFrame&) { ++frames; });
  const uint64_t t0 = now_us();
  device.start(t0);
  device.on_frame(od::CanFrame(0, {0x01, 0}), t0);  // NMT start: TPDOs flow as on a bus
  od::Dictionary& od = device.dictionary();
  write(od, 0x1017, 0, od::encode<uint16_t>(args.scenario == "idle-hb" ? 1000 : 0));
  if (args.scenario == "moving") start_jogs(od);
  device.on_tick(now_us());

  const uint64_t start = now_us(), end = start + static_cast<uint64_t>(args.seconds * 1e6);
  const double cpu0 = cpu_seconds();
  uint64_t wakeups = 0, next = start;
  while (next < end) {
    if (args.mode == "tick") next += 1000;
    else next = std::min(device.next_deadline_us(now_us()), now_us() + args.tick_us);
    sleep_until(std::min(next, end));
    if (now_us() >= end) break;
    device.on_tick(now_us());
    ++wakeups;
  }
  const double wall = static_cast<double>(now_us() - start) / 1e6, cpu = cpu_seconds() - cpu0;
  int64_t steps = 0;
  for (unsigned a = 0; a < 3; ++a) steps += device.axes().axis(a).motor_position();
  std::printf("mode %s, scenario %s, step horizon %u us\n", args.mode.c_str(),
              args.scenario.c_str(), args.horizon_us);
  std::printf("wakeups_per_second   %.1f\n", static_cast<double>(wakeups) / wall);
  std::printf("cpu_share_percent    %.2f  (of one core)\n", 100.0 * cpu / wall);
  std::printf("steps generated      %lld (%.0f steps/s in total), frames sent %llu\n",
              static_cast<long long>(steps), static_cast<double>(steps) / wall,
              static_cast<unsigned long long>(frames));
  return 0;
}
