#include "node/diagnostic_objects.hpp"

namespace stepnode::node {

void add_diagnostic_objects(od::Dictionary& od) {
  using DT = od::DataType;
  using AC = od::Access;
  // How many received frames the CAN socket's queue dropped since the last reset node (the
  // kernel's SO_RXQ_OVFL count); each increase also goes out as EMCY 0x8110.
  od.var(kReceiveOverruns, "CAN frames dropped at the socket", DT::Unsigned32, AC::ReadOnly,
         od::encode<uint32_t>(0), true);
  // Whose heartbeat loss is the master's: 0 any node in 0x1016, 1..127 only that node.
  // A lost master ramps every moving axis down and latches %I8; another node's loss is
  // an EMCY 0x8130 only.
  od::limits<uint8_t>(od.var(kMasterNodeId, "Master node-ID (0 = any monitored node)",
                             DT::Unsigned8, AC::ReadWrite, {0}),
                      0, 127);

  // The network time (TIME, 0x1012): read-only and computed when read, so never stored.
  od::Object& time = od.record(kNetworkTime, "Network time");
  time.add(1, "Network time: ms after midnight", DT::Unsigned32, AC::ReadOnly,
           od::encode<uint32_t>(0));
  time.add(2, "Network time: days since 1984-01-01", DT::Unsigned16, AC::ReadOnly,
           od::encode<uint16_t>(0));
  time.add(3, "Network time: ms since 1970-01-01 UTC", DT::Unsigned64, AC::ReadOnly,
           od::encode<uint64_t>(0));
  time.add(4, "Network time source (0 none, 1 TIME consumed, 2 produced)", DT::Unsigned8,
           AC::ReadOnly, {0});
  time.add(kTimeProducerPeriodSub, "TIME producer period (ms)", DT::Unsigned16, AC::ReadWrite,
           od::encode<uint16_t>(1000));
}

}  // namespace stepnode::node
