// The config file's [defaults] applied to the dictionary (node/config.hpp): each value as
// an SDO write would be checked, on the values a master configuring the device at boot
// could reach.
#include <cctype>
#include <map>
#include <string>
#include <string_view>

#include "node/config.hpp"
#include "od/cob_id.hpp"
#include "od/pdo_mapping.hpp"

namespace stepnode::node {
namespace {

// Hex digits only, 1..`most` of them.
bool parse_hex(std::string_view text, size_t most, unsigned& out) {
  if (text.empty() || text.size() > most) return false;
  out = 0;
  for (const char c : text) {
    if (!std::isxdigit(static_cast<unsigned char>(c))) return false;
    out = out * 16 +
          static_cast<unsigned>(std::isdigit(static_cast<unsigned char>(c))
                                    ? c - '0'
                                    : std::tolower(static_cast<unsigned char>(c)) - 'a' + 10);
  }
  return true;
}

// "1017" or "1016:1", hex, nothing else ("1017x" or "1017 1" is no key).
bool parse_key(std::string_view key, uint16_t& index, uint8_t& sub) {
  const size_t colon = key.find(':');
  unsigned i = 0, s = 0;
  if (!parse_hex(key.substr(0, colon), 4, i)) return false;
  if (colon != std::string_view::npos && !parse_hex(key.substr(colon + 1), 2, s)) return false;
  index = static_cast<uint16_t>(i);
  sub = static_cast<uint8_t>(s);
  return true;
}

bool is_pdo_communication(uint16_t index) {
  return (index >= 0x1400 && index <= 0x15FF) || (index >= 0x1800 && index <= 0x19FF);
}

// The entry's own check of `value` (its validate hook, as over SDO), from the state a master
// configuring the device would write it in: a COB-ID through invalid (bit 31 set first,
// CiA 301 7.5.2), a PDO's other parameters while the PDO is invalid. Rules on the device's
// state now (0x0800xxxx: a SYNC counter while producing) are not the file's to break; a
// PDO mapping is checked whole once all its entries are in (apply_object_defaults).
od::SdoAbort check_as_configured(od::Dictionary& od, od::Entry& e, const od::Bytes& value) {
  if (!e.validate || od::is_rpdo_mapping(e.index) || od::is_tpdo_mapping(e.index))
    return od::SdoAbort::None;
  // The values the check is made from, put back afterwards.
  std::vector<std::pair<od::Entry*, od::Bytes>> saved;
  const auto set_invalid = [&saved](od::Entry& cob) {
    saved.emplace_back(&cob, cob.value);
    cob.value = od::encode<uint32_t>(od::decode<uint32_t>(cob.value) | od::kCobInvalid);
  };
  if (is_pdo_communication(e.index) && e.sub != 1)
    if (od::Entry* cob = od.find(e.index, 1)) set_invalid(*cob);
  od::SdoAbort a = e.validate(value);
  if (a != od::SdoAbort::None && e.type == od::DataType::Unsigned32 && e.value.size() == 4) {
    const od::Bytes through = od::encode<uint32_t>(od::decode<uint32_t>(value) | od::kCobInvalid);
    if (e.validate(through) == od::SdoAbort::None) {  // a COB-ID: changed through invalid
      saved.emplace_back(&e, e.value);
      e.value = through;
      a = e.validate(value);
    }
  }
  for (auto it = saved.rbegin(); it != saved.rend(); ++it) it->first->value = it->second;
  if ((static_cast<uint32_t>(a) >> 16) == 0x0800) return od::SdoAbort::None;
  return a;
}

[[noreturn]] void refuse(const std::string& key, const std::string& text, od::SdoAbort a) {
  throw UsageError(std::string("defaults: ")
                       .append(key)
                       .append(" = ")
                       .append(text)
                       .append(": ")
                       .append(od::abort_text(a)));
}

}  // namespace

std::vector<RefusedMapping> apply_object_defaults(
    od::Dictionary& od, const std::vector<std::pair<std::string, std::string>>& defaults) {
  // The built-in records of the mappings the file touches, to go back to.
  std::map<uint16_t, std::map<uint8_t, od::Bytes>> built_in;
  for (const auto& [key, text] : defaults) {
    uint16_t index = 0;
    uint8_t sub = 0;
    if (!parse_key(key, index, sub))
      throw UsageError("defaults: '" + key +
                       "' is not INDEX or INDEX:SUB in hex (e.g. \"1017\" or \"1016:1\")");
    od::Entry* e = od.find(index, sub);
    if (!e || !od::writable(e->access))
      throw UsageError("defaults: object " + key + " does not exist or is not writable");
    od::Bytes value;
    try {
      value = od::parse_value(e->type, text);
    } catch (const std::invalid_argument& ex) {
      throw UsageError("defaults: " + key + ": " + ex.what());
    }
    if (od::SdoAbort a = od::check_value(*e, value); a != od::SdoAbort::None) refuse(key, text, a);
    if (od::SdoAbort a = check_as_configured(od, *e, value); a != od::SdoAbort::None)
      refuse(key, text, a);
    if ((od::is_rpdo_mapping(index) || od::is_tpdo_mapping(index)) && !built_in.contains(index))
      for (const auto& [sub_index, entry] : od.object(index)->entries)
        built_in[index][sub_index] = entry.default_value;
    e->default_value = value;
    e->value = value;
  }
  std::vector<RefusedMapping> refused;
  for (const auto& [index, record] : built_in) {
    od::SdoAbort a = od::check_mapping_record(od, index);
    if (a == od::SdoAbort::None) continue;
    for (const auto& [sub, value] : record) {
      od::Entry& e = od.object(index)->entries.at(sub);
      e.default_value = e.value = value;
    }
    refused.push_back({index, a});
  }
  return refused;
}

}  // namespace stepnode::node
