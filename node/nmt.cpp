#include "node/nmt.hpp"

namespace stepnode::node {

std::string_view state_name(NmtState state) {
  switch (state) {
    case NmtState::Initialising: return "initialising";
    case NmtState::Stopped: return "stopped";
    case NmtState::Operational: return "operational";
    case NmtState::PreOperational: return "pre-operational";
  }
  return "unknown";
}

std::string_view command_name(NmtCommand command) {
  switch (command) {
    case NmtCommand::Start: return "start";
    case NmtCommand::Stop: return "stop";
    case NmtCommand::EnterPreOperational: return "enter pre-operational";
    case NmtCommand::ResetNode: return "reset node";
    case NmtCommand::ResetCommunication: return "reset communication";
  }
  return "unknown";
}

std::optional<NmtCommand> decode_nmt(const od::CanFrame& frame, uint8_t node_id) {
  if (frame.id != od::cob::kNmt || frame.rtr || frame.dlc != 2) return std::nullopt;
  if (frame.data[1] != 0 && frame.data[1] != node_id) return std::nullopt;
  switch (frame.data[0]) {
    case 0x01: return NmtCommand::Start;
    case 0x02: return NmtCommand::Stop;
    case 0x80: return NmtCommand::EnterPreOperational;
    case 0x81: return NmtCommand::ResetNode;
    case 0x82: return NmtCommand::ResetCommunication;
    default: return std::nullopt;
  }
}

NmtState next_state(NmtState current, NmtCommand command) {
  switch (command) {
    case NmtCommand::Start: return NmtState::Operational;
    case NmtCommand::Stop: return NmtState::Stopped;
    case NmtCommand::EnterPreOperational: return NmtState::PreOperational;
    case NmtCommand::ResetNode:
    case NmtCommand::ResetCommunication: return NmtState::Initialising;
  }
  return current;
}

}  // namespace stepnode::node
