// The device layouts the node targets try, chosen by one input byte: each profile alone,
// the default set, all of them, an SPM30 multiplexed axis, and mixes, with 1..4 axes.
#pragma once
#include <cstdint>

#include "node/device_objects.hpp"

namespace stepnode::fuzz {

inline node::DeviceLayout layout_from(uint8_t selector) {
  node::DeviceLayout l;
  l.axes = 1 + ((selector >> 3) & 3);
  l.horner = l.hp = l.user = l.cia402 = false;
  switch (selector & 7) {
    case 0: l.horner = true; break;                             // Horner registers only
    case 1: l.hp = true; break;                                 // HP 44714A channels only
    case 2: l.cia402 = true; break;                             // a CiA 402 drive only
    case 3: l.horner = l.hp = l.user = true; break;             // the default device
    case 4: l.horner = l.hp = l.user = l.cia402 = true; break;  // every profile
    case 5:
      l.horner = l.hp = l.user = l.spm30_multiplexed = true;  // SPM30: 1 axis, 3 motors
      l.axes = 1;
      break;
    case 6: l.hp = l.cia402 = true; break;  // two front ends per axis
    default: l.user = true; break;          // the simulator and user objects
  }
  return l;
}

}  // namespace stepnode::fuzz
