// Store/restore of parameters (CiA 301 7.5.2.13/14, objects 0x1010/0x1011) in a file of
// the state directory. Saving is atomic: a temporary file is written, fsynced and renamed
// over the old one, so a crash mid-save leaves the previous file intact.
//
// The file is versioned and checksummed: "# stepnode stored parameters v2", one line per
// entry, and a last line "# crc32 XXXXXXXX" over everything before it. A file that is not
// ours, or whose checksum fails, is set aside (renamed to .corrupt-N) and defaults apply;
// files of version 1 (no checksum, written by earlier builds) still load.
#pragma once
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include "od/dictionary.hpp"

namespace stepnode::node {

class ParameterStore {
 public:
  using Key = std::pair<uint16_t, uint8_t>;

  // What a load found: the node reports a problem as EMCY 0x5530 (data storage).
  struct LoadReport {
    bool damaged = false;                            // a corrupt or foreign file: not loaded
    std::optional<std::filesystem::path> set_aside;  // ... and renamed to this (if it could be)
    unsigned refused = 0;                            // stored values the dictionary refused
    std::optional<Key> first_refused;
    void refuse(Key key) {
      if (refused++ == 0) first_refused = key;
    }
    bool problem() const { return damaged || refused > 0; }
  };

  ParameterStore(od::Dictionary& dictionary, std::filesystem::path file);

  // 0x1010 sub: saves the persistent entries in [first,last], keeping other stored values.
  // Returns false (and logs) when the file cannot be written.
  bool save(uint16_t first, uint16_t last);
  // 0x1011 sub: forgets the stored values in [first,last]; defaults apply after the next
  // reset or restart, as CiA 301 asks.
  bool forget(uint16_t first, uint16_t last);
  // Puts defaults then stored values into [first,last] of the dictionary. A missing file
  // is normal (first start); a leftover temporary file of a crashed save is removed. A
  // value that does not fit its entry keeps the default and counts as refused.
  LoadReport load_into_dictionary(uint16_t first, uint16_t last);

  const std::filesystem::path& file() const { return file_; }
  // The node-ID changed (LSS): the parameters stored for the new one apply from now on.
  void set_file(std::filesystem::path file) { file_ = std::move(file); }

 private:
  struct Contents {
    std::map<Key, od::Bytes> values;
    bool damaged = false;  // not a stepnode parameter file, or its checksum failed
  };
  Contents read_file() const;
  bool write_file(const std::map<Key, od::Bytes>& values) const;
  std::optional<std::filesystem::path> set_aside() const;

  od::Dictionary& dictionary_;
  std::filesystem::path file_;
};

}  // namespace stepnode::node
