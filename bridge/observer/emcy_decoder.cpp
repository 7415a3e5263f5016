#include "bridge/observer/emcy_decoder.hpp"

#include "od/emcy_text.hpp"

namespace stepnode::bridge {
namespace {

// %I1..%I8 (node/motion/axis_registers.hpp status::): bits 5 and 6 are not used by the
// modules and are named by number if they ever appear.
constexpr const char* kErrorBitNames[8] = {
    "emergency stop", "lower limit", "upper limit", "illegal move",
    "motor stalled",  "error bit 6", "error bit 7", "power-up/watchdog",
};

constexpr uint16_t kAxisErrorFirst = 0xFF01;
constexpr uint16_t kAxisErrorLast = 0xFF08;
constexpr uint16_t kHpErrorFirst = 0xFF00 + 89;
constexpr uint16_t kHpErrorLast = 0xFF00 + 94;
constexpr uint16_t kHpInterruptFirst = 0xFF43;
constexpr uint16_t kHpInterruptLast = 0xFF45;
constexpr const char* kHpInterruptNames[] = {"hard limit", "HALT SGL", "HALT switch"};

}  // namespace

std::string axis_error_bits_text(uint8_t bits) {
  std::string out;
  for (unsigned i = 0; i < 8; ++i) {
    if (!(bits & (1u << i))) continue;
    if (!out.empty()) out += ", ";
    out += kErrorBitNames[i];
  }
  return out;
}

const char* hp_error_text(uint8_t number) {
  switch (number) {  // HP 44714A manual, error messages
    case 89: return "accessory busy (a move is in progress)";
    case 90: return "no action defined (TRIG SGL without MOVE or SUSTAIN)";
    case 91: return "must stop to change direction";
    case 92: return "not valid in width mode";
    case 93: return "terminal card test jumper set";
    case 94: return "cannot move while standby on";
    default: return nullptr;
  }
}

std::string emcy_text(uint16_t code, uint8_t error_register,
                      const std::array<uint8_t, 5>& manufacturer, bool stepnode) {
  std::string text;
  if (stepnode && code >= kHpErrorFirst && code <= kHpErrorLast) {
    const auto number = static_cast<uint8_t>(code - 0xFF00);
    text = "HP error " + std::to_string(number) + ": " + hp_error_text(number);
  } else if (stepnode && code >= kHpInterruptFirst && code <= kHpInterruptLast) {
    text = std::string("HP interrupt: ") + kHpInterruptNames[code - kHpInterruptFirst];
  } else if (stepnode && code >= kAxisErrorFirst && code <= kAxisErrorLast) {
    text = "axis " + std::to_string(code - 0xFF00) + " error";
    const std::string latched = axis_error_bits_text(manufacturer[0]);
    if (!latched.empty()) text += ": " + latched;
    // The status word says which errors are latched in all (earlier ones too).
    const uint8_t others = static_cast<uint8_t>(manufacturer[1] & ~manufacturer[0]);
    if (others) text += " (also latched: " + axis_error_bits_text(others) + ")";
  } else {
    text = od::emcy_code_text(code);
  }
  text += "; error register: " + od::error_register_text(error_register);
  return text;
}

std::optional<EmergencySample> decode_emcy(uint8_t node, const od::CanFrame& f,
                                           uint64_t can_time_ns, bool stepnode) {
  if (f.dlc != 8 || f.rtr) return std::nullopt;
  EmergencySample s;
  s.node = node;
  s.code = od::get_u16(f.data.data());
  s.error_register = f.data[2];
  for (size_t i = 0; i < s.manufacturer.size(); ++i) s.manufacturer[i] = f.data[3 + i];
  s.text = emcy_text(s.code, s.error_register, s.manufacturer, stepnode);
  s.can_time_ns = can_time_ns;
  return s;
}

}  // namespace stepnode::bridge
