// Store/restore of parameters (CiA 301 7.5.2.13/14, objects 0x1010/0x1011) in a file of
// the state directory. Saving is atomic: a temporary file is written, fsynced and renamed
// over the old one, so a crash mid-save leaves the previous file intact.
#pragma once
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

#include "od/dictionary.hpp"

namespace stepnode::node {

class ParameterStore {
 public:
  ParameterStore(od::Dictionary& dictionary, std::filesystem::path file);

  // 0x1010 sub: saves the persistent entries in [first,last], keeping other stored values.
  // Returns false (and logs) when the file cannot be written.
  bool save(uint16_t first, uint16_t last);
  // 0x1011 sub: forgets the stored values in [first,last]; defaults apply after the next
  // reset or restart, as CiA 301 asks.
  bool forget(uint16_t first, uint16_t last);
  // Puts defaults then stored values into [first,last] of the dictionary. A missing file
  // is normal (first start); unreadable lines are skipped with a warning.
  void load_into_dictionary(uint16_t first, uint16_t last);

  const std::filesystem::path& file() const { return file_; }

 private:
  using Key = std::pair<uint16_t, uint8_t>;
  std::map<Key, od::Bytes> read_file() const;
  bool write_file(const std::map<Key, od::Bytes>& values) const;

  od::Dictionary& dictionary_;
  std::filesystem::path file_;
};

}  // namespace stepnode::node
