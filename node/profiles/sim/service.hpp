// The simulated machine's objects in the node (node/profiles/sim/objects.*): switches,
// encoder and faults written over SDO change the machine at once (under a moving axis
// too); its mechanical positions and inputs are published back.
#pragma once
#include <cstdint>

#include "node/axis_bank.hpp"
#include "node/profile.hpp"
#include "od/dictionary.hpp"

namespace stepnode::node {

class SimService final : public Profile {
 public:
  SimService(od::Dictionary& dictionary, AxisBank& axes);

  // The machine's settings as stored, before the axes power up.
  void configure(uint64_t now_us) override;
  void publish() override;
  // No timed work of its own: the machine's edges come from the steps (the axes' deadlines)
  // and its objects act when written.
  uint64_t next_advance_us(uint64_t) override { return kNoDeadline; }

 private:
  sim::Machine& machine() { return axes_.machine(); }
  void install_hooks();
  void load_machine(unsigned motor);
  void publish_motor(unsigned motor);

  od::Dictionary& dictionary_;
  AxisBank& axes_;
};

}  // namespace stepnode::node
