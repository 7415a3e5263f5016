// Electronic Data Sheet (CiA 306): writing the device's EDS from the dictionary table, and
// reading an EDS back into entry descriptions (stepctl types values with it).
#pragma once
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>

#include "od/communication_objects.hpp"
#include "od/dictionary.hpp"

namespace stepnode::od {

std::string write_eds(const Dictionary& od, const DeviceInfo& info);

// What an EDS says about one sub-entry.
struct EdsEntry {
  uint16_t index = 0;
  uint8_t sub = 0;
  std::string name;  // "Object name" or "Object name / sub name"
  DataType type = DataType::Unsigned8;
  Access access = Access::ReadOnly;
  bool pdo_mappable = false;
  std::string default_value;  // as written, may contain $NODEID
};

struct EdsFile {
  std::map<std::string, std::map<std::string, std::string>> sections;  // lower-cased names
  std::map<std::pair<uint16_t, uint8_t>, EdsEntry> entries;
  const EdsEntry* find(uint16_t index, uint8_t sub) const;
};

// Parses EDS text. Throws std::runtime_error naming the line and the rule on malformed input.
EdsFile parse_eds(std::string_view text);

}  // namespace stepnode::od
