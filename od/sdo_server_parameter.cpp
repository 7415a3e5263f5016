#include "od/sdo_server_parameter.hpp"

#include <string>

#include "od/can_frame.hpp"
#include "od/cob_id.hpp"

namespace stepnode::od {
namespace {

constexpr uint8_t kMaxClientNodeId = 127;

void add_default_channel(Dictionary& od, uint8_t node_id) {
  Object& sdo = od.record(kSdoServerParameter, "SDO server parameter");
  Entry& rx =
      sdo.add(sdo_param::kCobIdClientToServer, "COB-ID client to server", DataType::Unsigned32,
              Access::ReadOnly, encode<uint32_t>(cob::kSdoRx + node_id));
  Entry& tx =
      sdo.add(sdo_param::kCobIdServerToClient, "COB-ID server to client", DataType::Unsigned32,
              Access::ReadOnly, encode<uint32_t>(cob::kSdoTx + node_id));
  rx.eds_default = "$NODEID+0x600";
  tx.eds_default = "$NODEID+0x580";
}

// CiA 301 7.5.2.33: bit 31 valid, bit 30 dynamic (allowed, no meaning to the server),
// bit 29 frame (11-bit only here); the CAN-ID may change only while bit 31 is set.
void add_cob_id(Object& sdo, uint8_t sub, const char* name) {
  Entry& e =
      sdo.add(sub, name, DataType::Unsigned32, Access::ReadWrite, encode<uint32_t>(kCobInvalid));
  e.validate = [&e](std::span<const uint8_t> d) {
    return check_cob_id(decode<uint32_t>(e.value), decode<uint32_t>(d), kCobInvalid);
  };
}

void add_extra_channel(Dictionary& od, unsigned channel) {
  const auto index = static_cast<uint16_t>(kSdoServerParameter + channel);
  Object& sdo = od.record(index, "SDO server parameter " + std::to_string(channel + 1));
  add_cob_id(sdo, sdo_param::kCobIdClientToServer, "COB-ID client to server");
  add_cob_id(sdo, sdo_param::kCobIdServerToClient, "COB-ID server to client");
  // 0 = no client named yet; a client picks its channel by this entry (1..127).
  limits<uint8_t>(sdo.add(sdo_param::kClientNodeId, "Node-ID of the SDO client",
                          DataType::Unsigned8, Access::ReadWrite, encode<uint8_t>(0)),
                  0, kMaxClientNodeId);
}

}  // namespace

void add_sdo_server_parameters(Dictionary& od, uint8_t node_id) {
  add_default_channel(od, node_id);
  for (unsigned channel = 1; channel < kSdoServerChannels; ++channel)
    add_extra_channel(od, channel);
}

SdoChannelIds sdo_channel_ids(const Dictionary& od, unsigned channel) {
  const auto index = static_cast<uint16_t>(kSdoServerParameter + channel);
  const auto rx = od.get<uint32_t>(index, sdo_param::kCobIdClientToServer);
  const auto tx = od.get<uint32_t>(index, sdo_param::kCobIdServerToClient);
  return SdoChannelIds{rx & 0x7FF, tx & 0x7FF, !(rx & kCobInvalid) && !(tx & kCobInvalid)};
}

}  // namespace stepnode::od
