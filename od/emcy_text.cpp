#include "od/emcy_text.hpp"

namespace stepnode::od {
namespace {

const char* specific(uint16_t code) {
  switch (code) {
    case 0x0000: return "error reset or no error";
    case 0x1000: return "generic error";
    case 0x6100: return "internal software error";
    case 0x8100: return "communication error";
    case 0x8110: return "CAN overrun (objects lost)";
    case 0x8120: return "CAN in error passive mode";
    case 0x8130: return "life guard or heartbeat error";
    case 0x8140: return "recovered from bus off";
    case 0x8150: return "CAN-ID collision";
    case 0x8200: return "protocol error";
    case 0x8210: return "PDO not processed due to length error";
    case 0x8220: return "PDO length exceeded";
    case 0x8230: return "DAM MPDO not processed, destination object not available";
    case 0x8240: return "unexpected SYNC data length";
    case 0x8250: return "RPDO timeout";
    case 0x9000: return "external error";
    case 0xF000: return "additional functions";
    case 0xFF00: return "device specific";
    default: return nullptr;
  }
}

const char* error_class(uint16_t code) {
  switch (code >> 12) {
    case 0x0: return "error reset";
    case 0x1: return "generic error";
    case 0x2: return "current";
    case 0x3: return "voltage";
    case 0x4: return "temperature";
    case 0x5: return "device hardware";
    case 0x6: return "device software";
    case 0x7: return "additional modules";
    case 0x8: return "monitoring";
    case 0x9: return "external error";
    case 0xF: return (code >> 8) == 0xFF ? "device specific" : "additional functions";
    default: return "reserved";
  }
}

}  // namespace

std::string emcy_code_text(uint16_t code) {
  if (const char* s = specific(code)) return s;
  return std::string(error_class(code)) + " error";
}

std::string error_register_text(uint8_t reg) {
  if (reg == 0) return "no error";
  static const char* bits[8] = {"generic",       "current",        "voltage",  "temperature",
                                "communication", "device profile", "reserved", "manufacturer"};
  std::string out;
  for (int i = 0; i < 8; ++i) {
    if (!(reg & (1 << i))) continue;
    if (!out.empty()) out += ", ";
    out += bits[i];
  }
  return out;
}

}  // namespace stepnode::od
