#include "node/lss_store.hpp"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "node/atomic_file.hpp"

namespace stepnode::node {
namespace {

constexpr std::string_view kHeader = "# stepnode LSS configuration v1";

bool valid_node_id(unsigned id) { return (id >= 1 && id <= 127) || id == lss::kUnconfigured; }

}  // namespace

LssStore::LssStore(const std::filesystem::path& state_dir, const lss::Identity& identity) {
  char name[64];
  std::snprintf(name, sizeof name, "lss-%08x-%08x-%08x.conf", identity.vendor_id,
                identity.product_code, identity.serial_number);
  file_ = state_dir / name;
}

std::optional<LssStore::Contents> LssStore::load() const {
  std::ifstream in(file_);
  if (!in) return std::nullopt;  // nothing stored yet
  std::string line;
  Contents out;
  bool header = false, node_id = false;
  while (std::getline(in, line)) {
    if (line == kHeader) {
      header = true;
      continue;
    }
    std::istringstream fields(line);
    std::string key;
    unsigned value = 0;
    if (line.empty() || !(fields >> key)) continue;
    if (key == "node_id" && fields >> value && valid_node_id(value)) {
      out.node_id = static_cast<uint8_t>(value);
      node_id = true;
    } else if (key == "bit_timing" && fields >> value && value <= 0xFF &&
               lss::bit_rate_kbit(static_cast<uint8_t>(value))) {
      out.bit_timing = static_cast<uint8_t>(value);
    } else {
      header = false;  // a line that is not ours: the whole file is suspect
      break;
    }
  }
  if (!header || !node_id) {
    spdlog::error("{} is not a valid stepnode LSS configuration; it is ignored", file_.string());
    return std::nullopt;
  }
  return out;
}

bool LssStore::save(const Contents& contents) const {
  std::string text = std::string(kHeader) + "\nnode_id " + std::to_string(contents.node_id) + "\n";
  if (contents.bit_timing) text += "bit_timing " + std::to_string(*contents.bit_timing) + "\n";
  std::string error;
  if (!write_file_atomically(file_, text, error)) {
    spdlog::error("LSS: cannot store the configuration: {}", error);
    return false;
  }
  spdlog::info("LSS: node-ID {} stored in {}", contents.node_id, file_.string());
  return true;
}

}  // namespace stepnode::node
