// CRC used by SDO block transfer (CiA 301 7.2.4.3.16): CRC-16/XMODEM, polynomial
// x^16 + x^12 + x^5 + 1 (0x1021), initial value 0, no reflection.
#pragma once
#include <cstdint>
#include <span>

namespace stepnode::od {

uint16_t crc16_ccitt(std::span<const uint8_t> data, uint16_t crc = 0);

}  // namespace stepnode::od
