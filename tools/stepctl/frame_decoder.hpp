// Turns bus traffic into words for `stepctl watch`: NMT, SYNC, EMCY, heartbeat, SDO and
// PDOs by their mapping (learned from the nodes over SDO).
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "od/can_frame.hpp"
#include "od/pdo_mapping.hpp"
#include "tools/stepctl/object_catalog.hpp"

namespace stepnode::tools {

struct PdoLayout {
  uint8_t node = 0;
  bool transmit = true;  // TPDO of the node (else RPDO)
  unsigned number = 1;   // 1-based
  od::PdoMapping mapping;
};

class FrameDecoder {
 public:
  explicit FrameDecoder(const ObjectCatalog& catalog) : catalog_(catalog) {}
  void learn(uint32_t cob_id, PdoLayout layout) { pdos_[cob_id] = std::move(layout); }
  void forget_node(uint8_t node);
  std::string describe(const od::CanFrame& frame) const;

 private:
  std::string describe_sdo(const od::CanFrame& frame, bool request) const;
  std::string describe_pdo(const od::CanFrame& frame) const;
  std::string object_name(uint16_t index, uint8_t sub) const;

  const ObjectCatalog& catalog_;
  std::map<uint32_t, PdoLayout> pdos_;
};

std::string hex_bytes(const uint8_t* data, size_t n);

}  // namespace stepnode::tools
