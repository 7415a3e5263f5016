// EMCY (CiA 301 7.2.7.3.1) into an EmergencySample with text: the code and error
// register in CiA 301 words, and for a stepnode's axis errors (0xFF01..0xFF08) the
// module's error bits by name. What the node sends (node/profiles/horner/service.cpp,
// on_axis_event):
//   bytes 0-1 code 0xFF00 + axis (1-based), byte 2 error register,
//   manufacturer[0] the error bits that just latched (%I1..%I8),
//   manufacturer[1..2] the whole status word (little-endian), manufacturer[3] the axis.
// The HP 44714A channels (od/hp_objects.hpp) add 0xFF00 + error number (0xFF59..0xFF5E
// for errors 89..94) and interrupts 0xFF43 hard limit, 0xFF44 HALT SGL, 0xFF45 HALT switch.
#pragma once
#include <cstdint>
#include <optional>
#include <string>

#include "bridge/samples.hpp"
#include "od/can_frame.hpp"

namespace stepnode::bridge {

// "emergency stop, motor stalled" for the %I1..%I8 bits (bit 0 = %I1); "" for none.
std::string axis_error_bits_text(uint8_t bits);
// The HP 44714A manual's words for error numbers 89..94; nullptr for others.
const char* hp_error_text(uint8_t number);
// The sample's text. `stepnode`: the sender is a stepnode (its 0xFFxx codes are known).
std::string emcy_text(uint16_t code, uint8_t error_register,
                      const std::array<uint8_t, 5>& manufacturer, bool stepnode);
// nullopt for a frame that is no EMCY (DLC other than 8).
std::optional<EmergencySample> decode_emcy(uint8_t node, const od::CanFrame& frame,
                                           uint64_t can_time_ns, bool stepnode);

}  // namespace stepnode::bridge
