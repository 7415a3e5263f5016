// Many nodes in one process (issue 13): `--nodes` nodes (default 127, ids 1..N) with a
// 100 ms heartbeat (0x1017 from the defaults, as a config's [defaults] sets it) in one
// NodeSet, woken as node/node_process.cpp wakes it: one canio::EventLoop timerfd armed for
// the earliest deadline of all nodes. No CAN socket: the frames the process sends are
// stamped on CLOCK_MONOTONIC as they leave and the heartbeat periods are measured on them.
// Prints figures; asserts nothing.
//   build/node/multi_node_bench [--nodes 127] [--seconds 10] [--operational] [--consumers]
//   build/node/multi_node_bench --virtual [--seconds 60]   (virtual time, for callgrind:
//     valgrind --tool=callgrind build/node/multi_node_bench --virtual --seconds 60)
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "canio/event_loop.hpp"
#include "node/bench/bench_clock.hpp"
#include "node/node_id_list.hpp"
#include "node/node_set.hpp"

using namespace stepnode;

namespace {

constexpr uint64_t kPeriodUs = 100'000;

struct Args {
  unsigned nodes = 127;
  double seconds = 10;
  bool virtual_time = false;
  bool operational = false;
  bool consumers = false;  // every node watches node 1's heartbeat (0x1016:1, 150 ms)
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (k == "--nodes" && i + 1 < argc) a.nodes = static_cast<unsigned>(std::atoi(argv[++i]));
    else if (k == "--seconds" && i + 1 < argc) a.seconds = std::atof(argv[++i]);
    else if (k == "--virtual") a.virtual_time = true;
    else if (k == "--operational") a.operational = true;
    else if (k == "--consumers") a.consumers = true;
    else {
      std::fprintf(stderr,
                   "usage: multi_node_bench [--nodes 1..127] [--seconds S] [--virtual] "
                   "[--operational] [--consumers]\n");
      std::exit(2);
    }
  }
  if (a.nodes < 1 || a.nodes > 127 || a.seconds <= 0) std::exit(2);
  return a;
}

// Each node's heartbeat send times, and from them the period errors |interval - 100 ms|.
struct HeartbeatLog {
  std::vector<std::vector<uint64_t>> at = std::vector<std::vector<uint64_t>>(128);
  uint64_t frames = 0;

  void record(const od::CanFrame& f, uint64_t now) {
    ++frames;
    if (f.id > 0x700 && f.id <= 0x77F && f.dlc == 1 && f.data[0] != 0)
      at[f.id - 0x700].push_back(now);
  }
  void print() const {
    std::vector<double> errors_ms;
    for (const auto& times : at)
      for (size_t i = 1; i < times.size(); ++i) {
        const double interval = static_cast<double>(times[i] - times[i - 1]);
        errors_ms.push_back(std::abs(interval - static_cast<double>(kPeriodUs)) / 1000.0);
      }
    if (errors_ms.empty()) return;
    std::sort(errors_ms.begin(), errors_ms.end());
    std::printf(
        "  heartbeat periods: %zu, error |period - 100 ms| median %.3f ms, p99 %.3f ms, "
        "max %.3f ms\n",
        errors_ms.size(), errors_ms[errors_ms.size() / 2], errors_ms[errors_ms.size() * 99 / 100],
        errors_ms.back());
  }
};

double rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;  // KiB on Linux
}

std::filesystem::path temp_state_dir() {
  std::string tmpl = (std::filesystem::temp_directory_path() / "multi-node-bench-XXXXXX").string();
  if (!::mkdtemp(tmpl.data())) std::exit(1);
  return tmpl;
}

std::vector<node::NodeOptions> options(const Args& a, const std::filesystem::path& dir) {
  node::NodeOptions base;
  base.layout.axes = 1;
  base.state_dir = dir;
  base.device.serial_number = 1;
  return node::options_per_node(base, node::parse_node_id_list("1-" + std::to_string(a.nodes)));
}

// 0x1017 = 100 ms; with --consumers 0x1016:1 = node 1, 150 ms (a master's 1.5x): node 1's
// heartbeats then reach the 126 other nodes of the process by local delivery.
node::Device::ObjectDefaults defaults(const Args& a) {
  node::Device::ObjectDefaults d{{"1017", std::to_string(kPeriodUs / 1000)}};
  if (a.consumers) d.emplace_back("1016:1", "0x00010096");
  return d;
}

// Power-on, then (--operational) NMT start of all nodes: how long that one frame takes
// (every node enters OPERATIONAL and sends its TPDOs) and how many frames it causes.
void start_all(node::NodeSet& set, const Args& a, uint64_t now, HeartbeatLog& log) {
  set.start(now);
  if (!a.operational) return;
  const uint64_t frames = log.frames;
  const uint64_t begin = canio::EventLoop::now_us();
  set.on_frame(od::CanFrame(0x000, {0x01, 0}), now);  // NMT start all
  std::printf("  NMT start of all nodes: %llu us, %llu frames sent\n",
              static_cast<unsigned long long>(canio::EventLoop::now_us() - begin),
              static_cast<unsigned long long>(log.frames - frames));
  // A node sends a heartbeat at once when its state changes: periods count from there.
  for (auto& times : log.at) times.clear();
}

// Real clock: the event loop of node/node_process.cpp without the socket.
void run_real(const Args& a, const std::filesystem::path& dir) {
  HeartbeatLog log;
  node::NodeSet set(options(a, dir), defaults(a), [&log](const od::CanFrame& f) {
    log.record(f, canio::EventLoop::now_us());
    return true;
  });
  canio::EventLoop loop;
  int timer = -1;
  const uint64_t begin = canio::EventLoop::now_us();
  const uint64_t end = begin + static_cast<uint64_t>(a.seconds * 1e6);
  auto arm = [&] { loop.arm_at(timer, std::min(set.next_deadline_us(), end)); };
  std::vector<uint64_t> busy_us;  // how long each wake-up that sent something took
  timer = loop.add_timer([&] {
    const uint64_t now = canio::EventLoop::now_us();
    if (now >= end) return loop.stop();
    const uint64_t frames = log.frames;
    set.on_tick(now);
    if (log.frames != frames) busy_us.push_back(canio::EventLoop::now_us() - now);
    arm();
  });
  const double cpu0 = bench::cpu_seconds();
  start_all(set, a, begin, log);
  arm();
  loop.run();
  const double wall = static_cast<double>(canio::EventLoop::now_us() - begin) / 1e6;
  const double cpu = bench::cpu_seconds() - cpu0;
  std::printf(
      "multi_node_bench: %u nodes in one process, heartbeat 100 ms, %s, %.1f s real "
      "clock\n",
      a.nodes, a.operational ? "operational" : "pre-operational", wall);
  log.print();
  std::printf("  CPU share %.3f %% (user+system / wall), max RSS %.1f MiB\n", 100 * cpu / wall,
              rss_mib());
  std::sort(busy_us.begin(), busy_us.end());
  if (!busy_us.empty())
    std::printf("  a wake-up that sends heartbeats: median %llu us, max %llu us\n",
                static_cast<unsigned long long>(busy_us[busy_us.size() / 2]),
                static_cast<unsigned long long>(busy_us.back()));
  std::printf("  wake-ups %.1f /s, frames sent %.1f /s, local deliveries %.1f /s\n",
              static_cast<double>(loop.wakeups()) / wall, static_cast<double>(log.frames) / wall,
              static_cast<double>(set.local_deliveries()) / wall);
}

// Virtual time: the same set woken at its deadlines; the instructions callgrind counts are
// the process's work per second of bus time, free of this machine's noise.
void run_virtual(const Args& a, const std::filesystem::path& dir) {
  HeartbeatLog log;
  uint64_t t = 1'000'000;
  node::NodeSet set(options(a, dir), defaults(a), [&](const od::CanFrame& f) {
    log.record(f, t);
    return true;
  });
  start_all(set, a, t, log);
  const uint64_t end = t + static_cast<uint64_t>(a.seconds * 1e6);
  uint64_t wakeups = 0;
  for (uint64_t next = set.next_deadline_us(); next <= end; next = set.next_deadline_us()) {
    t = std::max(t, next);
    set.on_tick(t);
    ++wakeups;
  }
  std::printf("multi_node_bench: %u nodes, heartbeat 100 ms, %s, %.1f s virtual time\n", a.nodes,
              a.operational ? "operational" : "pre-operational", a.seconds);
  log.print();
  std::printf("  wake-ups %.1f /s of bus time, frames sent %.1f /s, local deliveries %.1f /s\n",
              static_cast<double>(wakeups) / a.seconds, static_cast<double>(log.frames) / a.seconds,
              static_cast<double>(set.local_deliveries()) / a.seconds);
}

}  // namespace

int main(int argc, char** argv) {
  const Args a = parse(argc, argv);
  const std::filesystem::path dir = temp_state_dir();
  if (a.virtual_time) run_virtual(a, dir);
  else run_real(a, dir);
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  return 0;
}
