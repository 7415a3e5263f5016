// An application that records what the CiA 301 slave told it, for the tests of the slave's
// own rules: it takes the device's place behind the CanopenNode (set_application), so the
// axes play no part.
#pragma once
#include <cstdint>
#include <vector>

#include "node/application.hpp"

namespace stepnode::node::test {

struct RecordingApplication : Application {
  void reset_application(uint64_t) override { ++resets; }
  void state_changed(NmtState state, uint64_t) override { states.push_back(state); }
  void communication_error(CommunicationError error, uint8_t node, uint64_t) override {
    if (error == CommunicationError::HeartbeatLost) lost.push_back(node);
    else if (error == CommunicationError::LifeGuardingLost) ++guarding_lost;
    else ++bus_offs;
  }
  void life_guarding_recovered(uint64_t) override { ++guarding_recovered; }
  int guarding_lost = 0;
  int guarding_recovered = 0;
  int resets = 0;
  int bus_offs = 0;
  std::vector<NmtState> states;
  std::vector<uint8_t> lost;  // the nodes whose heartbeat was lost, in order
};

}  // namespace stepnode::node::test
