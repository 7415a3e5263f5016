// CanopenNode's answer to another device with its node-ID (node/node_id_conflict.hpp says
// how it is found, README "Duplicate node-ID" what the node does): refuse before the
// boot-up, yield within the claim period, keep it after.
#include <spdlog/spdlog.h>

#include "node/canopen_node.hpp"

namespace stepnode::node {

void CanopenNode::node_id_conflict(const NodeIdConflict::Finding& finding, uint64_t now_us) {
  // Manufacturer bytes: the COB-ID heard (LE), 1 if this node gave its node-ID up.
  if (finding.action == NodeIdConflict::Action::Refuse) {
    // Nothing was sent with the node-ID, and nothing is: no boot-up, no EMCY.
    spdlog::error(
        "node-ID {} is already used by another device (0x{:03X} heard before boot-up): this node "
        "does not take it and waits for an LSS master",
        node_id(), finding.cob_id);
    lss_.give_up_node_id();
    conflict_.forget();
    initialise(false, now_us);
    return;
  }
  const bool yield = finding.action == NodeIdConflict::Action::Yield;
  const std::array<uint8_t, 5> info{static_cast<uint8_t>(finding.cob_id),
                                    static_cast<uint8_t>(finding.cob_id >> 8),
                                    static_cast<uint8_t>(yield), 0, 0};
  if (yield) {
    spdlog::error(
        "node-ID {} is already used by another device (0x{:03X} heard within {} s of boot-up): "
        "this node "
        "gives it up and waits for an LSS master",
        node_id(), finding.cob_id, NodeIdConflict::kClaimPeriodUs / 1'000'000);
    emcy_.report(emcy_code::kCommunication, error_bits::kCommunication, info, now_us);
    lss_.give_up_node_id();
    initialise(false, now_us);
    return;
  }
  if (!emcy_.active(emcy_code::kCommunication))
    spdlog::error(
        "node-ID {}: another device sends on 0x{:03X}{}; this node had the node-ID first and keeps "
        "it",
        node_id(), finding.cob_id, finding.boot_up ? " (its boot-up)" : "");
  // A newcomer that booted with this node-ID hears this node's heartbeat within its claim
  // period; first, so that it yields to the heartbeat rather than to the EMCY.
  if (finding.boot_up) heartbeat_.send_now(state_, now_us);
  emcy_.raise(emcy_code::kCommunication, error_bits::kCommunication, info, now_us);
}

}  // namespace stepnode::node
