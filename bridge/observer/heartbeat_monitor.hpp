// One node's heartbeat as the bridge sees it: the NMT state from the heartbeat byte
// (CiA 301 7.2.8.3.2), the interval between heartbeats, and the verdict "lost" when none
// came for the timeout.
#pragma once
#include <cstdint>
#include <optional>

#include "bridge/samples.hpp"

namespace stepnode::bridge {

// Heartbeat byte -> state; nullopt for a byte that is no NMT state. Bit 7 is the node
// guarding toggle (a guarding answer has the same layout) and is ignored.
std::optional<NodeState> nmt_state_from_byte(uint8_t byte);

class HeartbeatMonitor {
 public:
  struct Change {
    bool state_changed = false;
    bool boot_up = false;   // 0x00: the node (re)started, its settings are back to stored
    bool was_lost = false;  // a heartbeat after the verdict "lost"
  };

  Change on_heartbeat(NodeState state, uint64_t now_us);
  // The timeout in use: `configured_ms` when set; otherwise 3 x the last observed interval
  // (or 3 x `producer_ms`, the node's 0x1017, before two heartbeats were seen), at least
  // 1000 ms. 0 = no verdict possible (the node produces no heartbeat).
  uint64_t timeout_us(uint32_t configured_ms, uint16_t producer_ms, bool producer_known) const;
  // True once, when the node goes from alive to lost.
  bool check_lost(uint64_t now_us, uint32_t configured_ms, uint16_t producer_ms,
                  bool producer_known);

  // The node's period changed (a master wrote its 0x1017): measure it afresh.
  void forget_interval() {
    interval_us_ = 0;
    last_was_heartbeat = false;
  }

  NodeState state() const { return state_; }
  bool lost() const { return state_ == NodeState::Lost; }
  uint32_t age_ms(uint64_t now_us) const;
  uint64_t interval_us() const { return interval_us_; }

 private:
  NodeState state_ = NodeState::Unknown;
  uint64_t last_us_ = 0;
  uint64_t interval_us_ = 0;        // 0 = not measured yet
  bool last_was_heartbeat = false;  // the previous message was a heartbeat (not a boot-up)
  bool seen_ = false;
};

}  // namespace stepnode::bridge
