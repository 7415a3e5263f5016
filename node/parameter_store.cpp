#include "node/parameter_store.hpp"

#include <spdlog/spdlog.h>

#include <charconv>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "node/atomic_file.hpp"

namespace stepnode::node {
namespace {

// One line per entry: "IIII:SS HEXBYTES" (index, sub-index, value bytes in hex), between
// the header and the checksum line.
constexpr std::string_view kHeaderV1 = "# stepnode stored parameters v1";
constexpr std::string_view kHeader = "# stepnode stored parameters v2";
constexpr std::string_view kCrcPrefix = "# crc32 ";

// CRC-32 (IEEE 802.3, reflected 0xEDB88320): the file is small and read once per reset.
uint32_t crc32(std::string_view text) {
  uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char c : text) {
    crc ^= c;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

std::string with_suffix(const std::filesystem::path& p, const std::string& suffix) {
  return p.string() + suffix;
}

std::string to_hex(const od::Bytes& bytes) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (uint8_t b : bytes) {
    s += digits[b >> 4];
    s += digits[b & 15];
  }
  return s.empty() ? "-" : s;
}

bool from_hex(const std::string& text, od::Bytes& out) {
  out.clear();
  if (text == "-") return true;
  if (text.size() % 2) return false;
  for (size_t i = 0; i < text.size(); i += 2) {
    unsigned v = 0;
    if (std::sscanf(text.c_str() + i, "%2x", &v) != 1) return false;
    out.push_back(static_cast<uint8_t>(v));
  }
  return true;
}

}  // namespace

ParameterStore::ParameterStore(od::Dictionary& dictionary, std::filesystem::path file)
    : dictionary_(dictionary), file_(std::move(file)) {}

ParameterStore::Contents ParameterStore::read_file() const {
  Contents out;
  std::ifstream in(file_, std::ios::binary);
  if (!in) return out;  // first start: nothing stored
  std::stringstream whole;
  whole << in.rdbuf();
  const std::string text = whole.str();
  // Version 2 ends with the checksum of everything before its line; version 1 has none.
  std::string_view body = text;
  auto header_line = [&](std::string_view header) {
    if (!body.starts_with(header)) return false;
    std::string_view rest = body.substr(header.size());
    return rest.empty() || rest.starts_with("\n") || rest.starts_with("\r\n");
  };
  if (!header_line(kHeaderV1)) {
    const size_t last = body.rfind(kCrcPrefix);
    const size_t digits = last + kCrcPrefix.size();
    uint32_t stored = 0;
    const bool crc_line =
        last != std::string_view::npos && digits + 9 == text.size() && text.back() == '\n' &&
        std::from_chars(text.data() + digits, text.data() + digits + 8, stored, 16).ptr ==
            text.data() + digits + 8;
    if (!header_line(kHeader) || !crc_line || crc32(body.substr(0, last)) != stored) {
      out.damaged = true;
      return out;
    }
    body = body.substr(0, last);
  }
  std::istringstream lines{std::string(body)};
  std::string line;
  int line_no = 0;
  while (std::getline(lines, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string key, hex;
    unsigned index = 0, sub = 0;
    od::Bytes bytes;
    if (!(fields >> key >> hex) || std::sscanf(key.c_str(), "%4x:%2x", &index, &sub) != 2 ||
        !from_hex(hex, bytes)) {
      // Only a version 1 file gets here damaged (version 2 passed its checksum).
      spdlog::warn("{}:{}: unreadable stored parameter line skipped", file_.string(), line_no);
      continue;
    }
    out.values[{static_cast<uint16_t>(index), static_cast<uint8_t>(sub)}] = std::move(bytes);
  }
  return out;
}

std::optional<std::filesystem::path> ParameterStore::set_aside() const {
  // Kept for whoever wants to look at it, under the first free name.
  for (int n = 1; n <= 1000; ++n) {
    std::filesystem::path to = with_suffix(file_, ".corrupt-" + std::to_string(n));
    std::error_code ec;
    if (std::filesystem::exists(to, ec)) continue;
    std::filesystem::rename(file_, to, ec);
    if (!ec) return to;
    spdlog::error("cannot set aside {}: {}", file_.string(), ec.message());
    return std::nullopt;
  }
  spdlog::error("cannot set aside {}: {}.corrupt-1..1000 all exist", file_.string(),
                file_.string());
  return std::nullopt;
}

bool ParameterStore::write_file(const std::map<Key, od::Bytes>& values) const {
  std::ostringstream text;
  text << kHeader << "\n";
  for (const auto& [key, bytes] : values) {
    char head[16];
    std::snprintf(head, sizeof head, "%04X:%02X ", key.first, key.second);
    text << head << to_hex(bytes) << "\n";
  }
  char crc[32];
  std::snprintf(crc, sizeof crc, "%s%08x\n", std::string(kCrcPrefix).c_str(), crc32(text.str()));
  text << crc;
  std::string error;
  if (!write_file_atomically(file_, text.str(), error)) {
    spdlog::error("cannot save parameters: {}", error);
    return false;
  }
  return true;
}

bool ParameterStore::save(uint16_t first, uint16_t last) {
  // A damaged file contributes nothing: the save writes a whole, good file over it.
  auto values = read_file().values;
  for (const auto& [index, obj] : dictionary_.objects()) {
    if (index < first || index > last) continue;
    for (const auto& [sub, e] : obj.entries)
      if (e.persistent) values[{index, sub}] = e.value;
  }
  return write_file(values);
}

bool ParameterStore::forget(uint16_t first, uint16_t last) {
  auto values = read_file().values;
  std::erase_if(values,
                [&](const auto& kv) { return kv.first.first >= first && kv.first.first <= last; });
  return write_file(values);
}

ParameterStore::LoadReport ParameterStore::load_into_dictionary(uint16_t first, uint16_t last) {
  LoadReport report;
  // A save that crashed left its temporary file; the real file is the one that counts.
  std::error_code ec;
  std::filesystem::remove(with_suffix(file_, ".tmp"), ec);
  dictionary_.reset_to_defaults(first, last);
  Contents stored = read_file();
  if (stored.damaged) {
    spdlog::error(
        "{} is not a valid stepnode parameter file (damaged or foreign): set aside, defaults apply",
        file_.string());
    report.set_aside = set_aside();
    report.damaged = true;
    return report;
  }
  for (const auto& [key, bytes] : stored.values) {
    if (key.first < first || key.first > last) continue;
    od::Entry* e = dictionary_.find(key.first, key.second);
    // Restored values skip the validate hooks (the mapping procedure's ordering rules do
    // not apply to a consistent saved set) but must still fit the entry.
    if (!e || !e->persistent || od::check_value(*e, bytes) != od::SdoAbort::None) {
      spdlog::warn("stored value for {:04X}:{:02X} does not fit the dictionary; default kept",
                   key.first, key.second);
      report.refuse(key);
      continue;
    }
    e->value = bytes;
  }
  return report;
}

}  // namespace stepnode::node
