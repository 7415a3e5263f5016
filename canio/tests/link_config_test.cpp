// The rtnetlink requests that set a CAN controller's bit rate, byte for byte as the kernel's
// uapi lays them out (netlink(7), rtnetlink(7), linux/can/netlink.h), written here from
// those layouts: nlmsghdr {u32 len, u16 type, u16 flags, u32 seq, u32 pid}, ifinfomsg {u8
// family, u8 pad, u16 type, i32 index, u32 flags, u32 change}, rtattr {u16 len, u16 type}
// padded to 4 bytes; RTM_NEWLINK = 16, NLM_F_REQUEST | NLM_F_ACK = 0x5, IFF_UP = 1,
// IFLA_LINKINFO = 18, IFLA_INFO_KIND = 1, IFLA_INFO_DATA = 2, IFLA_CAN_BITTIMING = 1 (a
// struct of eight u32: bitrate first).
#include "canio/link_config.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace stepnode::canio {
namespace {

void put16(std::vector<uint8_t>& v, uint16_t x) {
  v.push_back(static_cast<uint8_t>(x));
  v.push_back(static_cast<uint8_t>(x >> 8));
}
void put32(std::vector<uint8_t>& v, uint32_t x) {
  put16(v, static_cast<uint16_t>(x));
  put16(v, static_cast<uint16_t>(x >> 16));
}
std::vector<uint8_t> header(uint32_t len, uint32_t seq, int index, uint32_t flags,
                            uint32_t change) {
  std::vector<uint8_t> v;
  put32(v, len);
  put16(v, 16);   // RTM_NEWLINK
  put16(v, 0x5);  // NLM_F_REQUEST | NLM_F_ACK
  put32(v, seq);
  put32(v, 0);     // pid: the kernel
  v.push_back(0);  // AF_UNSPEC
  v.push_back(0);
  put16(v, 0);  // device type: unchanged
  put32(v, static_cast<uint32_t>(index));
  put32(v, flags);
  put32(v, change);
  return v;
}

TEST(LinkConfig, LinkDownAndUpChangeOnlyTheUpFlag) {
  EXPECT_EQ(link_up_request(7, false, 1), header(32, 1, 7, 0, 1));
  EXPECT_EQ(link_up_request(7, true, 3), header(32, 3, 7, 1, 1));
}

TEST(LinkConfig, TheBitRateIsACanLinksBitTimingWithOnlyTheRateGiven) {
  std::vector<uint8_t> want = header(84, 2, 3, 0, 0);
  put16(want, 52);  // IFLA_LINKINFO: 4 + 8 + 40
  put16(want, 18);
  put16(want, 8);  // IFLA_INFO_KIND "can\0"
  put16(want, 1);
  for (uint8_t c : {'c', 'a', 'n', '\0'}) want.push_back(c);
  put16(want, 40);  // IFLA_INFO_DATA: 4 + 36
  put16(want, 2);
  put16(want, 36);  // IFLA_CAN_BITTIMING: 4 + 32
  put16(want, 1);
  put32(want, 250'000);                        // bitrate
  for (int i = 0; i < 7; ++i) put32(want, 0);  // sample point, tq, segments, sjw, brp: the kernel's
  EXPECT_EQ(bit_rate_request(3, 250'000, 2), want);
}

TEST(LinkConfig, AnInterfaceThatDoesNotExistIsOneLineNamingIt) {
  const std::string e = set_can_bit_rate("stepnode-none0", 500'000);
  EXPECT_NE(e.find("stepnode-none0"), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
}

}  // namespace
}  // namespace stepnode::canio
