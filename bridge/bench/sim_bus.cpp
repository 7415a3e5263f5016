#include "bridge/bench/sim_bus.hpp"

#include <chrono>
#include <string>

#include "bridge/bench/can_bit_length.hpp"
#include "node/device.hpp"

namespace stepnode::bridge::sim {
namespace {

// The kernel timestamp the bridge sees: CLOCK_REALTIME; any fixed epoch will do here.
constexpr uint64_t kRealtimeEpochNs = 1'700'000'000ull * 1'000'000'000ull;

// Host time spent in one observer call, for the CPU figure.
struct Timed {
  Timed(SimBusStats& s, void (*scope)(bool))
      : stats(s), scope(scope), start(std::chrono::steady_clock::now()) {
    if (scope) scope(true);
  }
  ~Timed() {
    if (scope) scope(false);
    ++stats.observer_calls;
    stats.observer_ns += static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                   std::chrono::steady_clock::now() - start)
                                                   .count());
  }
  SimBusStats& stats;
  void (*scope)(bool);
  std::chrono::steady_clock::time_point start;
};

}  // namespace

SimBus::SimBus(SimBusOptions options, SampleSink& sink)
    : options_(std::move(options)),
      observer_(sink, options_.observer),
      stations_(options_.nodes + 1),
      random_(options_.seed ? options_.seed : 1) {
  stats_.requests_to.assign(options_.nodes + 1, 0);
  for (unsigned id = 1; id <= options_.nodes; ++id) {
    node::NodeOptions o;
    o.device.node_id = static_cast<uint8_t>(id);
    o.layout.axes = options_.axes;
    o.state_dir = options_.state_dir;
    const node::Device::ObjectDefaults defaults = {{"1017", std::to_string(options_.heartbeat_ms)}};
    Station& s = stations_[id];
    s.device = std::make_unique<node::Device>(
        o, defaults, [&s](const od::CanFrame& f) { s.queue.push_back(f); });
    s.boot_at_ns = options_.boot_spread_us ? next_random() % options_.boot_spread_us * 1000 : 0;
  }
}

SimBus::~SimBus() = default;

// A 64-bit linear congruential generator (Knuth's MMIX constants), its high bits used.
uint64_t SimBus::next_random() {
  random_ = random_ * 6364136223846793005ull + 1442695040888963407ull;
  return random_ >> 11;
}

bool SimBus::lost() {
  return options_.loss > 0 && static_cast<double>(next_random()) * 0x1.0p-53 < options_.loss;
}

bool SimBus::step() {
  const uint64_t tick = std::min(next_node_tick_ns_, next_bridge_tick_ns_);
  if (busy_ && on_air_end_ns_ <= tick) {
    now_ns_ = on_air_end_ns_;
    busy_ = false;
    const od::CanFrame frame = on_air_;
    deliver(on_air_station_, frame);
    arbitrate();
    return false;
  }
  now_ns_ = tick;
  const bool bridge = next_bridge_tick_ns_ == tick;
  if (next_node_tick_ns_ == tick) {
    tick_nodes();
    next_node_tick_ns_ += options_.node_tick_us * 1000;
  }
  if (bridge) {
    tick_bridge();
    next_bridge_tick_ns_ += options_.bridge_tick_us * 1000;
  }
  arbitrate();
  return bridge;
}

void SimBus::arbitrate() {
  if (busy_) return;
  unsigned winner = 0;
  bool any = false;
  for (unsigned i = 0; i < stations_.size(); ++i) {
    const auto& q = stations_[i].queue;
    if (q.empty()) continue;
    if (!any || q.front().id < stations_[winner].queue.front().id) winner = i;
    any = true;
  }
  if (!any) return;
  on_air_ = stations_[winner].queue.front();
  stations_[winner].queue.pop_front();
  on_air_station_ = winner;
  const uint64_t bits = can_frame_bits(on_air_);
  const uint64_t duration_ns = bits * 1'000'000'000ull / options_.bit_rate;
  on_air_end_ns_ = now_ns_ + duration_ns;
  busy_ = true;
  ++stats_.frames;
  stats_.busy_ns += duration_ns;
}

void SimBus::deliver(unsigned sender, const od::CanFrame& frame) {
  const uint64_t now_us = now_ns_ / 1000;
  for (unsigned i = 1; i < stations_.size(); ++i) {
    Station& s = stations_[i];
    if (i == sender || !s.booted || !passes_filter(i, frame)) continue;
    if (lost()) {
      ++stats_.dropped;
      continue;
    }
    s.device->on_frame(frame, now_us, now_us);
  }
  if (sender == 0) return;  // SocketCAN does not loop a frame back to the sending socket
  if (lost()) {
    ++stats_.dropped;
    return;
  }
  ObservedFrame of;
  of.frame = frame;
  of.can_time_ns = kRealtimeEpochNs + now_ns_;
  {
    Timed t(stats_, options_.observer_scope);
    observer_.on_frame(of, now_us, out_);
  }
  bridge_sent(out_);
}

bool SimBus::passes_filter(unsigned node, const od::CanFrame& f) const {
  if (!options_.node_filters) return true;
  constexpr uint32_t kLssMasterToSlave = 0x7E5;  // CiA 305
  if (f.id == od::cob::kNmt || f.id == od::cob::kSync || f.id == od::cob::kTimeStamp ||
      f.id == kLssMasterToSlave)
    return true;
  return (f.id & 0x7F) == node;
}

void SimBus::tick_nodes() {
  const uint64_t now_us = now_ns_ / 1000;
  for (unsigned i = 1; i < stations_.size(); ++i) {
    Station& s = stations_[i];
    if (!s.booted && now_ns_ >= s.boot_at_ns) {
      s.booted = true;
      s.device->start(now_us);
    }
    if (s.booted) s.device->on_tick(now_us);
  }
}

void SimBus::tick_bridge() {
  const uint64_t before = stats_.observer_ns;
  {
    Timed t(stats_, options_.observer_scope);
    observer_.on_tick(now_ns_ / 1000, kRealtimeEpochNs + now_ns_, out_);
  }
  ++stats_.observer_ticks;
  stats_.observer_tick_ns += stats_.observer_ns - before;
  bridge_sent(out_);
}

void SimBus::bridge_sent(std::vector<od::CanFrame>& out) {
  for (const od::CanFrame& f : out) {
    ++stats_.bridge_frames;
    const uint32_t node = f.id - od::cob::kSdoRx;
    if (f.id > od::cob::kSdoRx && node < stats_.requests_to.size()) ++stats_.requests_to[node];
    stations_[0].queue.push_back(f);
  }
  out.clear();
}

bool SimBus::all_discovered() const { return discovered() == options_.nodes; }

unsigned SimBus::discovered() const {
  unsigned n = 0;
  for (unsigned id = 1; id <= options_.nodes; ++id)
    n += observer_.node_health(static_cast<uint8_t>(id), now_ns_ / 1000).discovered ? 1 : 0;
  return n;
}

}  // namespace stepnode::bridge::sim
