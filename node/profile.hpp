// One profile of the device: the service behind one folder of node/profiles (its objects'
// reactions, what it publishes, its EMCY codes, its stored settings and its per-tick
// work). The device assembly (node/device.*) owns the profiles it was configured with and
// calls them in this order; adding a profile is a new folder and one line there.
#pragma once
#include <cstdint>

#include "node/deadline.hpp"

namespace stepnode::node {

class Profile {
 public:
  virtual ~Profile() = default;
  // Power-up and NMT reset node, with the stored values loaded. configure() gives the axes
  // and the back end their settings before the axes power up; power_up() comes after.
  virtual void configure(uint64_t /*now_us*/) {}
  virtual void power_up(uint64_t /*now_us*/) {}
  // The axes were advanced to `now_us`: the profile's own timed work.
  virtual void advance(uint64_t /*now_us*/) {}
  // When the profile's own timed work next needs an advance (absolute us), besides the
  // axes' steps, which the AxisBank reports. Conservative by default: a profile that does
  // not say is advanced every poll period (node/deadline.hpp), as before issue 13.
  virtual uint64_t next_advance_us(uint64_t now_us) { return poll_deadline(now_us); }
  // Its readings into the dictionary (the TPDOs carry them).
  virtual void publish() {}
  // A SYNC (TRIG SYS), received at `frame_us` <= now_us (its arrival on the bus).
  virtual void sync(uint64_t /*now_us*/, uint64_t /*frame_us*/) {}
  // The master was lost (heartbeat, bus-off, NMT Stopped): the profile's own reaction
  // (CiA 402: 6007h), after the register front ends' ramp-down.
  virtual void master_lost(uint64_t /*now_us*/) {}
  // The master's heartbeat is back.
  virtual void master_back(uint64_t /*now_us*/) {}
};

}  // namespace stepnode::node
