// The SDO server parameter objects 0x1200..0x1203 (CiA 301 7.5.2.33): one per SDO server
// channel. 0x1200 is the default channel of the pre-defined connection set (0x600+id /
// 0x580+id, read-only); 0x1201..0x1203 are extra channels an integrator gives to further
// clients (a second master, a bridge), since one channel serves one client at a time.
#pragma once
#include <cstdint>

#include "od/dictionary.hpp"

namespace stepnode::od {

constexpr uint16_t kSdoServerParameter = 0x1200;
constexpr unsigned kSdoServerChannels = 4;  // 0x1200..0x1203
namespace sdo_param {
constexpr uint8_t kCobIdClientToServer = 1;  // the server receives on it (rx)
constexpr uint8_t kCobIdServerToClient = 2;  // the server answers on it (tx)
constexpr uint8_t kClientNodeId = 3;         // node-ID of the SDO client (0x1201.. only)
}  // namespace sdo_param

// Adds 0x1200 and 0x1201..0x1203. The extra channels start disabled (both COB-IDs with bit
// 31 set) and are rw, so 0x1010 stores them; a COB-ID change while it is valid is refused
// (set bit 31 first), as for PDOs.
void add_sdo_server_parameters(Dictionary& od, uint8_t node_id);

// One channel's COB-IDs as the dictionary holds them now.
struct SdoChannelIds {
  uint32_t rx = 0;     // client -> server CAN-ID (11 bit)
  uint32_t tx = 0;     // server -> client CAN-ID
  bool valid = false;  // both COB-IDs valid (bit 31 clear)
};
SdoChannelIds sdo_channel_ids(const Dictionary& od, unsigned channel);

}  // namespace stepnode::od
