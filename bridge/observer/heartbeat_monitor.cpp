#include "bridge/observer/heartbeat_monitor.hpp"

#include <algorithm>

namespace stepnode::bridge {
namespace {
constexpr uint64_t kMinTimeoutUs = 1'000'000;
// Before anything says how often the node beats: CiA 301 devices commonly use 1 s, and
// stepnode's default 0x1017 is 1000 ms.
constexpr uint64_t kAssumedPeriodUs = 1'000'000;
}  // namespace

std::optional<NodeState> nmt_state_from_byte(uint8_t byte) {
  switch (byte & 0x7F) {
    case 0x00: return NodeState::BootUp;
    case 0x04: return NodeState::Stopped;
    case 0x05: return NodeState::Operational;
    case 0x7F: return NodeState::PreOperational;
    default: return std::nullopt;
  }
}

HeartbeatMonitor::Change HeartbeatMonitor::on_heartbeat(NodeState state, uint64_t now_us) {
  Change c;
  c.was_lost = state_ == NodeState::Lost;
  c.boot_up = state == NodeState::BootUp;
  c.state_changed = state != state_;
  // The interval is measured between heartbeats only: boot-up to the first heartbeat is
  // not a producer period.
  const bool heartbeat = state != NodeState::BootUp;
  if (heartbeat && last_was_heartbeat && !c.was_lost && now_us > last_us_)
    interval_us_ = now_us - last_us_;
  if (c.boot_up || c.was_lost) interval_us_ = 0;  // the period may have changed
  last_was_heartbeat = heartbeat;
  last_us_ = now_us;
  seen_ = true;
  state_ = state;
  return c;
}

uint64_t HeartbeatMonitor::timeout_us(uint32_t configured_ms, uint16_t producer_ms,
                                      bool producer_known) const {
  if (configured_ms) return uint64_t{configured_ms} * 1000;
  uint64_t period = interval_us_;
  if (period == 0 && producer_known) {
    if (producer_ms == 0) return 0;  // heartbeat producer off: nothing to miss
    period = uint64_t{producer_ms} * 1000;
  }
  if (period == 0) period = kAssumedPeriodUs;
  return std::max(kMinTimeoutUs, 3 * period);
}

bool HeartbeatMonitor::check_lost(uint64_t now_us, uint32_t configured_ms, uint16_t producer_ms,
                                  bool producer_known) {
  if (!seen_ || state_ == NodeState::Lost) return false;
  const uint64_t timeout = timeout_us(configured_ms, producer_ms, producer_known);
  if (timeout == 0 || now_us - last_us_ < timeout) return false;
  state_ = NodeState::Lost;
  return true;
}

uint32_t HeartbeatMonitor::age_ms(uint64_t now_us) const {
  if (!seen_ || now_us < last_us_) return 0;
  return static_cast<uint32_t>(std::min<uint64_t>((now_us - last_us_) / 1000, UINT32_MAX));
}

}  // namespace stepnode::bridge
