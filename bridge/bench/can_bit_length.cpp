#include "bridge/bench/can_bit_length.hpp"

#include <array>

namespace stepnode::bridge::sim {
namespace {

// Bits after the CRC sequence that are never stuffed: CRC delimiter 1, ACK slot and
// delimiter 2, end of frame 7, intermission 3.
constexpr unsigned kUnstuffedTail = 1 + 2 + 7 + 3;

}  // namespace

uint16_t can_crc15(const uint8_t* bits, unsigned count) {
  uint16_t crc = 0;
  for (unsigned i = 0; i < count; ++i) {
    const bool next = (bits[i] != 0) != ((crc >> 14) & 1);
    crc = static_cast<uint16_t>((crc << 1) & 0x7FFF);
    if (next) crc ^= 0x4599;
  }
  return crc;
}

unsigned can_frame_bits(const od::CanFrame& f) {
  // SOF 1 + ID 11 + RTR 1 + IDE 1 + r0 1 + DLC 4 + data 64 at most + CRC 15.
  std::array<uint8_t, 1 + 11 + 3 + 4 + 64 + 15> bits{};
  unsigned n = 0;
  auto put = [&](uint32_t value, unsigned width) {
    for (unsigned i = width; i-- > 0;) bits[n++] = static_cast<uint8_t>((value >> i) & 1);
  };
  const unsigned dlc = f.dlc > 8 ? 8 : f.dlc;
  put(0, 1);  // SOF, dominant
  put(f.id & 0x7FF, 11);
  put(f.rtr ? 1 : 0, 1);
  put(0, 2);  // IDE and r0, dominant in a base frame
  put(dlc, 4);
  if (!f.rtr)
    for (unsigned i = 0; i < dlc; ++i) put(f.data[i], 8);
  put(can_crc15(bits.data(), n), 15);

  unsigned stuffed = 0, run = 0;
  uint8_t last = 2;  // no bit yet
  for (unsigned i = 0; i < n; ++i) {
    run = bits[i] == last ? run + 1 : 1;
    last = bits[i];
    if (run == 5) {
      ++stuffed;
      last = static_cast<uint8_t>(!last);  // the stuff bit starts the next run
      run = 1;
    }
  }
  return n + stuffed + kUnstuffedTail;
}

}  // namespace stepnode::bridge::sim
