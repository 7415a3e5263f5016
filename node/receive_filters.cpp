#include "node/receive_filters.hpp"

#include <algorithm>

#include "node/lss_slave.hpp"
#include "od/can_frame.hpp"
#include "od/cob_id.hpp"
#include "od/communication_objects.hpp"
#include "od/pdo_mapping.hpp"
#include "od/sdo_server_parameter.hpp"

namespace stepnode::node {
namespace {

bool valid(uint32_t cob_id) { return !(cob_id & od::kCobInvalid); }

// The services that listen to COB-IDs held in the dictionary.
void add_configured(std::vector<ReceiveFilter>& out, const od::Dictionary& od, unsigned pdo_count) {
  auto add = [&out](uint32_t cob_id) {
    out.push_back({cob_id & 0x7FF, ReceiveFilter::Frames::Data});
  };
  add(od.get<uint32_t>(
      0x1005, 0));  // SYNC: consumed whatever bit 31 says (the producer is not its own consumer)
  if (const uint32_t time = od.get<uint32_t>(0x1012, 0); time & 0x80000000u)
    add(time);  // bit 31: consumer
  // EMCY 0x1014: this node's own COB-ID; another device sending on it is a node-ID conflict.
  if (const uint32_t emcy = od.get<uint32_t>(0x1014, 0); valid(emcy)) add(emcy);
  // Heartbeat consumers 0x1016: node-ID in bits 16..23, time in 0..15; 0 of either is unused.
  for (uint8_t s = 1; s <= od.get<uint8_t>(0x1016, 0); ++s) {
    const uint32_t v = od.get<uint32_t>(0x1016, s);
    const uint32_t node = (v >> 16) & 0xFF;
    if (node != 0 && node <= 127 && (v & 0xFFFF) != 0) add(od::cob::kHeartbeat + node);
  }
  for (unsigned ch = 0; ch < od::kSdoServerChannels; ++ch)
    if (const od::SdoChannelIds ids = od::sdo_channel_ids(od, ch); ids.valid) add(ids.rx);
  // RPDOs with something mapped (an empty one is silent: CiA 301 7.5.2.36), and the remote
  // frames that ask for a TPDO whose COB-ID allows them (bit 30 = 0).
  for (unsigned n = 0; n < pdo_count; ++n) {
    const uint32_t cob = od.get<uint32_t>(od::rpdo_parameter(n), 1);
    if (valid(cob) && od.get<uint8_t>(od::rpdo_mapping(n), 0) != 0) add(cob);
    const uint32_t tpdo = od.get<uint32_t>(od::tpdo_parameter(n), 1);
    if (valid(tpdo) && (tpdo & od::kCobGenerate) == 0 &&
        od.get<uint8_t>(od::tpdo_mapping(n), 0) != 0)
      out.push_back({tpdo & 0x7FF, ReceiveFilter::Frames::DataAndRemote});
  }
}

}  // namespace

std::vector<ReceiveFilter> receive_filters(const od::Dictionary& od, uint8_t node_id,
                                           unsigned pdo_count) {
  std::vector<ReceiveFilter> out{{lss::kMasterToSlave, ReceiveFilter::Frames::Data},
                                 {od::cob::kNmt, ReceiveFilter::Frames::Data}};
  if (node_id != lss::kUnconfigured) {
    // Node guarding requests (remote) and another device's boot-up or heartbeat (data).
    out.push_back({od::cob::kHeartbeat + node_id, ReceiveFilter::Frames::DataAndRemote});
    // Another device's SDO answer on this node's default server channel: a conflict.
    out.push_back({od::cob::kSdoTx + node_id, ReceiveFilter::Frames::Data});
    add_configured(out, od, pdo_count);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  // 0x700+id as data and remote covers its data-only twin (a heartbeat consumer of itself).
  // (Sorted: Data before DataAndRemote, so the first of two with one id is dropped.)
  for (size_t i = 1; i < out.size();) {
    if (out[i].id == out[i - 1].id) out.erase(out.begin() + static_cast<long>(i - 1));
    else ++i;
  }
  if (out.size() > kMaxReceiveFilters) out.clear();
  return out;
}

}  // namespace stepnode::node
