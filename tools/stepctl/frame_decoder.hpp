// Turns bus traffic into words for `stepctl watch`: NMT, SYNC, EMCY, heartbeat, SDO and
// PDOs by their mapping (learned from the nodes over SDO).
#pragma once
#include <array>
#include <cstdint>
#include <map>
#include <optional>
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
  // Not const: a block transfer's sub-block segments carry no command specifier, so where a
  // node's block transfer stands is followed from frame to frame.
  std::string describe(const od::CanFrame& frame);

 private:
  // Where a node's SDO block transfer stands (CiA 301 7.2.4.3.10-17): while its sub-blocks
  // run, a frame of the sender is a segment (c, seqno, 7 bytes), not a command.
  enum class Block : uint8_t {
    None,
    Download,      // the client's segments
    DownloadLast,  // ... the last one (c) sent: the server's ack ends the data
    DownloadEnd,   // the client's end request next
    Upload,        // the server's segments (after the client's start)
    UploadLast,    // ... the last one sent
    UploadEnd,     // the server's end request, then the client's end response
  };
  std::optional<std::string> describe_block(const od::CanFrame& frame, bool request, uint8_t node);
  std::string describe_sdo(const od::CanFrame& frame, bool request);
  std::string describe_pdo(const od::CanFrame& frame) const;
  std::string object_name(uint16_t index, uint8_t sub) const;

  const ObjectCatalog& catalog_;
  std::map<uint32_t, PdoLayout> pdos_;
  std::array<Block, 128> blocks_{};
};

std::string hex_bytes(const uint8_t* data, size_t n);

}  // namespace stepnode::tools
