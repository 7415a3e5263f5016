#include "node/node_id_list.hpp"

#include <algorithm>
#include <charconv>
#include <stdexcept>
#include <string>

namespace stepnode::node {
namespace {

// One node-ID of a list: decimal 1..127.
uint8_t parse_id(std::string_view item) {
  int id = -1;
  auto [end, ec] = std::from_chars(item.data(), item.data() + item.size(), id);
  if (item.empty() || ec != std::errc() || end != item.data() + item.size())
    throw std::invalid_argument("'" + std::string(item) + "' is not a node-ID (1..127)");
  if (id < 1 || id > 127)
    throw std::invalid_argument("node-ID " + std::to_string(id) + " is outside 1..127");
  return static_cast<uint8_t>(id);
}

}  // namespace

std::vector<uint8_t> parse_node_id_list(std::string_view text) {
  std::vector<uint8_t> ids;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    const std::string_view item = text.substr(start, comma - start);
    const size_t dash = item.find('-');
    if (dash == 0 || (dash != std::string_view::npos && dash + 1 == item.size()))
      throw std::invalid_argument("'" + std::string(item) + "' is not a node-ID or a range");
    const uint8_t first = parse_id(item.substr(0, dash));
    const uint8_t last = dash == std::string_view::npos ? first : parse_id(item.substr(dash + 1));
    if (last < first) throw std::invalid_argument("range " + std::string(item) + " runs backwards");
    for (unsigned id = first; id <= last; ++id) ids.push_back(static_cast<uint8_t>(id));
    start = comma + 1;
  }
  std::sort(ids.begin(), ids.end());
  if (auto twice = std::adjacent_find(ids.begin(), ids.end()); twice != ids.end())
    throw std::invalid_argument("node-ID " + std::to_string(*twice) + " is given twice");
  return ids;
}

NodeOptions options_of_node(const NodeOptions& base, uint8_t node_id, unsigned index) {
  NodeOptions o = base;
  o.device.node_id = node_id;
  o.device.serial_number = base.device.serial_number + index;
  return o;
}

std::vector<NodeOptions> options_per_node(const NodeOptions& base,
                                          const std::vector<uint8_t>& ids) {
  if (ids.empty()) return {base};
  std::vector<NodeOptions> out;
  out.reserve(ids.size());
  for (unsigned i = 0; i < ids.size(); ++i) out.push_back(options_of_node(base, ids[i], i));
  return out;
}

}  // namespace stepnode::node
