#include "config/toml_file.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <utility>

namespace stepnode::config {

std::string one_line(std::string_view text) {
  std::string out;
  for (unsigned char c : text) {
    if (c == '\n' || c == '\r' || c == '\t') {
      out += ' ';
    } else if (c < 0x20 || c >= 0x7F) {
      char esc[8];
      std::snprintf(esc, sizeof esc, "\\x%02X", c);
      out += esc;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out;
}

TomlFile::TomlFile(std::string path) : path_(std::move(path)) {
  // A directory or a missing file: toml++ would say something less clear.
  if (!std::filesystem::is_regular_file(path_))
    throw UsageError("config " + path_ + ": cannot read file");
  try {
    table_ = toml::parse_file(path_);
  } catch (const toml::parse_error& e) {
    std::ostringstream msg;
    msg << "config " << path_ << ": " << one_line(e.description());
    if (e.source().begin) msg << " (line " << e.source().begin.line << ")";
    throw UsageError(msg.str());
  }
}

void TomlFile::refuse(std::string_view key, std::string_view rule) const {
  throw UsageError("config " + path_ + ": " + std::string(key) + ": " + std::string(rule));
}

std::optional<std::string> TomlFile::string(std::string_view key) const {
  const toml::node* n = table_.get(key);
  if (!n) return std::nullopt;
  if (!n->is_string()) refuse(key, "must be a string");
  return *n->value_exact<std::string>();
}

std::optional<bool> TomlFile::boolean(std::string_view key) const {
  const toml::node* n = table_.get(key);
  if (!n) return std::nullopt;
  if (!n->is_boolean()) refuse(key, "must be true or false");
  return *n->value_exact<bool>();
}

std::optional<int64_t> TomlFile::integer(std::string_view key, int64_t min, int64_t max) const {
  const toml::node* n = table_.get(key);
  if (!n) return std::nullopt;
  const std::optional<int64_t> v = n->is_integer() ? n->value_exact<int64_t>() : std::nullopt;
  if (!v || *v < min || *v > max)
    refuse(key, "must be an integer " + std::to_string(min) + ".." + std::to_string(max));
  return v;
}

void TomlFile::refuse_unknown_keys(std::initializer_list<std::string_view> known) const {
  for (const auto& [key, value] : table_)
    if (std::find(known.begin(), known.end(), key.str()) == known.end())
      refuse(key.str(), "unknown key");
}

}  // namespace stepnode::config
