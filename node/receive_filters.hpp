// The kernel receive filters of the node: exactly the CAN-IDs it serves, computed from its
// dictionary, so frames for other nodes never reach (or fill) its socket's receive queue.
// Pure: node/main.cpp hands the list to the socket (canio::SocketCan::set_filters).
//
// Exact identifiers, not masks: the kernel keeps an exact 11-bit data-frame filter in a
// table indexed by the identifier (one lookup per frame), while every mask or remote-frame
// filter is tried in turn for every frame. The one filter that must also pass remote
// frames is 0x700+id (node guarding requests; data frames there are another device's
// boot-up or heartbeat, the duplicate node-ID check).
//
// Not NMT-state dependent: a state change takes effect at the NMT command's place in the
// bus order, a filter change only for frames that reach the socket after the process has
// handled it; an RPDO sent right after NMT start would be lost in between.
#pragma once
#include <cstdint>
#include <vector>

#include "od/dictionary.hpp"

namespace stepnode::node {

struct ReceiveFilter {
  enum class Frames : uint8_t { Data, DataAndRemote };
  uint32_t id = 0;  // 11-bit CAN-ID
  Frames frames = Frames::Data;
  bool operator==(const ReceiveFilter&) const = default;
  auto operator<=>(const ReceiveFilter&) const = default;
};

// The kernel refuses more filters than this on one socket (CAN_RAW_FILTER_MAX, not in
// every libc's headers); a longer list becomes "everything".
constexpr size_t kMaxReceiveFilters = 512;

// Sorted, without duplicates. `node_id` lss::kUnconfigured: only LSS and NMT. Empty: no
// filter (every frame), only for a list longer than kMaxReceiveFilters.
std::vector<ReceiveFilter> receive_filters(const od::Dictionary& od, uint8_t node_id,
                                           unsigned pdo_count);

}  // namespace stepnode::node
