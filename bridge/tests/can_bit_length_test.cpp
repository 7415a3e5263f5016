// The simulated bus's frame lengths, from ISO 11898-1's frame layout worked by hand.
#include <gtest/gtest.h>

#include <array>

#include "bridge/bench/can_bit_length.hpp"

namespace stepnode::bridge::sim {
namespace {

TEST(CanBitLength, AllDominantFrameStuffsEveryFifthBit) {
  // ID 0, no data: SOF, 11 ID bits, RTR, IDE, r0 and 4 DLC bits are 19 zeros, and the
  // CRC of all zeros is zero: 34 dominant bits in a row. A stuff bit after each 5 (the
  // recessive stuff bit starts a new run): 6 stuff bits. Then 13 fixed bits.
  EXPECT_EQ(can_crc15(std::array<uint8_t, 19>{}.data(), 19), 0);
  EXPECT_EQ(can_frame_bits(od::CanFrame(0x000, {})), 34u + 6u + 13u);
}

TEST(CanBitLength, StaysWithinTheUnstuffedAndWorstCaseLengths) {
  // 47 + 8n bits unstuffed; at most one stuff bit per 4 bits after the first 5 of the
  // 34 + 8n stuffed bits: (34 + 8n - 1) / 4.
  for (uint8_t n = 0; n <= 8; ++n) {
    for (uint32_t id : {0x000u, 0x080u, 0x185u, 0x5FFu, 0x605u, 0x7FFu}) {
      for (uint8_t fill : {0x00, 0x55, 0xAA, 0xFF, 0x0F}) {
        od::CanFrame f;
        f.id = id;
        f.dlc = n;
        f.data.fill(fill);
        const unsigned bits = can_frame_bits(f);
        EXPECT_GE(bits, 47u + 8u * n);
        EXPECT_LE(bits, 47u + 8u * n + (34u + 8u * n - 1u) / 4u);
      }
    }
  }
}

TEST(CanBitLength, TheCrcIsTheRemainderOfThePolynomialDivision) {
  // A message followed by its CRC-15 divides by x^15 + x^14 + x^10 + x^8 + x^7 + x^4 +
  // x^3 + 1 (0xC599 with the top bit) without remainder; one flipped bit breaks that.
  std::array<uint8_t, 40> bits{};
  for (unsigned i = 0; i < 25; ++i) bits[i] = static_cast<uint8_t>((0x1A2B3C5u >> i) & 1);
  const uint16_t crc = can_crc15(bits.data(), 25);
  for (unsigned i = 0; i < 15; ++i) bits[25 + i] = static_cast<uint8_t>((crc >> (14 - i)) & 1);
  EXPECT_EQ(can_crc15(bits.data(), 40), 0);
  bits[7] ^= 1;
  EXPECT_NE(can_crc15(bits.data(), 40), 0);
}

}  // namespace
}  // namespace stepnode::bridge::sim
