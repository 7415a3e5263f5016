#include "node/node_guarding.hpp"

namespace stepnode::node {

NodeGuarding::NodeGuarding(const od::Dictionary& dictionary, uint8_t node_id, Events events)
    : dictionary_(dictionary), node_id_(node_id), events_(std::move(events)) {}

bool NodeGuarding::heartbeat_in_use() const { return dictionary_.get<uint16_t>(0x1017, 0) != 0; }

uint64_t NodeGuarding::life_time_us() const {
  return uint64_t{dictionary_.get<uint16_t>(kGuardTime, 0)} *
         dictionary_.get<uint8_t>(kLifeTimeFactor, 0) * 1000;
}

std::optional<od::CanFrame> NodeGuarding::on_frame(const od::CanFrame& frame, NmtState state,
                                                   uint64_t now_us) {
  if (!frame.rtr || frame.id != od::cob::kHeartbeat + node_id_) return std::nullopt;
  if (state == NmtState::Initialising || heartbeat_in_use()) return std::nullopt;
  started_ = true;
  last_request_us_ = now_us;
  if (lost_) {
    lost_ = false;
    if (events_.recovered) events_.recovered(now_us);
  }
  const auto byte =
      static_cast<uint8_t>((toggle_ ? 0x80 : 0x00) | (static_cast<uint8_t>(state) & 0x7F));
  toggle_ = !toggle_;
  return od::CanFrame(od::cob::kHeartbeat + node_id_, {byte});
}

void NodeGuarding::on_tick(uint64_t now_us) {
  const uint64_t life_time = heartbeat_in_use() ? 0 : life_time_us();
  if (lost_) {
    // Guarding switched off (life time 0, or heartbeat instead) while lost: nothing is
    // missing any more.
    if (life_time == 0) {
      lost_ = false;
      if (events_.recovered) events_.recovered(now_us);
    }
    return;
  }
  if (!started_ || life_time == 0 || now_us - last_request_us_ <= life_time) return;
  lost_ = true;
  if (events_.lost) events_.lost(now_us);
}

uint64_t NodeGuarding::next_deadline_us() const {
  const uint64_t life_time = heartbeat_in_use() ? 0 : life_time_us();
  if (lost_ || !started_ || life_time == 0) return kNoDeadline;
  return last_request_us_ + life_time + 1;
}

void NodeGuarding::reset() {
  toggle_ = false;
  started_ = false;
  lost_ = false;
}

}  // namespace stepnode::node
