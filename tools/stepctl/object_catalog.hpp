// What stepctl knows about a node's objects (name, type, access): from an EDS file given
// with --eds, or else from stepnode's own dictionary table.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "od/data_type.hpp"

namespace stepnode::tools {

struct ObjectInfo {
  uint16_t index = 0;
  uint8_t sub = 0;
  std::string name;
  od::DataType type = od::DataType::Unsigned32;
  od::Access access = od::Access::ReadWrite;
};

class ObjectCatalog {
 public:
  // eds_path empty: stepnode's built-in table (8 axes, so every PDO object is known).
  explicit ObjectCatalog(const std::string& eds_path = "");
  std::optional<ObjectInfo> find(uint16_t index, uint8_t sub) const;
  const std::vector<ObjectInfo>& all() const { return entries_; }
  const std::string& source() const { return source_; }

 private:
  std::vector<ObjectInfo> entries_;  // sorted by index, sub
  std::string source_;
};

// "0x1017", "1017", "0x1016:1", "1016:01" -> index, sub. Throws std::invalid_argument.
std::pair<uint16_t, uint8_t> parse_object_address(const std::string& text);

}  // namespace stepnode::tools
