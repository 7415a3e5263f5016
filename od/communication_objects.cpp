#include "od/communication_objects.hpp"

#include <cstdio>
#include <string>
#include <string_view>

#include "od/can_frame.hpp"
#include "od/cob_id.hpp"
#include "od/pdo_mapping.hpp"
#include "od/sdo_server_parameter.hpp"

namespace stepnode::od {
namespace {

using DT = DataType;
using AC = Access;

uint32_t u32(std::span<const uint8_t> d) { return decode<uint32_t>(d); }

std::string hex_index(const char* fmt, unsigned n) {
  char buf[32];
  std::snprintf(buf, sizeof buf, fmt, n);
  return buf;
}

void add_identity(Dictionary& od, const DeviceInfo& info) {
  od.var(0x1000, "Device type", DT::Unsigned32, AC::ReadOnly, encode<uint32_t>(0));
  od.var(0x1001, "Error register", DT::Unsigned8, AC::ReadOnly, {0}, true);
  od.var(0x1008, "Manufacturer device name", DT::VisibleString, AC::Const,
         encode_string(info.device_name));
  od.var(0x1009, "Manufacturer hardware version", DT::VisibleString, AC::Const,
         encode_string(info.hardware_version));
  od.var(0x100A, "Manufacturer software version", DT::VisibleString, AC::Const,
         encode_string(info.software_version));
  Object& id = od.record(0x1018, "Identity object");
  id.add(1, "Vendor-ID", DT::Unsigned32, AC::ReadOnly, encode(info.vendor_id));
  id.add(2, "Product code", DT::Unsigned32, AC::ReadOnly, encode(info.product_code));
  id.add(3, "Revision number", DT::Unsigned32, AC::ReadOnly, encode(info.revision));
  id.add(4, "Serial number", DT::Unsigned32, AC::ReadOnly, encode(info.serial_number));
  // 0x1021: the device serves its own EDS (the node fills it in on read); 0x1022 = ASCII.
  od.var(0x1021, "Store EDS", DT::Domain, AC::ReadOnly, {});
  od.var(0x1022, "Store format", DT::Unsigned8, AC::ReadOnly, {0});
}

void add_error_history(Dictionary& od) {
  Object& hist = od.record(0x1003, "Pre-defined error field", ObjectCode::Array);
  Entry& count = hist.entries.at(0);
  count.name = "Number of errors";
  count.access = AC::ReadWrite;
  count.persistent = false;
  for (unsigned i = 1; i <= kErrorHistoryLength; ++i)
    hist.add(static_cast<uint8_t>(i), hex_index("Standard error field %u", i), DT::Unsigned32,
             AC::ReadOnly, encode<uint32_t>(0));
  // Writing 0 clears the history; any other value is refused (CiA 301 7.5.2.3).
  count.validate = [](std::span<const uint8_t> d) {
    return d[0] == 0 ? SdoAbort::None : SdoAbort::InvalidValue;
  };
  listen(count, [&od] {
    for (unsigned i = 1; i <= kErrorHistoryLength; ++i)
      od.put<uint32_t>(0x1003, static_cast<uint8_t>(i), 0);
  });
}

void add_sync_and_emcy(Dictionary& od, const DeviceInfo& info) {
  Entry& sync = od.var(0x1005, "COB-ID SYNC message", DT::Unsigned32, AC::ReadWrite,
                       encode<uint32_t>(cob::kSync));
  sync.validate = [&od](std::span<const uint8_t> d) {
    uint32_t current = od.get<uint32_t>(0x1005, 0), next = u32(d);
    // CiA 301 7.5.2.5: base frames only (bit 29 and bits 11..28 are 0), the SYNC CAN-ID is
    // not a restricted one (7.3.5), and it may not change while this device produces SYNC.
    if (next & (kCobExtended | kCobIdHighBits)) return SdoAbort::InvalidValue;
    if (is_restricted_can_id(next & 0x7FF)) return SdoAbort::InvalidValue;
    if ((next & 0x7FF) != (current & 0x7FF) && (current & kCobGenerate) && (next & kCobGenerate))
      return SdoAbort::InvalidValue;
    return SdoAbort::None;
  };
  od.var(0x1006, "Communication cycle period", DT::Unsigned32, AC::ReadWrite, encode<uint32_t>(0));
  // CiA 301 7.5.2.8: the window (us) after a SYNC in which synchronous PDOs are sent and
  // accepted; 0 = not used.
  od.var(kSyncWindowLength, "Synchronous window length", DT::Unsigned32, AC::ReadWrite,
         encode<uint32_t>(0));
  Entry& overflow =
      od.var(0x1019, "Synchronous counter overflow value", DT::Unsigned8, AC::ReadWrite, {0});
  // 0 = no counter, 2..240 = counter range; 1 and 241..255 are reserved. The value may
  // only change while the SYNC cycle period is 0 (CiA 301 7.5.2.22).
  overflow.validate = [&od](std::span<const uint8_t> d) {
    if (d[0] == 1 || d[0] > 240) return SdoAbort::InvalidValue;
    if (od.get<uint32_t>(0x1006, 0) != 0) return SdoAbort::DeviceState;
    return SdoAbort::None;
  };

  Entry& emcy = od.var(0x1014, "COB-ID EMCY", DT::Unsigned32, AC::ReadWrite,
                       encode<uint32_t>(cob::kEmcyBase + info.node_id));
  emcy.eds_default = "$NODEID+0x80";
  emcy.validate = [&od](std::span<const uint8_t> d) {
    // Bit 30 of the EMCY COB-ID is reserved and 0 (CiA 301 7.5.2.17).
    if (u32(d) & kCobGenerate) return SdoAbort::InvalidValue;
    return check_cob_id(od.get<uint32_t>(0x1014, 0), u32(d), kCobInvalid);
  };
  od.var(0x1015, "Inhibit time EMCY", DT::Unsigned16, AC::ReadWrite, encode<uint16_t>(0));
}

void add_time(Dictionary& od) {
  // CiA 301 7.5.2.14: bit 31 consumes TIME, bit 30 produces it, bit 29 = 29-bit CAN-ID (not
  // supported here). The default: consumer on 0x100.
  Entry& time = od.var(0x1012, "COB-ID time stamp object", DT::Unsigned32, AC::ReadWrite,
                       encode<uint32_t>(kCobInvalid | cob::kTimeStamp));
  time.validate = [&od](std::span<const uint8_t> d) {
    const uint32_t current = od.get<uint32_t>(0x1012, 0), next = u32(d);
    constexpr uint32_t kInUse = kCobInvalid | kCobGenerate;  // consumer, producer
    if (next & (kCobExtended | kCobIdHighBits)) return SdoAbort::InvalidValue;
    if (is_restricted_can_id(next & 0x7FF)) return SdoAbort::InvalidValue;
    // The CAN-ID does not change while the TIME object is consumed or produced.
    if ((next & 0x7FF) != (current & 0x7FF) && (current & kInUse) && (next & kInUse))
      return SdoAbort::InvalidValue;
    return SdoAbort::None;
  };
}

void add_nmt_startup(Dictionary& od) {
  // CiA 302-2 0x1F80 NMT startup. Bit 2 ("NMT master start"): 0 = enter operational by
  // itself after boot-up (a self-starting device), 1 = wait for NMT start, the default, as
  // CiA 301 devices do. The other bits are NMT master functions this device does not have:
  // an attempt to change one is refused with 0x06090030, as CiA 302-2 says.
  Entry& startup = od.var(kNmtStartup, "NMT startup", DT::Unsigned32, AC::ReadWrite,
                          encode<uint32_t>(kNmtStartupNoAutoStart));
  startup.validate = [](std::span<const uint8_t> d) {
    return u32(d) & ~kNmtStartupNoAutoStart ? SdoAbort::InvalidValue : SdoAbort::None;
  };
}

void add_heartbeat(Dictionary& od) {
  Object& consumer = od.record(0x1016, "Consumer heartbeat time", ObjectCode::Array);
  for (unsigned i = 1; i <= kHeartbeatConsumers; ++i) {
    Entry& e = consumer.add(static_cast<uint8_t>(i), hex_index("Consumer heartbeat time %u", i),
                            DT::Unsigned32, AC::ReadWrite, encode<uint32_t>(0));
    // Two active entries may not watch the same node (CiA 301 7.5.2.18: abort 0x06040043).
    e.validate = [&od, i](std::span<const uint8_t> d) {
      uint32_t next = u32(d);
      uint32_t node = (next >> 16) & 0xFF, time = next & 0xFFFF;
      if (next >> 24) return SdoAbort::InvalidValue;
      if (node == 0 || node > 127 || time == 0) return SdoAbort::None;
      for (unsigned j = 1; j <= kHeartbeatConsumers; ++j) {
        if (j == i) continue;
        uint32_t other = od.get<uint32_t>(0x1016, static_cast<uint8_t>(j));
        if (((other >> 16) & 0xFF) == node && (other & 0xFFFF) != 0)
          return SdoAbort::ParameterIncompatible;
      }
      return SdoAbort::None;
    };
  }
  od.var(0x1017, "Producer heartbeat time", DT::Unsigned16, AC::ReadWrite, encode<uint16_t>(1000));
}

void add_node_guarding(Dictionary& od) {
  // CiA 301 7.5.2.11/12: guard time (ms) x life time factor = the node life time; 0 in
  // either: no life guarding. Used only while the heartbeat producer time 0x1017 is 0.
  od.var(0x100C, "Guard time", DT::Unsigned16, AC::ReadWrite, encode<uint16_t>(0));
  od.var(0x100D, "Life time factor", DT::Unsigned8, AC::ReadWrite, {0});
}

void add_error_behaviour(Dictionary& od) {
  // CiA 301 7.5.2.32: what a communication error (heartbeat consumer timeout, bus-off) does
  // to the NMT state: 0 pre-operational (if operational), 1 no change, 2 stopped. 3..0x7F
  // are reserved and 0x80..0xFF manufacturer-specific, of which this device defines none.
  Object& behaviour = od.record(kErrorBehaviour, "Error behaviour", ObjectCode::Array);
  limits<uint8_t>(behaviour.add(kCommunicationErrorSub, "Communication error", DT::Unsigned8,
                                AC::ReadWrite, {kErrorBehaviourPreOperational}),
                  kErrorBehaviourPreOperational, kErrorBehaviourStopped);
}

void add_store_restore(Dictionary& od) {
  Object& store = od.record(0x1010, "Store parameters", ObjectCode::Array);
  Object& restore = od.record(0x1011, "Restore default parameters", ObjectCode::Array);
  for (const auto& g : kParameterGroups) {
    // Reading gives the capability: bit 0 = the device saves on command.
    Entry& s = store.add(g.sub, std::string("Save ") + g.name, DT::Unsigned32, AC::ReadWrite,
                         encode<uint32_t>(1));
    Entry& r = restore.add(g.sub, std::string("Restore ") + g.name, DT::Unsigned32, AC::ReadWrite,
                           encode<uint32_t>(1));
    s.persistent = r.persistent = false;
    s.on_read = r.on_read = [](Bytes& v) { v = encode<uint32_t>(1); };
    // A wrong signature is refused with 0x08000020 (CiA 301 7.5.2.13).
    s.validate = [](std::span<const uint8_t> d) {
      return u32(d) == kSaveSignature ? SdoAbort::None : SdoAbort::DataTransfer;
    };
    r.validate = [](std::span<const uint8_t> d) {
      return u32(d) == kLoadSignature ? SdoAbort::None : SdoAbort::DataTransfer;
    };
  }
}

// Communication + mapping parameters of one PDO, with the CiA 301 reconfiguration rules.
void add_pdo(Dictionary& od, PdoDirection dir, unsigned n, uint8_t node_id) {
  bool rx = dir == PdoDirection::Receive;
  uint16_t comm_index = rx ? rpdo_parameter(n) : tpdo_parameter(n);
  uint16_t map_index = rx ? rpdo_mapping(n) : tpdo_mapping(n);
  const char* kind = rx ? "RPDO" : "TPDO";

  // PDOs 1-4 have the pre-defined connection set IDs; the others start without an ID.
  // TPDOs start with bit 30 (no RTR); a master may clear it, and a remote frame then asks for
  // the PDO (node/pdo_engine.cpp).
  uint32_t base = (rx ? cob::kRpdo1 : cob::kTpdo1) + 0x100 * n;
  uint32_t no_rtr = rx ? 0 : kCobGenerate;
  uint32_t cob_id = (n < 4 ? base + node_id : kCobInvalid) | no_rtr;

  Object& comm = od.record(
      comm_index,
      hex_index(rx ? "RPDO %u communication parameter" : "TPDO %u communication parameter", n + 1));
  Entry& id = comm.add(1, std::string("COB-ID used by ") + kind, DT::Unsigned32, AC::ReadWrite,
                       encode<uint32_t>(cob_id));
  if (n < 4) id.eds_default = hex_index("$NODEID+0x%X", no_rtr | base);
  Entry& type = comm.add(2, "Transmission type", DT::Unsigned8, AC::ReadWrite, {254});
  if (!rx) {
    comm.add(3, "Inhibit time", DT::Unsigned16, AC::ReadWrite, encode<uint16_t>(0));
  }
  comm.add(5, "Event timer", DT::Unsigned16, AC::ReadWrite, encode<uint16_t>(0));
  // SYNC start value: 0 = not used, 1..240 = SYNC counter value; 241..255 are reserved
  // (CiA 301 7.5.2.37).
  if (!rx) comm.add(6, "SYNC start value", DT::Unsigned8, AC::ReadWrite, {0}).high = Bytes{240};

  auto pdo_valid = [&od, comm_index] { return !(od.get<uint32_t>(comm_index, 1) & kCobInvalid); };
  id.validate = [&od, comm_index](std::span<const uint8_t> d) {
    return check_cob_id(od.get<uint32_t>(comm_index, 1), u32(d), kCobInvalid);
  };
  // Types 0..240 (synchronous), 254/255 (event-driven). 252/253 (sent only when asked by a
  // remote frame) are not supported, and 241..251 are reserved.
  type.validate = [](std::span<const uint8_t> d) {
    return d[0] <= 240 || d[0] >= 254 ? SdoAbort::None : SdoAbort::InvalidValue;
  };
  if (!rx) {
    // Inhibit time and SYNC start value may only change while the PDO does not exist.
    auto only_when_invalid = [pdo_valid](std::span<const uint8_t>) {
      return pdo_valid() ? SdoAbort::InvalidValue : SdoAbort::None;
    };
    comm.entries.at(3).validate = only_when_invalid;
    comm.entries.at(6).validate = only_when_invalid;
  }

  Object& map = od.record(
      map_index, hex_index(rx ? "RPDO %u mapping parameter" : "TPDO %u mapping parameter", n + 1));
  Entry& count = map.entries.at(0);
  count.name = "Number of mapped objects";
  count.access = AC::ReadWrite;
  count.persistent = true;
  count.high = Bytes{static_cast<uint8_t>(kMaxMappedEntries)};
  for (unsigned i = 1; i <= kMaxMappedEntries; ++i) {
    Entry& e = map.add(static_cast<uint8_t>(i), hex_index("Mapped object %u", i), DT::Unsigned32,
                       AC::ReadWrite, encode<uint32_t>(0));
    // CiA 301 7.5.2.36: entries change only while the PDO is invalid and the count is 0.
    e.validate = [&od, map_index, pdo_valid, dir](std::span<const uint8_t> d) {
      if (pdo_valid() || od.get<uint8_t>(map_index, 0) != 0) return SdoAbort::DeviceState;
      uint32_t word = u32(d);
      return word == 0 ? SdoAbort::None : check_mapping_entry(od, word, dir);
    };
  }
  count.validate = [&od, map_index, pdo_valid, dir](std::span<const uint8_t> d) {
    if (pdo_valid()) return SdoAbort::DeviceState;
    std::vector<uint32_t> words;
    for (unsigned i = 1; i <= d[0]; ++i)
      words.push_back(od.get<uint32_t>(map_index, static_cast<uint8_t>(i)));
    return check_mapping(od, words, dir);
  };
}

}  // namespace

bool is_restricted_can_id(uint32_t id) {
  return id == 0x000 || (id >= 0x001 && id <= 0x07F) || (id >= 0x101 && id <= 0x180) ||
         (id >= 0x581 && id <= 0x5FF) || (id >= 0x601 && id <= 0x67F) ||
         (id >= 0x6E0 && id <= 0x6FF) || (id >= 0x701 && id <= 0x77F) ||
         (id >= 0x780 && id <= 0x7FF);
}

void build_communication_objects(Dictionary& od, const DeviceInfo& info, unsigned pdos) {
  add_identity(od, info);
  add_error_history(od);
  add_sync_and_emcy(od, info);
  add_time(od);
  add_heartbeat(od);
  add_nmt_startup(od);
  add_node_guarding(od);
  add_error_behaviour(od);
  add_store_restore(od);
  add_sdo_server_parameters(od, info.node_id);
  for (unsigned n = 0; n < pdos && n < kMaxPdos; ++n) {
    add_pdo(od, PdoDirection::Receive, n, info.node_id);
    add_pdo(od, PdoDirection::Transmit, n, info.node_id);
  }
}

void apply_node_id(Dictionary& od, uint8_t node_id) {
  constexpr std::string_view kPrefix = "$NODEID+";
  for (const auto& [index, unused] : od.objects()) {
    (void)unused;
    for (auto& [sub, e] : od.object(index)->entries) {
      if (!e.eds_default.starts_with(kPrefix) || e.type != DataType::Unsigned32) continue;
      const uint32_t offset =
          static_cast<uint32_t>(std::stoul(e.eds_default.substr(kPrefix.size()), nullptr, 0));
      e.default_value = encode<uint32_t>(offset + node_id);
    }
  }
}

}  // namespace stepnode::od
