// The node's own manufacturer objects beside the CiA 301 communication area: what it
// counts about the bus (0x2F10) and whom it treats as the master (0x2F11).
#pragma once
#include <cstdint>

#include "od/dictionary.hpp"

namespace stepnode::node {

// 0x2F10: received frames the CAN socket dropped (receive queue overflow), U32 ro.
constexpr uint16_t kReceiveOverruns = 0x2F10;
// 0x2F11: the node-ID of the master whose heartbeat loss stops the axes (0: any), U8 rw.
constexpr uint16_t kMasterNodeId = 0x2F11;

void add_diagnostic_objects(od::Dictionary& dictionary);

}  // namespace stepnode::node
