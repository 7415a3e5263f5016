#include "od/sdo_abort.hpp"

namespace stepnode::od {

// Texts as worded in CiA 301 table 22.
std::string_view abort_text(uint32_t code) {
  switch (code) {
    case 0x00000000: return "no abort";
    case 0x05030000: return "Toggle bit not alternated";
    case 0x05040000: return "SDO protocol timed out";
    case 0x05040001: return "Client/server command specifier not valid or unknown";
    case 0x05040002: return "Invalid block size";
    case 0x05040003: return "Invalid sequence number";
    case 0x05040004: return "CRC error";
    case 0x05040005: return "Out of memory";
    case 0x06010000: return "Unsupported access to an object";
    case 0x06010001: return "Attempt to read a write only object";
    case 0x06010002: return "Attempt to write a read only object";
    case 0x06020000: return "Object does not exist in the object dictionary";
    case 0x06040041: return "Object cannot be mapped to the PDO";
    case 0x06040042:
      return "The number and length of the objects to be mapped would exceed PDO length";
    case 0x06040043: return "General parameter incompatibility reason";
    case 0x06040047: return "General internal incompatibility in the device";
    case 0x06060000: return "Access failed due to a hardware error";
    case 0x06070010: return "Data type does not match, length of service parameter does not match";
    case 0x06070012: return "Data type does not match, length of service parameter too high";
    case 0x06070013: return "Data type does not match, length of service parameter too low";
    case 0x06090011: return "Sub-index does not exist";
    case 0x06090030: return "Invalid value for parameter";
    case 0x06090031: return "Value of parameter written too high";
    case 0x06090032: return "Value of parameter written too low";
    case 0x06090036: return "Maximum value is less than minimum value";
    case 0x060A0023: return "Resource not available: SDO connection";
    case 0x08000000: return "General error";
    case 0x08000020: return "Data cannot be transferred or stored to the application";
    case 0x08000021:
      return "Data cannot be transferred or stored to the application because of local control";
    case 0x08000022:
      return "Data cannot be transferred or stored to the application because of the present "
             "device state";
    case 0x08000023:
      return "Object dictionary dynamic generation fails or no object dictionary is present";
    case 0x08000024: return "No data available";
    default: return "unknown abort code";
  }
}

std::string_view abort_text(SdoAbort code) { return abort_text(static_cast<uint32_t>(code)); }

}  // namespace stepnode::od
