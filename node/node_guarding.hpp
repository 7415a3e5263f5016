// Node guarding and life guarding, the NMT slave's side (CiA 301 7.2.8.3.1). The master
// guards the node with a remote frame on 0x700 + node-ID; the node answers with one byte:
// its NMT state in bits 0..6 and a toggle bit 7 that alternates from one answer to the
// next, 0 in the first answer after an NMT reset communication (no other transition resets
// it). Life guarding: once the first request came, and with the node life time (guard time
// 0x100C in ms x life time factor 0x100D) not 0, the next request is due within the node
// life time; missing it is a life guarding event, a communication error, and the next
// request resolves it. A device does not run both error control protocols: while the
// heartbeat producer time 0x1017 is not 0, heartbeat is the one in use and guarding
// requests get no answer.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>

#include "node/deadline.hpp"

#include "node/nmt.hpp"
#include "od/can_frame.hpp"
#include "od/dictionary.hpp"

namespace stepnode::node {

constexpr uint16_t kGuardTime = 0x100C;       // UNSIGNED16, ms
constexpr uint16_t kLifeTimeFactor = 0x100D;  // UNSIGNED8

class NodeGuarding {
 public:
  struct Events {
    std::function<void(uint64_t now_us)> lost;  // the life guarding event
    std::function<void(uint64_t now_us)>
        recovered;  // a request came again, or guarding was switched off
  };
  NodeGuarding(const od::Dictionary& dictionary, uint8_t node_id, Events events);

  // A node-ID configured over LSS, from the reset communication that applies it.
  void set_node_id(uint8_t node_id) { node_id_ = node_id; }
  // The answer to a guarding request (a remote frame on 0x700 + node-ID) in `state`, to be
  // sent now; nullopt for any other frame, in Initialising, or while heartbeat is in use.
  std::optional<od::CanFrame> on_frame(const od::CanFrame& frame, NmtState state, uint64_t now_us);
  void on_tick(uint64_t now_us);
  // The first moment on_tick finds the node life time passed since the last request (+1
  // us: "within" the life time is not late); kNoDeadline while life guarding does not run.
  // Guarding switched off while lost is a write, and every write is followed by a tick.
  uint64_t next_deadline_us() const;
  // NMT reset communication: the toggle bit back to 0; life guarding waits for a first
  // request again (a lost guarding is over with the reset, as the EMCY state is).
  void reset();
  bool lost() const { return lost_; }

 private:
  uint64_t life_time_us() const;
  bool heartbeat_in_use() const;

  const od::Dictionary& dictionary_;
  uint8_t node_id_;
  Events events_;
  bool toggle_ = false;   // bit 7 of the next answer
  bool started_ = false;  // a request came since the reset: life guarding runs
  bool lost_ = false;
  uint64_t last_request_us_ = 0;
};

}  // namespace stepnode::node
