#include "od/crc16.hpp"

#include <array>

namespace stepnode::od {
namespace {

// Byte-at-a-time table for the MSB-first polynomial 0x1021 (CiA 301 7.2.4.3.16).
constexpr std::array<uint16_t, 256> make_table() {
  std::array<uint16_t, 256> table{};
  for (unsigned i = 0; i < 256; ++i) {
    uint16_t crc = static_cast<uint16_t>(i << 8);
    for (int bit = 0; bit < 8; ++bit)
      crc = static_cast<uint16_t>((crc & 0x8000) ? (crc << 1) ^ 0x1021 : crc << 1);
    table[i] = crc;
  }
  return table;
}

constexpr std::array<uint16_t, 256> kTable = make_table();

}  // namespace

uint16_t crc16_ccitt(std::span<const uint8_t> data, uint16_t crc) {
  for (uint8_t b : data)
    crc = static_cast<uint16_t>((crc << 8) ^ kTable[static_cast<uint8_t>((crc >> 8) ^ b)]);
  return crc;
}

}  // namespace stepnode::od
