// NMT slave state machine (CiA 301 7.3.2): the states, the commands, and which services a
// state allows.
#pragma once
#include <cstdint>
#include <optional>
#include <string_view>

#include "od/can_frame.hpp"

namespace stepnode::node {

// Values are the heartbeat state codes (CiA 301 7.2.8.3.2.1).
enum class NmtState : uint8_t {
  Initialising = 0x00,
  Stopped = 0x04,
  Operational = 0x05,
  PreOperational = 0x7F,
};

enum class NmtCommand : uint8_t {
  Start = 0x01,
  Stop = 0x02,
  EnterPreOperational = 0x80,
  ResetNode = 0x81,
  ResetCommunication = 0x82,
};

std::string_view state_name(NmtState state);
std::string_view command_name(NmtCommand command);

// Decodes an NMT frame (COB-ID 0, DLC 2) addressed to `node_id` or broadcast (0). Frames
// of another length or with an unknown command specifier are ignored, as CiA 301 asks.
std::optional<NmtCommand> decode_nmt(const od::CanFrame& frame, uint8_t node_id);

// Which services run in a state (CiA 301 table 85).
inline bool sdo_allowed(NmtState s) {
  return s == NmtState::PreOperational || s == NmtState::Operational;
}
inline bool pdo_allowed(NmtState s) { return s == NmtState::Operational; }
inline bool emcy_allowed(NmtState s) { return sdo_allowed(s); }
inline bool sync_allowed(NmtState s) { return sdo_allowed(s); }

// The state a command leads to; reset commands lead through Initialising (the node does
// the reset, sends boot-up and enters pre-operational).
NmtState next_state(NmtState current, NmtCommand command);

}  // namespace stepnode::node
