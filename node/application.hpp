// What the CiA 301 services drive: the device's profiles behind the dictionary. The
// CanopenNode calls its one Application at these points; the device assembly
// (node/device.*) is the application of the real node, and tests give their own.
#pragma once
#include <cstdint>
#include <vector>

#include "node/deadline.hpp"
#include "node/nmt.hpp"
#include "node/receive_filters.hpp"

namespace stepnode::node {

// The communication errors of CiA 301's error class "communication error" (0x1029 sub 1).
// LifeGuardingLost: no node guarding request within the node life time (0x100C x 0x100D).
enum class CommunicationError { HeartbeatLost, BusOff, LifeGuardingLost };

class Application {
 public:
  virtual ~Application() = default;
  // Brings the application up to `now_us`; called before every frame and tick, so a
  // command in a frame acts on an application that is current to the microsecond.
  virtual void advance(uint64_t /*now_us*/) {}
  // When the application next needs an advance (absolute us, node/deadline.hpp): the
  // earliest of its axes and profiles. The default is the conservative poll, so an
  // application that does not say is advanced every poll period as before issue 13.
  virtual uint64_t next_advance_us(uint64_t now_us) { return poll_deadline(now_us); }
  // Power-up and NMT reset node, after the stored parameters were loaded.
  virtual void reset_application(uint64_t /*now_us*/) {}
  // Every SYNC received (or produced here), after the synchronous PDOs.
  virtual void sync(uint64_t /*now_us*/) {}
  // A new NMT state; Initialising only when a running device lost its node-ID over LSS.
  virtual void state_changed(NmtState /*state*/, uint64_t /*now_us*/) {}
  // A communication error, before 0x1029's change of NMT state. `node`: the monitored node
  // whose heartbeat was lost (0 for a bus-off and for life guarding: the guarding master).
  virtual void communication_error(CommunicationError /*error*/, uint8_t /*node*/,
                                   uint64_t /*now_us*/) {}
  // The heartbeat of monitored node `node` is back (or it is no longer watched).
  virtual void heartbeat_recovered(uint8_t /*node*/, uint64_t /*now_us*/) {}
  // The guarding master's requests are back after a life guarding event.
  virtual void life_guarding_recovered(uint64_t /*now_us*/) {}
  // The CAN-IDs the node serves changed (a COB-ID written, a new node-ID, a restore): the
  // socket's kernel filters should become `filters` (node/receive_filters.hpp). Called
  // before the node sends its next frame, so a master that waits for the SDO answer that
  // made an RPDO valid finds the filter open when it sends the RPDO.
  virtual void receive_filters_changed(const std::vector<ReceiveFilter>& /*filters*/) {}
};

}  // namespace stepnode::node
