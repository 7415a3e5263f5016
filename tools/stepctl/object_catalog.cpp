#include "tools/stepctl/object_catalog.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "node/device_objects.hpp"
#include "od/communication_objects.hpp"
#include "od/eds.hpp"

namespace stepnode::tools {

ObjectCatalog::ObjectCatalog(const std::string& eds_path) {
  if (eds_path.empty()) {
    od::Dictionary dictionary;
    // Every object a stepnode can have: all profiles, the most axes.
    node::build_device_objects(dictionary, od::DeviceInfo{},
                               node::DeviceLayout{.axes = node::kMaxAxes});
    for (const auto& [index, obj] : dictionary.objects())
      for (const auto& [sub, e] : obj.entries) {
        std::string name = obj.code == od::ObjectCode::Var ? obj.name : obj.name + " / " + e.name;
        entries_.push_back({index, sub, name, e.type, e.access});
      }
    source_ = "stepnode built-in dictionary";
    return;
  }
  std::ifstream in(eds_path);
  if (!in) throw std::runtime_error("cannot read EDS file " + eds_path);
  std::stringstream text;
  text << in.rdbuf();
  od::EdsFile eds = od::parse_eds(text.str());
  for (const auto& [key, e] : eds.entries)
    entries_.push_back({e.index, e.sub, e.name, e.type, e.access});
  source_ = eds_path;
}

std::optional<ObjectInfo> ObjectCatalog::find(uint16_t index, uint8_t sub) const {
  auto it = std::find_if(entries_.begin(), entries_.end(),
                         [&](const ObjectInfo& o) { return o.index == index && o.sub == sub; });
  if (it == entries_.end()) return std::nullopt;
  return *it;
}

std::pair<uint16_t, uint8_t> parse_object_address(const std::string& text) {
  auto number = [&](const std::string& s, unsigned long max) {
    size_t used = 0;
    unsigned long v = 0;
    try {
      v = std::stoul(s, &used, 16);
    } catch (const std::exception&) {
      used = 0;
    }
    if (s.empty() || used != s.size() || v > max)
      throw std::invalid_argument("object '" + text +
                                  "' is not INDEX[:SUB] in hex (e.g. 0x1017 or 1016:1)");
    return v;
  };
  std::string index = text, sub = "0";
  if (auto colon = text.find(':'); colon != std::string::npos) {
    index = text.substr(0, colon);
    sub = text.substr(colon + 1);
  }
  auto strip = [](const std::string& s) {
    return s.rfind("0x", 0) == 0 || s.rfind("0X", 0) == 0 ? s.substr(2) : s;
  };
  return {static_cast<uint16_t>(number(strip(index), 0xFFFF)),
          static_cast<uint8_t>(number(strip(sub), 0xFF))};
}

}  // namespace stepnode::tools
