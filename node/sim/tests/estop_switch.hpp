// The e-stop switch of a test fixture: one input wired to every simulated motor of the
// axis under test (the motors' input ports report it), so `estop = true;` presses it.
#pragma once
#include <vector>

#include "node/sim/machine.hpp"

namespace stepnode::sim {

struct EStopSwitch {
  std::vector<AxisMachine*> wired;
  bool pressed = false;

  EStopSwitch& operator=(bool on) {
    pressed = on;
    for (AxisMachine* m : wired) m->set_emergency_stop(on);
    return *this;
  }
  void wire(std::vector<AxisMachine*> motors) {
    wired = std::move(motors);
    for (AxisMachine* m : wired) m->set_emergency_stop(pressed);
  }
};

}  // namespace stepnode::sim
