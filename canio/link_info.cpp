#include "canio/link_info.hpp"

#include <linux/can/netlink.h>
#include <linux/if_link.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <net/if.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cstring>

namespace stepnode::canio {
namespace {

// The attributes nested in `rta` (a nested attribute's payload is an attribute list).
template <class F>
void for_each_attribute(const rtattr* rta, int len, F f) {
  for (; RTA_OK(rta, len); rta = RTA_NEXT(rta, len)) f(rta);
}

// IFLA_INFO_DATA of a CAN link: the bit timing, whose first field is the bit rate.
void read_can_data(const rtattr* data, LinkInfo& out) {
  for_each_attribute(
      static_cast<const rtattr*>(RTA_DATA(data)), static_cast<int>(RTA_PAYLOAD(data)),
      [&](const rtattr* d) {
        if (d->rta_type != IFLA_CAN_BITTIMING || RTA_PAYLOAD(d) < sizeof(can_bittiming)) return;
        can_bittiming bt{};
        std::memcpy(&bt, RTA_DATA(d), sizeof bt);
        if (bt.bitrate) out.bit_rate = bt.bitrate;
      });
}

void read_link_info(const rtattr* linkinfo, LinkInfo& out) {
  for_each_attribute(static_cast<const rtattr*>(RTA_DATA(linkinfo)),
                     static_cast<int>(RTA_PAYLOAD(linkinfo)), [&](const rtattr* a) {
                       const auto* text = static_cast<const char*>(RTA_DATA(a));
                       if (a->rta_type == IFLA_INFO_KIND)
                         out.kind.assign(text, strnlen(text, RTA_PAYLOAD(a)));
                       if (a->rta_type == IFLA_INFO_DATA) read_can_data(a, out);
                     });
}

}  // namespace

std::optional<LinkInfo> link_info(const std::string& iface) {
  const unsigned index = if_nametoindex(iface.c_str());
  if (index == 0) return std::nullopt;
  const int fd = ::socket(AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC, NETLINK_ROUTE);
  if (fd < 0) return std::nullopt;
  struct {
    nlmsghdr header;
    ifinfomsg info;
  } request{};
  request.header.nlmsg_len = NLMSG_LENGTH(sizeof(ifinfomsg));
  request.header.nlmsg_type = RTM_GETLINK;
  request.header.nlmsg_flags = NLM_F_REQUEST;
  request.info.ifi_family = AF_UNSPEC;
  request.info.ifi_index = static_cast<int>(index);
  std::array<char, 16384> buffer{};
  ssize_t n = -1;
  if (::send(fd, &request, request.header.nlmsg_len, 0) >= 0)
    n = ::recv(fd, buffer.data(), buffer.size(), 0);
  ::close(fd);
  if (n <= 0) return std::nullopt;
  LinkInfo out;
  auto len = static_cast<unsigned>(n);
  for (auto* h = reinterpret_cast<nlmsghdr*>(buffer.data()); NLMSG_OK(h, len);
       h = NLMSG_NEXT(h, len)) {
    if (h->nlmsg_type != RTM_NEWLINK) continue;
    auto* info = static_cast<ifinfomsg*>(NLMSG_DATA(h));
    for_each_attribute(IFLA_RTA(info), static_cast<int>(IFLA_PAYLOAD(h)), [&](const rtattr* a) {
      if (a->rta_type == IFLA_LINKINFO) read_link_info(a, out);
    });
    return out;
  }
  return std::nullopt;
}

}  // namespace stepnode::canio
