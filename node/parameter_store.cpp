#include "node/parameter_store.hpp"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

namespace stepnode::node {
namespace {

// One line per entry: "IIII:SS HEXBYTES" (index, sub-index, value bytes in hex).
constexpr const char* kHeader = "# stepnode stored parameters v1";

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

bool write_all(int fd, const std::string& data) {
  size_t done = 0;
  while (done < data.size()) {
    ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<size_t>(n);
  }
  return true;
}

}  // namespace

ParameterStore::ParameterStore(od::Dictionary& dictionary, std::filesystem::path file)
    : dictionary_(dictionary), file_(std::move(file)) {}

std::map<ParameterStore::Key, od::Bytes> ParameterStore::read_file() const {
  std::map<Key, od::Bytes> values;
  std::ifstream in(file_);
  if (!in) return values;  // first start: nothing stored
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string key, hex;
    unsigned index = 0, sub = 0;
    od::Bytes bytes;
    if (!(fields >> key >> hex) || std::sscanf(key.c_str(), "%4x:%2x", &index, &sub) != 2 ||
        !from_hex(hex, bytes)) {
      spdlog::warn("{}:{}: unreadable stored parameter line skipped", file_.string(), line_no);
      continue;
    }
    values[{static_cast<uint16_t>(index), static_cast<uint8_t>(sub)}] = std::move(bytes);
  }
  return values;
}

bool ParameterStore::write_file(const std::map<Key, od::Bytes>& values) const {
  std::ostringstream text;
  text << kHeader << "\n";
  for (const auto& [key, bytes] : values) {
    char head[16];
    std::snprintf(head, sizeof head, "%04X:%02X ", key.first, key.second);
    text << head << to_hex(bytes) << "\n";
  }
  std::error_code ec;
  std::filesystem::create_directories(file_.parent_path(), ec);
  std::filesystem::path tmp = file_;
  tmp += ".tmp";
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    spdlog::error("cannot save parameters: {}: {}", tmp.string(), std::strerror(errno));
    return false;
  }
  bool ok = write_all(fd, text.str()) && ::fsync(fd) == 0;
  ::close(fd);
  if (!ok || std::rename(tmp.c_str(), file_.c_str()) != 0) {
    spdlog::error("cannot save parameters: {}: {}", file_.string(), std::strerror(errno));
    ::unlink(tmp.c_str());
    return false;
  }
  // The rename itself must reach the disk: sync the directory.
  int dir = ::open(file_.parent_path().empty() ? "." : file_.parent_path().c_str(),
                   O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir >= 0) {
    ::fsync(dir);
    ::close(dir);
  }
  return true;
}

bool ParameterStore::save(uint16_t first, uint16_t last) {
  auto values = read_file();
  for (const auto& [index, obj] : dictionary_.objects()) {
    if (index < first || index > last) continue;
    for (const auto& [sub, e] : obj.entries)
      if (e.persistent) values[{index, sub}] = e.value;
  }
  return write_file(values);
}

bool ParameterStore::forget(uint16_t first, uint16_t last) {
  auto values = read_file();
  std::erase_if(values, [&](const auto& kv) { return kv.first.first >= first && kv.first.first <= last; });
  return write_file(values);
}

void ParameterStore::load_into_dictionary(uint16_t first, uint16_t last) {
  dictionary_.reset_to_defaults(first, last);
  for (const auto& [key, bytes] : read_file()) {
    if (key.first < first || key.first > last) continue;
    od::Entry* e = dictionary_.find(key.first, key.second);
    // Restored values skip the validate hooks (the mapping procedure's ordering rules do
    // not apply to a consistent saved set) but must still fit the entry.
    if (!e || !e->persistent || od::check_value(*e, bytes) != od::SdoAbort::None) {
      spdlog::warn("stored value for {:04X}:{:02X} does not fit the dictionary; default kept",
                   key.first, key.second);
      continue;
    }
    e->value = bytes;
  }
}

}  // namespace stepnode::node
