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

[[noreturn]] void fail(size_t line, const std::string& what) {
  throw std::runtime_error("EDS line " + std::to_string(line) + ": " + what);
}

unsigned long number(const std::string& text, size_t line, const std::string& what) {
  try {
    size_t used = 0;
    if (!text.empty() && text[0] == '-') throw std::invalid_argument(text);
    unsigned long v = std::stoul(text, &used, 0);
    if (used != text.size()) throw std::invalid_argument(text);
    return v;
  } catch (const std::exception&) {
    fail(line, what + " '" + text + "' is not a number");
  }
}

Access parse_access(const std::string& text, size_t line, const std::string& where) {
  std::string a = lower(text);
  if (a == "ro") return Access::ReadOnly;
  if (a == "wo") return Access::WriteOnly;
  if (a == "rw" || a == "rwr" || a == "rww") return Access::ReadWrite;
  if (a == "const") return Access::Const;
  fail(line, where + " AccessType '" + text + "' is not ro/wo/rw/rwr/rww/const");
}

// Where each section and key was found, so that errors name the line.
struct Lines {
  std::map<std::string, size_t> section;
  std::map<std::pair<std::string, std::string>, size_t> key;
  size_t of(const std::string& sec, const std::string& k) const {
    auto it = key.find({sec, k});
    return it != key.end() ? it->second : section.at(sec);
  }
};

const std::string& key(const std::map<std::string, std::string>& section, const char* name,
                       const std::string& where, const Lines& lines) {
  auto it = section.find(lower(name));
  if (it == section.end()) fail(lines.section.at(where), "[" + where + "] has no " + name);
  return it->second;
}

}  // namespace

const EdsEntry* EdsFile::find(uint16_t index, uint8_t sub) const {
  auto it = entries.find({index, sub});
  return it == entries.end() ? nullptr : &it->second;
}

namespace {

// The sections and their key=value lines (keys lower-cased), with the line of each for
// the messages.
void read_sections(std::string_view text, EdsFile& eds, Lines& lines) {
  std::string current;
  size_t line_no = 0;
  while (!text.empty()) {
    size_t nl = text.find('\n');
    std::string line = trim(text.substr(0, nl));
    text = nl == std::string_view::npos ? std::string_view{} : text.substr(nl + 1);
    ++line_no;
    if (line.empty() || line[0] == ';') continue;
    if (line[0] == '[') {
      if (line.back() != ']') fail(line_no, "unterminated section header '" + line + "'");
      current = lower(trim(line.substr(1, line.size() - 2)));
      if (current.empty()) fail(line_no, "empty section name");
      eds.sections[current];
      lines.section.emplace(current, line_no);
      continue;
    }
    size_t eq = line.find('=');
    if (eq == std::string::npos) fail(line_no, "expected key=value, got '" + line + "'");
    if (current.empty()) fail(line_no, "key=value before the first [section]");
    std::string k = lower(trim(line.substr(0, eq)));
    if (k.empty()) fail(line_no, "empty key");
    eds.sections[current][k] = trim(line.substr(eq + 1));
    lines.key[{current, k}] = line_no;
  }
}

}  // namespace

EdsFile parse_eds(std::string_view text) {
  EdsFile eds;
  Lines lines;
  read_sections(text, eds, lines);

  auto is_hex = [](const std::string& s) {
    return !s.empty() &&
           std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isxdigit(c); });
  };

  for (const auto& [name, values] : eds.sections) {
    // Object sections are "[iiii]" and "[iiiisubs]" (CiA 306 4.6.3); the others (FileInfo,
    // DeviceInfo, lists, "[iiiiName]" of compact arrays, ...) carry no entry.
    if (name.size() < 4 || !is_hex(name.substr(0, 4))) continue;
    uint16_t index = static_cast<uint16_t>(std::stoul(name.substr(0, 4), nullptr, 16));
    int sub = -1;
    if (name.size() > 4) {
      if (name.compare(4, 3, "sub") != 0) continue;
      std::string digits = name.substr(7);
      if (!is_hex(digits) || digits.size() > 2)
        fail(lines.section.at(name), "[" + name + "] is not a sub-index section (sub 0..FF)");
      sub = static_cast<int>(std::stoul(digits, nullptr, 16));
    }
    auto type_it = values.find("datatype");
    if (sub < 0) {
      // An ARRAY/RECORD header (it may carry a DataType when its sub-entries are compact).
      auto code = values.find("objecttype");
      unsigned long object_type =
          code == values.end()
              ? 0x7
              : number(code->second, lines.of(name, "objecttype"), "[" + name + "] ObjectType");
      if (object_type == 0x8 || object_type == 0x9) continue;
      if (object_type != 0x7 && object_type != 0x2) continue;  // DEFTYPE, DEFSTRUCT, NULL
    }
    if (type_it == values.end()) fail(lines.section.at(name), "[" + name + "] has no DataType");
    EdsEntry e;
    e.index = index;
    e.sub = static_cast<uint8_t>(sub < 0 ? 0 : sub);
    e.name = key(values, "ParameterName", name, lines);
    if (sub >= 0) {
      auto parent = eds.sections.find(name.substr(0, 4));
      if (parent != eds.sections.end() && parent->second.contains("parametername"))
        e.name = parent->second.at("parametername") + " / " + e.name;
    }
    unsigned long type =
        number(type_it->second, lines.of(name, "datatype"), "[" + name + "] DataType");
    if (type > 0xFFFF) fail(lines.of(name, "datatype"), "[" + name + "] DataType is not 16-bit");
    e.type = static_cast<DataType>(type);
    e.access = parse_access(key(values, "AccessType", name, lines), lines.of(name, "accesstype"),
                            "[" + name + "]");
    auto pdo = values.find("pdomapping");
    if (pdo != values.end())
      e.pdo_mappable =
          number(pdo->second, lines.of(name, "pdomapping"), "[" + name + "] PDOMapping") != 0;
    auto def = values.find("defaultvalue");
    if (def != values.end()) e.default_value = def->second;
    eds.entries[{e.index, e.sub}] = e;
  }
  return eds;
}

}  // namespace stepnode::od
