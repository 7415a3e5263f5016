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
  od::limits<uint8_t>(od.var(kMasterNodeId, "Master node-ID (0 = any monitored node)", DT::Unsigned8,
                             AC::ReadWrite, {0}),
                      0, 127);
}

}  // namespace stepnode::node
