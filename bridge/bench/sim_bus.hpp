// A whole CAN network in one process and in virtual time, for the bridge at scale (issue
// 13): the real node (node::Device, as node/main.cpp builds it) once per node-ID, and the
// bridge's BusObserver, on one simulated bus. The bus is a broadcast medium of finite
// bandwidth: one frame at a time, each taking its exact bit length (can_bit_length.hpp)
// at the bit rate; when it is free, the lowest identifier waiting at any station wins the
// arbitration (CiA 301 relies on this priority). A frame that ends is delivered to every
// other station; `loss` drops a delivery to one receiver with that probability (a full
// receive queue, as SocketCAN drops them), deterministically from `seed`. Nodes are ticked
// as the node process ticks them, the observer as stepbridge does.
#pragma once
#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <vector>

#include "bridge/observer/bus_observer.hpp"
#include "od/can_frame.hpp"

namespace stepnode::node {
class Device;
}

namespace stepnode::bridge::sim {

struct SimBusOptions {
  unsigned nodes = 127;         // node-IDs 1..nodes
  unsigned axes = 3;            // per node (the node's default layout otherwise)
  uint32_t bit_rate = 500'000;  // bit/s
  double loss = 0.0;            // probability a delivery to a receiver is dropped
  uint32_t seed = 1;
  uint16_t heartbeat_ms = 100;        // every node's 0x1017
  uint64_t boot_spread_us = 100'000;  // nodes power up at random instants in this span
  uint64_t node_tick_us = 1000;       // node/main.cpp's tick
  uint64_t bridge_tick_us = 10'000;   // stepbridge's tick_ms
  std::filesystem::path state_dir;    // where the nodes would store parameters
  // Each node receives only the frames its kernel receive filter would pass (issue 13's
  // filters: the broadcast services NMT, SYNC, TIME, LSS, and every COB-ID whose low 7
  // bits are its node-ID, which covers its SDO, RPDOs, guarding and the node-ID check).
  // The bridge's figures barely change (127 nodes: all discovered after 7.16 s without,
  // 7.15 s with, in one measurement: a node's tick phase moves with the frames it handles); without
  // the filter today's node spends a full tick on each frame and the bench runs 6 times longer.
  bool node_filters = true;
  ObserverConfig observer;
  // Called with true before and false after every observer call (the bench counts the
  // memory the observer allocates with it).
  void (*observer_scope)(bool inside) = nullptr;
};

struct SimBusStats {
  std::vector<uint64_t> requests_to;  // SDO frames the bridge sent to node n (index n)
  uint64_t bridge_frames = 0;         // every frame the bridge sent
  uint64_t frames = 0;                // frames on the bus
  uint64_t busy_ns = 0;               // time the bus carried a frame
  uint64_t dropped = 0;               // deliveries dropped (loss)
  uint64_t observer_calls = 0;        // on_frame + on_tick calls of the observer
  uint64_t observer_ns = 0;           // host time spent in them (steady clock)
  uint64_t observer_ticks = 0;        // of which on_tick calls
  uint64_t observer_tick_ns = 0;      // and their time
};

class SimBus {
 public:
  SimBus(SimBusOptions options, SampleSink& sink);
  ~SimBus();
  SimBus(const SimBus&) = delete;
  SimBus& operator=(const SimBus&) = delete;

  // Runs virtual time until `done()` is true (checked every bridge tick) or `limit_us`
  // of virtual time passed. Returns the virtual time (us since the first power-up).
  template <class Done>
  uint64_t run(uint64_t limit_us, Done done) {
    while (now_ns_ < limit_us * 1000) {
      if (step() && done()) break;
    }
    return now_ns_ / 1000;
  }

  BusObserver& observer() { return observer_; }
  const SimBusStats& stats() const { return stats_; }
  uint64_t now_us() const { return now_ns_ / 1000; }
  bool all_discovered() const;
  unsigned discovered() const;

 private:
  struct Station {
    std::unique_ptr<node::Device> device;  // null: the bridge (station 0)
    std::deque<od::CanFrame> queue;        // frames waiting for the bus
    uint64_t boot_at_ns = 0;
    bool booted = false;
  };
  // One event: a frame's end, a node tick or a bridge tick, whichever is first. True when
  // it was a bridge tick.
  bool step();
  void arbitrate();
  void deliver(unsigned sender, const od::CanFrame& frame);
  void tick_nodes();
  void tick_bridge();
  void bridge_sent(std::vector<od::CanFrame>& out);
  bool lost();
  bool passes_filter(unsigned node, const od::CanFrame& frame) const;
  uint64_t next_random();

  SimBusOptions options_;
  BusObserver observer_;
  std::vector<Station> stations_;
  SimBusStats stats_;
  uint64_t now_ns_ = 0;
  uint64_t next_node_tick_ns_ = 0, next_bridge_tick_ns_ = 0;
  bool busy_ = false;
  unsigned on_air_station_ = 0;
  od::CanFrame on_air_;
  uint64_t on_air_end_ns_ = 0;
  uint64_t random_;
  std::vector<od::CanFrame> out_;
};

}  // namespace stepnode::bridge::sim
