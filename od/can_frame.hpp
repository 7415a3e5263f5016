// A classic CAN frame as the pure protocol layers see it (no socket types here).
#pragma once
#include <array>
#include <cstdint>
#include <initializer_list>
#include <span>

namespace stepnode::od {

struct CanFrame {
  uint32_t id = 0;  // 11-bit identifier (CANopen uses base frames only)
  uint8_t dlc = 0;
  std::array<uint8_t, 8> data{};
  bool rtr = false;

  CanFrame() = default;
  CanFrame(uint32_t cob_id, std::initializer_list<uint8_t> bytes) : id(cob_id) {
    for (uint8_t b : bytes) data[dlc++] = b;
  }
  CanFrame(uint32_t cob_id, std::span<const uint8_t> bytes) : id(cob_id) {
    for (uint8_t b : bytes) {
      if (dlc == 8) break;
      data[dlc++] = b;
    }
  }
  std::span<const uint8_t> payload() const { return {data.data(), dlc}; }
  bool operator==(const CanFrame&) const = default;
};

// Pre-defined connection set function codes (CiA 301 7.3.3).
namespace cob {
constexpr uint32_t kNmt = 0x000;
constexpr uint32_t kSync = 0x080;
constexpr uint32_t kEmcyBase = 0x080;
constexpr uint32_t kTimeStamp = 0x100;
constexpr uint32_t kTpdo1 = 0x180;
constexpr uint32_t kRpdo1 = 0x200;
constexpr uint32_t kTpdo2 = 0x280;
constexpr uint32_t kRpdo2 = 0x300;
constexpr uint32_t kTpdo3 = 0x380;
constexpr uint32_t kRpdo3 = 0x400;
constexpr uint32_t kTpdo4 = 0x480;
constexpr uint32_t kRpdo4 = 0x500;
constexpr uint32_t kSdoTx = 0x580;  // server -> client
constexpr uint32_t kSdoRx = 0x600;  // client -> server
constexpr uint32_t kHeartbeat = 0x700;
}  // namespace cob

// Little-endian helpers used by every codec.
inline uint16_t get_u16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
inline uint32_t get_u32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
         (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}
inline void put_u16(uint8_t* p, uint16_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}
inline void put_u32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}

}  // namespace stepnode::od
