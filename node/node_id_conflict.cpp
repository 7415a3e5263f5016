#include "node/node_id_conflict.hpp"

namespace stepnode::node {

void NodeIdConflict::listen(uint8_t node_id, uint64_t now_us, uint64_t duration_us) {
  node_id_ = node_id;
  listen_end_us_ = now_us + duration_us;
}

void NodeIdConflict::booted(uint8_t node_id, uint64_t now_us) {
  node_id_ = node_id;
  booted_us_ = now_us;
  listen_end_us_ = 0;
}

void NodeIdConflict::forget() {
  node_id_ = 0;
  listen_end_us_ = 0;
}

std::optional<NodeIdConflict::Finding> NodeIdConflict::on_frame(const od::CanFrame& frame,
                                                                uint32_t emcy_cob_id,
                                                                uint64_t now_us) const {
  if (node_id_ == 0 || frame.rtr) return std::nullopt;
  const bool heartbeat = frame.id == od::cob::kHeartbeat + node_id_ && frame.dlc == 1;
  const bool sdo_answer = frame.id == od::cob::kSdoTx + node_id_ && frame.dlc == 8;
  const bool emcy =
      !(emcy_cob_id & 0x80000000u) && frame.id == (emcy_cob_id & 0x7FF) && frame.dlc == 8;
  if (!heartbeat && !sdo_answer && !emcy) return std::nullopt;
  Finding f;
  f.cob_id = frame.id;
  f.boot_up = heartbeat && frame.data[0] == 0x00;
  if (listening()) f.action = Action::Refuse;
  else f.action = now_us - booted_us_ < kClaimPeriodUs ? Action::Yield : Action::Keep;
  return f;
}

}  // namespace stepnode::node
