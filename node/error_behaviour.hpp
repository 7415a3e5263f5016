// CiA 301 7.5.2.32 error behaviour (object 0x1029): the NMT state a communication error
// leads to, from sub 1's value and the present state.
#pragma once
#include <cstdint>
#include <optional>

#include "node/nmt.hpp"

namespace stepnode::node {

// The state to enter, or nothing when the state stays: 0 pre-operational (only from
// operational), 1 no change, 2 stopped (from any state after initialisation).
std::optional<NmtState> state_after_communication_error(uint8_t behaviour, NmtState current);

}  // namespace stepnode::node
