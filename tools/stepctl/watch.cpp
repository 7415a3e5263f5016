#include "tools/stepctl/watch.hpp"

#include <cstdio>
#include <map>
#include <memory>

#include "tools/stepctl/frame_decoder.hpp"
#include "tools/stepctl/master_bus.hpp"

namespace stepnode::tools {
namespace {

// An SDO server has one channel for one client (CiA 301 7.2.4.1): reading mappings while
// another master talks to the node would break both transfers, so the watch waits until
// the node's SDO channel has been quiet for this long.
constexpr uint64_t kSdoQuietUs = 300'000;

struct NodeView {
  bool mapping_known = false;
  uint64_t last_sdo_us = 0;
  uint64_t hide_sdo_until_ns = 0;  // kernel timestamps of our own discovery traffic
};

// Reads every valid PDO's COB-ID and mapping. Returns false when a transfer failed for a
// reason other than "no such PDO" (busy channel, timeout): the caller tries again later.
bool discover_pdos(MasterBus& sdo, FrameDecoder& decoder, uint8_t node, unsigned& count) {
  decoder.forget_node(node);
  count = 0;
  for (bool transmit : {true, false}) {
    uint16_t comm = transmit ? 0x1800 : 0x1400, map = transmit ? 0x1A00 : 0x1600;
    for (unsigned n = 0; n < 512; ++n) {
      od::SdoResult id = sdo.upload(node, static_cast<uint16_t>(comm + n), 1);
      if (id.abort == od::SdoAbort::NoObject) break;  // no more PDOs
      if (!id.ok()) return false;
      uint32_t cob = od::decode<uint32_t>(id.data);
      if (cob & 0x80000000u) continue;
      od::SdoResult size = sdo.upload(node, static_cast<uint16_t>(map + n), 0);
      if (!size.ok() || size.data.empty()) return false;
      PdoLayout layout{node, transmit, n + 1, {}};
      for (uint8_t i = 1; i <= size.data[0] && i <= 8; ++i) {
        od::SdoResult w = sdo.upload(node, static_cast<uint16_t>(map + n), i);
        if (!w.ok()) return false;
        layout.mapping.push_back(od::MappedEntry::from_word(od::decode<uint32_t>(w.data)));
      }
      decoder.learn(cob & 0x7FF, layout);
      ++count;
    }
  }
  return true;
}

uint64_t realtime_ns() {
  timespec ts;
  ::clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1'000'000'000u + static_cast<uint64_t>(ts.tv_nsec);
}

}  // namespace

int run_watch(const std::string& iface, const ObjectCatalog& catalog, bool passive, int seconds) {
  MasterBus bus(iface);
  std::unique_ptr<MasterBus> sdo;
  if (!passive) sdo = std::make_unique<MasterBus>(iface);
  FrameDecoder decoder(catalog);
  std::map<uint8_t, NodeView> nodes;
  uint64_t start = monotonic_us();
  uint64_t end = seconds > 0 ? start + static_cast<uint64_t>(seconds) * 1'000'000 : UINT64_MAX;
  while (monotonic_us() < end) {
    auto r = bus.receive(100);
    if (!r) continue;
    const od::CanFrame& f = r->frame;
    uint64_t now = monotonic_us();
    bool sdo_frame = (f.id > 0x580 && f.id < 0x600) || (f.id > 0x600 && f.id < 0x680);
    uint8_t sdo_node = static_cast<uint8_t>(f.id & 0x7F);
    if (sdo_frame) {
      NodeView& v = nodes[sdo_node];
      if (r->kernel_time_ns && r->kernel_time_ns <= v.hide_sdo_until_ns) continue;
      v.last_sdo_us = now;
      // A master rewrote a PDO parameter: read the mapping again.
      if (f.id < 0x600 && f.data[0] == 0x60) {
        uint16_t index = od::get_u16(f.data.data() + 1);
        if (index >= 0x1400 && index <= 0x1BFF) v.mapping_known = false;
      }
    }
    std::printf("%10.3f  %03X [%u] %-23s  %s\n", static_cast<double>(now - start) / 1e6, f.id,
                f.dlc, hex_bytes(f.data.data(), f.dlc).c_str(), decoder.describe(f).c_str());
    std::fflush(stdout);
    if (!sdo || f.id <= 0x700 || f.id >= 0x780 || f.dlc != 1) continue;
    uint8_t node = static_cast<uint8_t>(f.id - 0x700);
    NodeView& v = nodes[node];
    if (f.data[0] == 0x00) v.mapping_known = false;  // boot-up: mapping back to stored
    if (v.mapping_known || f.data[0] == 0x04 || f.data[0] == 0x00) continue;  // stopped: no SDO
    if (now - v.last_sdo_us < kSdoQuietUs && v.last_sdo_us != 0) continue;
    unsigned count = 0;
    v.mapping_known = discover_pdos(*sdo, decoder, node, count);
    v.hide_sdo_until_ns = realtime_ns();
    v.last_sdo_us = monotonic_us();
    if (v.mapping_known)
      std::printf("%10.3f  (read the mapping of node %u's %u valid PDOs over SDO)\n",
                  static_cast<double>(monotonic_us() - start) / 1e6, node, count);
  }
  return 0;
}

}  // namespace stepnode::tools
