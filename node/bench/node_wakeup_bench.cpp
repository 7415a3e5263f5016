// The node's wake-ups per second and CPU share (issue 13): the real device (node/device.*,
// as node/main.cpp builds it) on CLOCK_MONOTONIC, woken either every 1 ms as the process was
// before issue 13 (--mode tick) or at its own earliest deadline as node/main.cpp does now
// (--mode event, bounded by --tick-us). No CAN socket: frames go to a counter. Scenarios:
// idle with a 1000 ms heartbeat, idle without one, and three axes jogging at 81,910 steps/s
// each (245,730 steps/s in total), at the step port horizon --horizon-us. Issue 13's
// formerly polled parts, each with the heartbeat off: sdo-open (a segmented SDO download
// left open, a 10 s SDO timeout), hp-delay (an HP MOVE triggered with DELAY 10), cia402-idle
// (three CiA 402 drives in operation enabled, standing), cia402-pp (the three in a PP move
// at 81,910 steps/s each). Prints figures; asserts nothing.
//   build/node/node_wakeup_bench [--mode event|tick] [--scenario idle-hb|idle|moving|sdo-open|
//                                hp-delay|cia402-idle|cia402-pp] [--seconds 5]
//                                [--tick-us 1000000] [--horizon-us 0]
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
#include "node/profiles/cia402/objects.hpp"
#include "node/profiles/horner/objects.hpp"
#include "node/profiles/hp44714a/objects.hpp"
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

// HP 44714A channel 1: DELAY 10 / TRIG HOLD / MOVE 20 NOWAIT / TRIG: the delay runs.
void start_hp_delay(od::Dictionary& od) {
  using namespace hp44714a::obj;
  write(od, index(0, kDelay), 0, od::encode<uint16_t>(10'000));
  write(od, index(0, kTrig), 0, {0});
  write(od, index(0, kMove), hp44714a::move_sub::kNowait, {1});
  write(od, index(0, kMove), hp44714a::move_sub::kRelative, od::encode<double>(20.0));
  write(od, index(0, kTrig), 0, {2});
}

// Three CiA 402 drives through shutdown, switch on, enable operation; with `move`, each in
// a PP move at 81,910 steps/s long enough for the run.
void start_drives(od::Dictionary& od, bool move) {
  using namespace cia402::obj;
  for (unsigned a = 0; a < 3; ++a) {
    write(od, index(a, kModesOfOperation), 0,
          {static_cast<uint8_t>(cia402::mode::kProfilePosition)});
    for (uint16_t cw : {0x0006, 0x0007, 0x000F})
      write(od, index(a, kControlword), 0, od::encode<uint16_t>(cw));
    if (!move) continue;
    // No limit switches: the move runs for the whole run, as the jogs do.
    write(od, sim::obj::index(a, sim::obj::kSwitches), sim::switches_sub::kLowerLimitEnabled, {0});
    write(od, sim::obj::index(a, sim::obj::kSwitches), sim::switches_sub::kUpperLimitEnabled, {0});
    write(od, index(a, kMaxProfileVelocity), 0, od::encode<uint32_t>(81'910));
    write(od, index(a, kProfileVelocity), 0, od::encode<uint32_t>(81'910));
    write(od, index(a, kProfileAcceleration), 0, od::encode<uint32_t>(1'000'000));
    write(od, index(a, kProfileDeceleration), 0, od::encode<uint32_t>(1'000'000));
    write(od, index(a, kTargetPosition), 0, od::encode<int32_t>(5'000'000));
    write(od, index(a, kControlword), 0, od::encode<uint16_t>(0x001F));  // new set-point
    write(od, index(a, kControlword), 0, od::encode<uint16_t>(0x000F));
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
  const bool cia402 = args.scenario.rfind("cia402", 0) == 0;
  if (cia402)
    options.layout = node::DeviceLayout{.axes = 3,
                                        .horner = false,
                                        .hp = false,
                                        .user = false,
                                        .cia402 = true,
                                        .step_horizon_us = args.horizon_us};
  options.sdo_timeout_us = 10'000'000;  // sdo-open: the transfer stays open for the run
  options.state_dir = std::filesystem::temp_directory_path() / "stepnode-wakeup-bench";
  uint64_t frames = 0;
  node::Device device(options, {}, [&frames](const od::CanFrame&) { ++frames; });
  const uint64_t t0 = now_us();
  device.start(t0);
  device.on_frame(od::CanFrame(0, {0x01, 0}), t0);  // NMT start: TPDOs flow as on a bus
  od::Dictionary& od = device.dictionary();
  write(od, 0x1017, 0, od::encode<uint16_t>(args.scenario == "idle-hb" ? 1000 : 0));
  if (args.scenario == "moving") start_jogs(od);
  if (args.scenario == "hp-delay") start_hp_delay(od);
  if (cia402) start_drives(od, args.scenario == "cia402-pp");
  if (args.scenario == "sdo-open")  // initiate a segmented download of 0x1017 (size 2)
    device.on_frame(od::CanFrame(0x600 + options.device.node_id, {0x21, 0x17, 0x10, 0, 2, 0, 0, 0}),
                    now_us());
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
  for (unsigned a = 0; a < 3; ++a) steps += std::llabs(device.machine().axes[a].position());
  std::printf("mode %s, scenario %s, step horizon %u us\n", args.mode.c_str(),
              args.scenario.c_str(), args.horizon_us);
  std::printf("wakeups_per_second   %.1f\n", static_cast<double>(wakeups) / wall);
  std::printf("cpu_share_percent    %.2f  (of one core)\n", 100.0 * cpu / wall);
  std::printf("steps generated      %lld (%.0f steps/s in total), frames sent %llu\n",
              static_cast<long long>(steps), static_cast<double>(steps) / wall,
              static_cast<unsigned long long>(frames));
  return 0;
}
