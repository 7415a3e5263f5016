// The TOML config files of stepnode and stepbridge: read, parsed and checked key by key
// with one set of rules and messages (toml++). Knows nothing of either process's keys.
#pragma once
#include <toml++/toml.h>

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace stepnode::config {

// Bad input at the process edge (an argument, a config file): the process prints the
// message as one line and exits with status 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// `text` as one printable line: line breaks and tabs become spaces, other control bytes
// and bytes outside ASCII become \xNN (toml++ copies the offending bytes of a file into
// its message; stderr gets one line whatever the file held).
std::string one_line(std::string_view text);

// A config file, parsed. Every refusal is a UsageError that names the file:
// "config PATH: cannot read file", "config PATH: <the parser's message> (line N)",
// "config PATH: KEY: RULE".
class TomlFile {
 public:
  explicit TomlFile(std::string path);

  const std::string& path() const { return path_; }
  const toml::table& table() const { return table_; }
  bool has(std::string_view key) const { return table_.contains(key); }

  // Refuses the file: "config PATH: KEY: RULE".
  [[noreturn]] void refuse(std::string_view key, std::string_view rule) const;

  // A key's value when the file has the key (nullopt when it does not). A value of another
  // type, or out of [min, max], refuses the file: "must be a string", "must be true or
  // false", "must be an integer MIN..MAX". No conversions: 5.0 is no integer, 1 no boolean.
  std::optional<std::string> string(std::string_view key) const;
  std::optional<bool> boolean(std::string_view key) const;
  std::optional<int64_t> integer(std::string_view key, int64_t min, int64_t max) const;

  // Refuses the first top-level key not in `known`: "KEY: unknown key".
  void refuse_unknown_keys(std::initializer_list<std::string_view> known) const;

 private:
  std::string path_;
  toml::table table_;
};

}  // namespace stepnode::config
