#include "node/error_behaviour.hpp"

#include "od/communication_objects.hpp"

namespace stepnode::node {

std::optional<NmtState> state_after_communication_error(uint8_t behaviour, NmtState current) {
  if (current == NmtState::Initialising) return std::nullopt;
  switch (behaviour) {
    case od::kErrorBehaviourPreOperational:
      if (current == NmtState::Operational) return NmtState::PreOperational;
      return std::nullopt;
    case od::kErrorBehaviourStopped:
      if (current != NmtState::Stopped) return NmtState::Stopped;
      return std::nullopt;
    default:  // 1, and the values the dictionary refuses: no change
      return std::nullopt;
  }
}

}  // namespace stepnode::node
