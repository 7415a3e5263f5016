// The length on the wire of a classic CAN data or remote frame with an 11-bit identifier
// (ISO 11898-1), so a simulated bus spends the time a real one would: SOF, identifier,
// RTR, IDE, r0, DLC, data, CRC-15 (computed, polynomial 0x4599), then CRC delimiter, ACK
// slot and delimiter, EOF (7) and intermission (3). Stuff bits are counted exactly: after
// five equal bits from SOF to the end of the CRC a complementary bit is inserted, and it
// counts as the first of the next run.
#pragma once
#include <cstdint>

#include "od/can_frame.hpp"

namespace stepnode::bridge::sim {

// Bits from SOF to the end of the intermission, stuff bits included.
unsigned can_frame_bits(const od::CanFrame& frame);

// The CRC-15 of ISO 11898-1 over the first `count` bits of `bits` (one bit per entry).
uint16_t can_crc15(const uint8_t* bits, unsigned count);

}  // namespace stepnode::bridge::sim
