// Many nodes in one process (issue 13): the node-IDs `--node-id 1-32` or `1,5,10-12` names,
// and the options of each node. Every node gets its own dictionary, NMT state and state
// files; they differ from one another only in what must differ on one bus: the node-ID and
// the LSS address (the serial number of 0x1018, or LSS fast scan could not tell them apart).
#pragma once
#include <cstdint>
#include <string_view>
#include <vector>

#include "node/canopen_node.hpp"

namespace stepnode::node {

// "5", "1-32", "1,5,10-12": node-IDs 1..127, ascending, each once. Throws
// std::invalid_argument saying what is wrong (0, above 127, a reversed range, an id given
// twice, an empty item, anything not a number such as "none" in a list).
std::vector<uint8_t> parse_node_id_list(std::string_view text);

// The options of node `index` (0-based, in ascending node-ID order) of a set: `base` with
// its node-ID and serial number base.serial_number + index (so the first node keeps the
// configured serial, and a single node is exactly `base`).
NodeOptions options_of_node(const NodeOptions& base, uint8_t node_id, unsigned index);

// The options of every node: `ids` empty means the one node `base` describes (whose
// node-ID may be none, for LSS); else one per id, as options_of_node.
std::vector<NodeOptions> options_per_node(const NodeOptions& base, const std::vector<uint8_t>& ids);

}  // namespace stepnode::node
