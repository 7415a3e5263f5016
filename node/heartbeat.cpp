#include "node/heartbeat.hpp"

namespace stepnode::node {

HeartbeatProducer::HeartbeatProducer(od::Dictionary& dictionary, uint8_t node_id, Send send)
    : dictionary_(dictionary), node_id_(node_id), send_(std::move(send)) {}

void HeartbeatProducer::send_now(NmtState state, uint64_t now_us) {
  if (dictionary_.get<uint16_t>(0x1017, 0) == 0) return;  // producer disabled
  send_(od::CanFrame(od::cob::kHeartbeat + node_id_, {static_cast<uint8_t>(state)}));
  last_sent_us_ = now_us;
}

void HeartbeatProducer::on_tick(NmtState state, uint64_t now_us) {
  uint64_t period_us = uint64_t{dictionary_.get<uint16_t>(0x1017, 0)} * 1000;
  if (period_us == 0) return;
  const uint64_t due = last_sent_us_ + period_us;
  if (now_us < due) return;
  send_now(state, now_us);
  // Late by at most a tenth of the period (the loop's latency, a coarse tick), the cycle is
  // kept: the next is due a period after this one was due, so the heartbeat does not drift.
  // Later than that (a stalled or overloaded process) the cycle restarts at this one, as
  // CANopenNode does: a heartbeat right after a late one would tell a consumer nothing new
  // and load a bus that may be why it was late (issue 13 measured gaps of 0.4–5.5 ms). So a
  // consumer sees gaps of at least 0.9 × 0x1017 and at most 0x1017 + the send's lateness.
  if (now_us - due <= period_us / kKeptLatenessDivisor) last_sent_us_ = due;
}

uint64_t HeartbeatProducer::next_deadline_us() const {
  const uint64_t period_us = uint64_t{dictionary_.get<uint16_t>(0x1017, 0)} * 1000;
  return period_us ? last_sent_us_ + period_us : kNoDeadline;
}

HeartbeatConsumer::HeartbeatConsumer(od::Dictionary& dictionary, Events events)
    : dictionary_(dictionary), events_(std::move(events)) {
  load();
}

void HeartbeatConsumer::load() {
  for (unsigned i = 0; i < slots_.size(); ++i) {
    uint32_t v = dictionary_.get<uint32_t>(0x1016, static_cast<uint8_t>(i + 1));
    slots_[i] = Slot{static_cast<uint8_t>((v >> 16) & 0xFF), static_cast<uint16_t>(v & 0xFFFF)};
  }
}

void HeartbeatConsumer::reset() { load(); }

void HeartbeatConsumer::reconfigure() {
  for (unsigned i = 0; i < slots_.size(); ++i) {
    uint32_t v = dictionary_.get<uint32_t>(0x1016, static_cast<uint8_t>(i + 1));
    Slot next{static_cast<uint8_t>((v >> 16) & 0xFF), static_cast<uint16_t>(v & 0xFFFF)};
    Slot& s = slots_[i];
    if (next.node == s.node && next.time_ms == s.time_ms) continue;
    Slot old = s;
    s = next;
    if (old.timed_out && events_.recovered) events_.recovered(old.node, now_us_);
  }
}

bool HeartbeatConsumer::timed_out(uint8_t node) const {
  for (const auto& s : slots_)
    if (s.node == node && s.timed_out) return true;
  return false;
}

bool HeartbeatConsumer::any_timed_out() const {
  for (const auto& s : slots_)
    if (s.timed_out) return true;
  return false;
}

uint64_t HeartbeatConsumer::next_deadline_us() const {
  uint64_t next = kNoDeadline;
  for (const auto& s : slots_)
    if (s.started && !s.timed_out && s.time_ms != 0 && s.node != 0)
      next = earliest(next, s.last_us + uint64_t{s.time_ms} * 1000 + 1);
  return next;
}

void HeartbeatConsumer::on_frame(const od::CanFrame& frame, uint64_t now_us) {
  now_us_ = now_us;
  if (frame.rtr || frame.dlc != 1 || frame.id <= od::cob::kHeartbeat ||
      frame.id > od::cob::kHeartbeat + 127)
    return;
  uint8_t node = static_cast<uint8_t>(frame.id - od::cob::kHeartbeat);
  for (auto& s : slots_) {
    if (s.node != node || s.time_ms == 0 || s.node == 0) continue;
    if (frame.data[0] == static_cast<uint8_t>(NmtState::Initialising) && s.started &&
        events_.remote_reset)
      events_.remote_reset(node, now_us);
    s.started = true;
    s.last_us = now_us;
    if (s.timed_out) {
      s.timed_out = false;
      if (events_.recovered) events_.recovered(node, now_us);
    }
  }
}

void HeartbeatConsumer::on_tick(uint64_t now_us) {
  now_us_ = now_us;
  for (auto& s : slots_) {
    if (!s.started || s.timed_out || s.time_ms == 0 || s.node == 0) continue;
    if (now_us - s.last_us > uint64_t{s.time_ms} * 1000) {
      s.timed_out = true;
      if (events_.timeout) events_.timeout(s.node, now_us);
    }
  }
}

}  // namespace stepnode::node
