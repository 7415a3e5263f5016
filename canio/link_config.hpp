// Setting a CAN controller's bit rate (rtnetlink RTM_NEWLINK), as `ip link set IFACE down;
// ip link set IFACE type can bitrate N; ip link set IFACE up` does: the kernel refuses a
// new bit timing on a running controller, so the link goes down first and up after. The
// kernel computes the bit timing (sample point, segments) from the bit rate alone.
// Needs CAP_NET_ADMIN. A link of another kind (vcan has no bit rate) is refused before it
// is touched.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace stepnode::canio {

// Empty on success, else one line: what failed and the kernel's reason.
std::string set_can_bit_rate(const std::string& iface, uint32_t bit_rate);

// The requests set_can_bit_rate sends (each asks for an acknowledgement), for tests.
std::vector<uint8_t> link_up_request(int ifindex, bool up, uint32_t sequence);
std::vector<uint8_t> bit_rate_request(int ifindex, uint32_t bit_rate, uint32_t sequence);

}  // namespace stepnode::canio
