// Heartbeat producer (0x1017) and consumer (0x1016), CiA 301 7.2.8.3.2.
#pragma once
#include <array>
#include <cstdint>
#include <functional>

#include "node/deadline.hpp"

#include "node/nmt.hpp"
#include "od/can_frame.hpp"
#include "od/communication_objects.hpp"
#include "od/dictionary.hpp"

namespace stepnode::node {

class HeartbeatProducer {
 public:
  using Send = std::function<void(const od::CanFrame&)>;
  HeartbeatProducer(od::Dictionary& dictionary, uint8_t node_id, Send send);

  // Sends the heartbeat now (state changes are confirmed at once) and restarts the period.
  void send_now(NmtState state, uint64_t now_us);
  void on_tick(NmtState state, uint64_t now_us);
  // When on_tick sends the next heartbeat: the last one + 0x1017 ms (CiA 301 7.2.8.3.2.2),
  // counted from when the last was due if it went out at most 0x1017 / 10 late (the cycle
  // kept), else from when it went out; kNoDeadline while 0x1017 is 0.
  uint64_t next_deadline_us() const;
  // A node-ID configured over LSS, in effect from the reset communication that applies it.
  void set_node_id(uint8_t node_id) { node_id_ = node_id; }

 private:
  od::Dictionary& dictionary_;
  uint8_t node_id_;
  // A heartbeat late by at most 0x1017 / this keeps the cycle; a later one restarts it.
  static constexpr uint64_t kKeptLatenessDivisor = 10;
  Send send_;
  uint64_t last_sent_us_ = 0;  // when the last heartbeat went out, or was due (cycle kept)
};

// Watches the nodes listed in 0x1016. Monitoring of a node starts with its first
// heartbeat; a missing heartbeat after the consumer time is a timeout (EMCY 0x8130).
class HeartbeatConsumer {
 public:
  struct Events {
    std::function<void(uint8_t node, uint64_t now_us)> timeout;
    std::function<void(uint8_t node, uint64_t now_us)> recovered;
    std::function<void(uint8_t node, uint64_t now_us)> remote_reset;  // boot-up seen
  };
  HeartbeatConsumer(od::Dictionary& dictionary, Events events);

  // Feeds a frame from the bus (anything not a heartbeat is ignored).
  void on_frame(const od::CanFrame& frame, uint64_t now_us);
  void on_tick(uint64_t now_us);
  // Forget all monitoring state (reset communication).
  void reset();
  // 0x1016 was written: entries whose node and time are unchanged go on being monitored
  // as before; a changed entry starts afresh, and if it was timed out that loss is over
  // (`recovered` is called, so the error does not stay active with nothing to clear it).
  void reconfigure();
  bool timed_out(uint8_t node) const;
  bool any_timed_out() const;
  // The first moment on_tick finds a monitored node late: its last heartbeat + its
  // consumer time + 1 us (late is "more than" the consumer time); kNoDeadline if none runs.
  uint64_t next_deadline_us() const;

 private:
  struct Slot {
    uint8_t node = 0;
    uint16_t time_ms = 0;
    bool started = false;
    bool timed_out = false;
    uint64_t last_us = 0;
  };
  void load();

  od::Dictionary& dictionary_;
  Events events_;
  std::array<Slot, od::kHeartbeatConsumers> slots_{};
  uint64_t now_us_ = 0;  // the latest time seen in on_frame/on_tick
};

}  // namespace stepnode::node
