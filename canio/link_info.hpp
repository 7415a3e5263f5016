// What the kernel says about a network interface's CAN link (rtnetlink RTM_GETLINK): its
// kind ("can" for a controller, "vcan" for a virtual one) and, for a controller, the bit
// rate it is set to. Read only: setting a bit rate is root's, with `ip link`.
#pragma once
#include <cstdint>
#include <optional>
#include <string>

namespace stepnode::canio {

struct LinkInfo {
  std::string kind;                  // IFLA_INFO_KIND; empty when the kernel gave none
  std::optional<uint32_t> bit_rate;  // bit/s (IFLA_CAN_BITTIMING), for a CAN controller
};

// Nullopt when the interface does not exist or netlink could not be asked.
std::optional<LinkInfo> link_info(const std::string& iface);

}  // namespace stepnode::canio
