// Words for EMCY messages (CiA 301 7.2.7.3.1 table 21, error register 7.5.2.2), used by
// stepctl watch and the bridge.
#pragma once
#include <cstdint>
#include <string>

namespace stepnode::od {

// "heartbeat error (communication: monitoring)" for 0x8130; falls back to the class.
std::string emcy_code_text(uint16_t code);
// "generic, communication" for 0x11; "no error" for 0.
std::string error_register_text(uint8_t reg);

}  // namespace stepnode::od
