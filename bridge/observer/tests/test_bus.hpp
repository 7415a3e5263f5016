// A virtual CAN bus for the observer's tests: every frame reaches the observer, the fake
// nodes and (optionally) another master's SDO client, in order; virtual time advances in
// 1 ms ticks and the fake nodes send heartbeats on their period. The observer does not
// receive its own frames (SocketCAN does not loop them back to the sending socket)
// unless `echo_observer_frames` says the socket does.
#pragma once
#include <deque>
#include <memory>
#include <vector>

#include "bridge/observer/bus_observer.hpp"
#include "fake_node.hpp"
#include "od/sdo_client.hpp"
#include "recording_sink.hpp"

namespace stepnode::bridge::test {

class TestBus {
 public:
  explicit TestBus(const ObserverConfig& config = {}) : observer(sink, config) {}

  struct Beat {
    FakeNode* node;
    bool beating = true;
    uint8_t state = 0x7F;  // pre-operational after boot-up
    uint64_t period_us = 100'000;
    uint64_t next_us = 0;
  };

  RecordingSink sink;
  BusObserver observer;
  std::vector<Beat> nodes;
  std::unique_ptr<od::SdoClient> master;  // another master on the bus
  std::vector<od::CanFrame> observer_sent;
  std::vector<uint64_t> observer_sent_at;  // virtual time of each, us
  bool echo_observer_frames = false;
  uint64_t now_us = 1'000'000;

  Beat& add(FakeNode& node, uint64_t period_ms = 100) {
    nodes.push_back(Beat{&node, true, 0x7F, period_ms * 1000, now_us + period_ms * 1000});
    return nodes.back();
  }
  Beat& beat_of(const FakeNode& node) {
    for (Beat& b : nodes)
      if (b.node == &node) return b;
    throw std::logic_error("node not on the bus");
  }

  // A frame from a node or anyone but the observer and the master.
  void send(const od::CanFrame& f) {
    queue_.push_back({f, Origin::Other});
    drain();
  }
  // The node boots: boot-up message, then heartbeats in pre-operational.
  void boot(FakeNode& node) {
    Beat& b = beat_of(node);
    b.state = 0x7F;
    b.beating = true;
    b.next_us = now_us + b.period_us;
    send(node.boot_up());
  }

  // The node's held SDO responses go out now, and it answers at once again.
  void release(FakeNode& node, bool keep_holding = false) {
    node.hold = keep_holding;
    std::vector<od::CanFrame> frames;
    frames.swap(node.held);
    for (const od::CanFrame& f : frames) queue_.push_back({f, Origin::Other});
    drain();
  }

  void master_start(uint8_t node) {
    master = std::make_unique<od::SdoClient>(0x600 + node, 0x580 + node);
  }
  void master_download(uint16_t index, uint8_t sub, od::Bytes data) {
    std::vector<od::CanFrame> out;
    master->start_download(index, sub, std::move(data), od::SdoClient::Mode::Auto, now_us, out);
    enqueue(out, Origin::Master);
    drain();
  }
  void master_upload(uint16_t index, uint8_t sub) {
    std::vector<od::CanFrame> out;
    master->start_upload(index, sub, od::SdoClient::Mode::Auto, now_us, out);
    enqueue(out, Origin::Master);
    drain();
  }

  void tick() {
    std::vector<od::CanFrame> out;
    observer.on_tick(now_us, now_us * 1000, out);
    enqueue(out, Origin::Observer);
    if (master) {
      out.clear();
      master->on_tick(now_us, out);
      enqueue(out, Origin::Master);
    }
    for (Beat& b : nodes) {
      if (!b.beating || now_us < b.next_us) continue;
      b.next_us += b.period_us;
      queue_.push_back({b.node->heartbeat(b.state), Origin::Other});
    }
    drain();
  }
  // Advances virtual time by `ms`, one tick per millisecond.
  void run_ms(uint64_t ms) {
    for (uint64_t i = 0; i < ms; ++i) {
      now_us += 1000;
      tick();
    }
  }

 private:
  enum class Origin { Observer, Master, Other };
  struct Queued {
    od::CanFrame frame;
    Origin origin;
  };
  void enqueue(const std::vector<od::CanFrame>& out, Origin origin) {
    for (const od::CanFrame& f : out) queue_.push_back({f, origin});
  }
  void drain() {
    std::vector<od::CanFrame> out;
    while (!queue_.empty()) {
      const Queued q = queue_.front();
      queue_.pop_front();
      if (q.origin == Origin::Observer) {
        observer_sent.push_back(q.frame);
        observer_sent_at.push_back(now_us);
      }
      if (q.origin != Origin::Observer || echo_observer_frames) {
        out.clear();
        ObservedFrame of;
        of.frame = q.frame;
        of.can_time_ns = now_us * 1000;
        observer.on_frame(of, now_us, out);
        enqueue(out, Origin::Observer);
      }
      for (Beat& b : nodes) {
        out.clear();
        b.node->on_frame(q.frame, now_us, out);
        enqueue(out, Origin::Other);
      }
      if (master && q.origin != Origin::Master) {
        out.clear();
        master->on_frame(q.frame, now_us, out);
        enqueue(out, Origin::Master);
      }
    }
  }
  std::deque<Queued> queue_;
};

}  // namespace stepnode::bridge::test
