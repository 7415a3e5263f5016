// The bridge discovering a full bus (issue 13), natively and in virtual time: 127 real
// nodes (node::Device) and the bridge's BusObserver on a simulated 500 kbit/s bus
// (bridge/bench/sim_bus.hpp), all powering up within 100 ms. Prints the virtual time until
// every node is discovered, the SDO frames the bridge sent per node, the retries, the bus
// load, the observer's host time and the memory it holds per node. Asserts nothing.
//   build/bridge/discovery_bench [--nodes 127] [--loss 0.01] [--seed 1] [--rate 1000]
//                                [--outstanding 8] [--bit-rate 500000] [--limit-s 600]
//                                [--node-tick-us 1000]   (10000: the nodes cost less under
//                                callgrind)
// The observer's instructions alone (deterministic, so the count repeats):
//   valgrind --tool=callgrind --toggle-collect='stepnode::bridge::BusObserver::on_*'
//            build/bridge/discovery_bench --nodes 127    (one line)
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <new>

#include <spdlog/spdlog.h>

#include "bridge/bench/sim_bus.hpp"

using namespace stepnode;

namespace {

// Heap bytes the observer holds: every allocation made inside an observer call is tagged
// in a header, so its release (wherever it happens) is counted against the same account.
thread_local bool g_inside_observer = false;
long long g_observer_bytes = 0;
constexpr size_t kHeader = alignof(std::max_align_t);

void observer_scope(bool inside) { g_inside_observer = inside; }

struct NullSink : bridge::SampleSink {
  unsigned long long samples = 0;
  void axis_status(const bridge::AxisStatusSample&) override { ++samples; }
  void axis_position(const bridge::AxisPositionSample&) override { ++samples; }
  void node_health(const bridge::NodeHealthSample&) override { ++samples; }
  void emergency(const bridge::EmergencySample&) override { ++samples; }
  void drive_status(const bridge::DriveStatusSample&) override { ++samples; }
  void dispose_axes(uint8_t, uint8_t) override {}
};

}  // namespace

void* operator new(size_t size) {
  auto* p = static_cast<unsigned char*>(std::malloc(size + kHeader));
  if (!p) throw std::bad_alloc();
  const size_t tagged = g_inside_observer ? size : 0;
  std::memcpy(p, &tagged, sizeof tagged);
  g_observer_bytes += static_cast<long long>(tagged);
  return p + kHeader;
}
void operator delete(void* q) noexcept {
  if (!q) return;
  auto* p = static_cast<unsigned char*>(q) - kHeader;
  size_t tagged = 0;
  std::memcpy(&tagged, p, sizeof tagged);
  g_observer_bytes -= static_cast<long long>(tagged);
  std::free(p);
}
void operator delete(void* q, size_t) noexcept { operator delete(q); }

int main(int argc, char** argv) {
  bridge::sim::SimBusOptions o;
  o.observer.sdo_max_outstanding = 8;  // stepbridge's defaults (bridge/config.hpp)
  o.observer.sdo_rate_per_s = 1000;
  uint64_t limit_s = 600;
  for (int i = 1; i + 1 < argc; i += 2) {
    const char* v = argv[i + 1];
    if (!std::strcmp(argv[i], "--nodes")) o.nodes = static_cast<unsigned>(std::atoi(v));
    else if (!std::strcmp(argv[i], "--loss")) o.loss = std::atof(v);
    else if (!std::strcmp(argv[i], "--seed")) o.seed = static_cast<uint32_t>(std::atoi(v));
    else if (!std::strcmp(argv[i], "--rate"))
      o.observer.sdo_rate_per_s = static_cast<uint32_t>(std::atoi(v));
    else if (!std::strcmp(argv[i], "--outstanding"))
      o.observer.sdo_max_outstanding = static_cast<uint32_t>(std::atoi(v));
    else if (!std::strcmp(argv[i], "--bit-rate")) o.bit_rate = static_cast<uint32_t>(std::atoi(v));
    else if (!std::strcmp(argv[i], "--limit-s")) limit_s = std::strtoull(v, nullptr, 10);
    else if (!std::strcmp(argv[i], "--node-tick-us"))
      o.node_tick_us = std::strtoull(v, nullptr, 10);
  }
  if (o.nodes < 1 || o.nodes > 127) {
    std::fprintf(stderr, "discovery_bench: --nodes must be 1..127\n");
    return 2;
  }
  o.state_dir = std::filesystem::temp_directory_path() / "stepnode-discovery-bench";
  std::filesystem::create_directories(o.state_dir);
  o.observer_scope = observer_scope;
  spdlog::set_level(spdlog::level::off);  // 127 nodes' start-up lines say nothing here

  NullSink sink;
  bridge::sim::SimBus bus(o, sink);
  const uint64_t t = bus.run(limit_s * 1'000'000, [&] { return bus.all_discovered(); });
  const bridge::sim::SimBusStats& s = bus.stats();

  uint64_t min = ~0ull, max = 0, total = 0, retries = 0;
  for (unsigned id = 1; id <= o.nodes; ++id) {
    min = std::min(min, s.requests_to[id]);
    max = std::max(max, s.requests_to[id]);
    total += s.requests_to[id];
    retries += bus.observer().node_health(static_cast<uint8_t>(id), bus.now_us()).sdo_failures;
  }
  std::printf(
      "nodes                    %u (%u axes each, heartbeat %u ms), %u bit/s, loss %.3f %%\n",
      o.nodes, o.axes, o.heartbeat_ms, o.bit_rate, 100 * o.loss);
  std::printf("node tick                %llu us, bridge tick %llu us\n",
              static_cast<unsigned long long>(o.node_tick_us),
              static_cast<unsigned long long>(o.bridge_tick_us));
  std::printf("pacing                   %u transfers in flight, %u starts/s\n",
              o.observer.sdo_max_outstanding, o.observer.sdo_rate_per_s);
  std::printf("discovered               %u of %u after %.3f s (virtual)\n", bus.discovered(),
              o.nodes, static_cast<double>(t) / 1e6);
  std::printf("sdo_requests_per_node    min %llu  mean %.1f  max %llu\n",
              static_cast<unsigned long long>(min), static_cast<double>(total) / o.nodes,
              static_cast<unsigned long long>(max));
  std::printf("retries                  %llu (failed transfers, each tried again)\n",
              static_cast<unsigned long long>(retries));
  std::printf("bus                      %llu frames, load %.1f %%, %llu deliveries dropped\n",
              static_cast<unsigned long long>(s.frames),
              100.0 * static_cast<double>(s.busy_ns) / (static_cast<double>(t) * 1e3),
              static_cast<unsigned long long>(s.dropped));
  std::printf("observer_host_time       %.1f ms in %llu calls (%.0f ns per call)\n",
              static_cast<double>(s.observer_ns) / 1e6,
              static_cast<unsigned long long>(s.observer_calls),
              static_cast<double>(s.observer_ns) / static_cast<double>(s.observer_calls));
  const uint64_t frame_calls = s.observer_calls - s.observer_ticks;
  std::printf(
      "observer_per_frame       %.0f ns (%llu frames); per tick %.0f ns (%llu ticks)\n",
      static_cast<double>(s.observer_ns - s.observer_tick_ns) / static_cast<double>(frame_calls),
      static_cast<unsigned long long>(frame_calls),
      static_cast<double>(s.observer_tick_ns) / static_cast<double>(s.observer_ticks),
      static_cast<unsigned long long>(s.observer_ticks));
  std::printf("observer_memory          %lld bytes (%.0f per node)\n", g_observer_bytes,
              static_cast<double>(g_observer_bytes) / o.nodes);
  return bus.all_discovered() ? 0 : 1;
}
