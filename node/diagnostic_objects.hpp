// The node's own manufacturer objects beside the CiA 301 communication area: what it
// counts about the bus (0x2F10), whom it treats as the master (0x2F11) and the network
// time (0x2F12).
#pragma once
#include <cstdint>

#include "od/dictionary.hpp"

namespace stepnode::node {

// 0x2F10: received frames the CAN socket dropped (receive queue overflow), U32 ro.
constexpr uint16_t kReceiveOverruns = 0x2F10;
// 0x2F11: the node-ID of the master whose heartbeat loss stops the axes (0: any), U8 rw.
constexpr uint16_t kMasterNodeId = 0x2F11;

// 0x2F12: the network time (TIME, 0x1012) as the node keeps it: 1 ms after midnight (U32),
// 2 days since 1984-01-01 (U16), 3 ms since 1970-01-01 UTC (U64), 4 source (U8: 0 none, 1
// consumed, 2 produced from the node's clock); all ro, computed when read; 5 the TIME
// producer's period in ms (U16 rw, stored; 0: no TIME produced).
constexpr uint16_t kNetworkTime = 0x2F12;
constexpr uint8_t kTimeProducerPeriodSub = 5;

void add_diagnostic_objects(od::Dictionary& od);

}  // namespace stepnode::node
