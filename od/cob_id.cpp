#include "od/cob_id.hpp"

#include <stdexcept>

#include "od/communication_objects.hpp"

namespace stepnode::od {

SdoAbort check_cob_id(uint32_t current, uint32_t next, uint32_t valid_mask_when_clear) {
  if (next & (kCobExtended | kCobIdHighBits)) return SdoAbort::InvalidValue;
  bool next_valid = valid_mask_when_clear ? !(next & valid_mask_when_clear) : true;
  bool current_valid = valid_mask_when_clear ? !(current & valid_mask_when_clear) : true;
  uint32_t id = next & 0x7FF;
  if (next_valid && is_restricted_can_id(id)) return SdoAbort::InvalidValue;
  if (next_valid && current_valid && (current & 0x7FF) != id) return SdoAbort::InvalidValue;
  return SdoAbort::None;
}

std::optional<uint32_t> parse_can_id(const std::string& text) {
  size_t used = 0;
  unsigned long v = 0;
  try {
    v = std::stoul(text, &used, 0);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (used != text.size() || v < 1 || v > 0x7FF) return std::nullopt;
  return static_cast<uint32_t>(v);
}

}  // namespace stepnode::od
