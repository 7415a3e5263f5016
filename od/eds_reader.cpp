#include <algorithm>
#include <cctype>
#include <stdexcept>
#include <string>

#include "od/eds.hpp"

namespace stepnode::od {
namespace {

std::string trim(std::string_view s) {
  size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return std::string(s.substr(b, e - b));
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

unsigned long number(const std::string& text, const std::string& where) {
  try {
    size_t used = 0;
    unsigned long v = std::stoul(text, &used, 0);
    if (used != text.size()) throw std::invalid_argument(text);
    return v;
  } catch (const std::exception&) {
    throw std::runtime_error("EDS: " + where + ": '" + text + "' is not a number");
  }
}

Access parse_access(const std::string& text, const std::string& where) {
  std::string a = lower(text);
  if (a == "ro") return Access::ReadOnly;
  if (a == "wo") return Access::WriteOnly;
  if (a == "rw" || a == "rwr" || a == "rww") return Access::ReadWrite;
  if (a == "const") return Access::Const;
  throw std::runtime_error("EDS: " + where + ": AccessType '" + text + "' is not ro/wo/rw/rwr/rww/const");
}

const std::string& key(const std::map<std::string, std::string>& section, const char* name,
                       const std::string& where) {
  auto it = section.find(name);
  if (it == section.end()) throw std::runtime_error("EDS: [" + where + "] has no " + name);
  return it->second;
}

}  // namespace

const EdsEntry* EdsFile::find(uint16_t index, uint8_t sub) const {
  auto it = entries.find({index, sub});
  return it == entries.end() ? nullptr : &it->second;
}

EdsFile parse_eds(std::string_view text) {
  EdsFile eds;
  std::string current;
  size_t line_no = 0;
  while (!text.empty()) {
    size_t nl = text.find('\n');
    std::string line = trim(text.substr(0, nl));
    text = nl == std::string_view::npos ? std::string_view{} : text.substr(nl + 1);
    ++line_no;
    if (line.empty() || line[0] == ';') continue;
    if (line[0] == '[') {
      if (line.back() != ']')
        throw std::runtime_error("EDS line " + std::to_string(line_no) + ": unterminated section");
      current = lower(line.substr(1, line.size() - 2));
      eds.sections[current];
      continue;
    }
    size_t eq = line.find('=');
    if (eq == std::string::npos || current.empty())
      throw std::runtime_error("EDS line " + std::to_string(line_no) + ": expected key=value");
    eds.sections[current][lower(trim(line.substr(0, eq)))] = trim(line.substr(eq + 1));
  }

  auto hex_section = [](const std::string& name, uint16_t& index, int& sub) {
    auto is_hex = [](const std::string& s) {
      return !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isxdigit(c); });
    };
    std::string head = name.substr(0, 4);
    if (name.size() < 4 || !is_hex(head)) return false;
    index = static_cast<uint16_t>(std::stoul(head, nullptr, 16));
    if (name.size() == 4) return sub = -1, true;
    if (name.compare(4, 3, "sub") != 0 || !is_hex(name.substr(7))) return false;
    sub = static_cast<int>(std::stoul(name.substr(7), nullptr, 16));
    return true;
  };

  for (const auto& [name, values] : eds.sections) {
    uint16_t index = 0;
    int sub = 0;
    if (!hex_section(name, index, sub)) continue;
    auto type_it = values.find("datatype");
    if (type_it == values.end()) continue;  // an ARRAY/RECORD header
    EdsEntry e;
    e.index = index;
    e.sub = static_cast<uint8_t>(sub < 0 ? 0 : sub);
    e.name = key(values, "parametername", name);
    if (sub >= 0) {
      auto parent = eds.sections.find(name.substr(0, 4));
      if (parent != eds.sections.end() && parent->second.count("parametername"))
        e.name = parent->second.at("parametername") + " / " + e.name;
    }
    e.type = static_cast<DataType>(number(type_it->second, "[" + name + "] DataType"));
    e.access = parse_access(key(values, "accesstype", name), "[" + name + "]");
    auto pdo = values.find("pdomapping");
    e.pdo_mappable = pdo != values.end() && pdo->second == "1";
    auto def = values.find("defaultvalue");
    if (def != values.end()) e.default_value = def->second;
    eds.entries[{e.index, e.sub}] = e;
  }
  return eds;
}

}  // namespace stepnode::od
