// The LSS slave's non-volatile memory (CiA 305 store configuration): the node-ID and the
// bit timing a master configured, kept in a small file of the state directory and read at
// the next start. The file is named after the device's identity (vendor-ID, product code,
// serial number), so identical nodes sharing one state directory keep theirs apart, and it
// does not depend on the node-ID it holds.
#pragma once
#include <cstdint>
#include <filesystem>
#include <optional>

#include "node/lss_slave.hpp"

namespace stepnode::node {

class LssStore {
 public:
  struct Contents {
    uint8_t node_id = lss::kUnconfigured;  // 1..127, or lss::kUnconfigured
    std::optional<uint8_t> bit_timing;     // CiA 305 table index, when one was configured
    bool operator==(const Contents&) const = default;
  };

  LssStore(const std::filesystem::path& state_dir, const lss::Identity& identity);

  // What was stored; nullopt when nothing was (first start) or the file is not a valid
  // one (logged, and then ignored: the other sources of the node-ID apply).
  std::optional<Contents> load() const;
  // False (logged) when the file cannot be written: the store configuration answer is
  // then "storage media access error".
  bool save(const Contents& contents) const;

  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
};

}  // namespace stepnode::node
