#include "canio/link_config.hpp"

#include "canio/link_info.hpp"

#include <linux/can/netlink.h>
#include <linux/if_link.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <net/if.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstddef>
#include <cstring>

namespace stepnode::canio {
namespace {

// A netlink message built attribute by attribute; every length is aligned as the kernel
// reads it (NLMSG_ALIGN, RTA_ALIGN).
class Message {
 public:
  Message(uint16_t type, uint32_t sequence, const ifinfomsg& info) {
    nlmsghdr h{};
    h.nlmsg_type = type;
    h.nlmsg_flags = NLM_F_REQUEST | NLM_F_ACK;
    h.nlmsg_seq = sequence;
    append(&h, sizeof h);
    append(&info, sizeof info);
  }
  // Opens an attribute; close() sets its length once what it holds is appended.
  size_t open(uint16_t type) {
    const size_t at = bytes_.size();
    rtattr a{};
    a.rta_type = type;
    append(&a, sizeof a);
    return at;
  }
  void close(size_t at) {
    const auto len = static_cast<unsigned short>(bytes_.size() - at);
    std::memcpy(bytes_.data() + at + offsetof(rtattr, rta_len), &len, sizeof len);
    pad();
  }
  void attribute(uint16_t type, const void* data, size_t size) {
    const size_t at = open(type);
    append(data, size);
    close(at);
  }
  std::vector<uint8_t> finish() {
    const auto len = static_cast<uint32_t>(bytes_.size());
    std::memcpy(bytes_.data() + offsetof(nlmsghdr, nlmsg_len), &len, sizeof len);
    return std::move(bytes_);
  }

 private:
  void append(const void* data, size_t size) {
    const auto* p = static_cast<const uint8_t*>(data);
    bytes_.insert(bytes_.end(), p, p + size);
  }
  void pad() { bytes_.resize(RTA_ALIGN(bytes_.size()), 0); }
  std::vector<uint8_t> bytes_;
};

ifinfomsg link(int ifindex) {
  ifinfomsg info{};
  info.ifi_family = AF_UNSPEC;
  info.ifi_index = ifindex;
  return info;
}

// Sends one request and reads its acknowledgement: 0, or the kernel's errno.
int request(int fd, const std::vector<uint8_t>& message) {
  if (::send(fd, message.data(), message.size(), 0) < 0) return errno;
  std::array<char, 4096> buffer{};
  const ssize_t n = ::recv(fd, buffer.data(), buffer.size(), 0);
  if (n < 0) return errno;
  auto len = static_cast<unsigned>(n);
  for (auto* h = reinterpret_cast<nlmsghdr*>(buffer.data()); NLMSG_OK(h, len);
       h = NLMSG_NEXT(h, len))
    if (h->nlmsg_type == NLMSG_ERROR) return -static_cast<const nlmsgerr*>(NLMSG_DATA(h))->error;
  return EPROTO;  // no acknowledgement
}

std::string failure(const std::string& iface, const std::string& step, int error) {
  std::string why = std::strerror(error);
  if (error == EPERM) why += " (needs CAP_NET_ADMIN)";
  return iface + ": " + step + ": " + why;
}

}  // namespace

std::vector<uint8_t> link_up_request(int ifindex, bool up, uint32_t sequence) {
  ifinfomsg info = link(ifindex);
  info.ifi_flags = up ? IFF_UP : 0;
  info.ifi_change = IFF_UP;  // only this flag changes
  return Message(RTM_NEWLINK, sequence, info).finish();
}

std::vector<uint8_t> bit_rate_request(int ifindex, uint32_t bit_rate, uint32_t sequence) {
  Message m(RTM_NEWLINK, sequence, link(ifindex));
  const size_t linkinfo = m.open(IFLA_LINKINFO);
  const char kind[] = "can";  // with its terminating zero, as the kernel compares it
  m.attribute(IFLA_INFO_KIND, kind, sizeof kind);
  const size_t data = m.open(IFLA_INFO_DATA);
  can_bittiming timing{};
  timing.bitrate = bit_rate;  // the rest 0: the kernel calculates them
  m.attribute(IFLA_CAN_BITTIMING, &timing, sizeof timing);
  m.close(data);
  m.close(linkinfo);
  return m.finish();
}

std::string set_can_bit_rate(const std::string& iface, uint32_t bit_rate) {
  const auto index = static_cast<int>(if_nametoindex(iface.c_str()));
  if (index == 0) return failure(iface, "no such interface", errno);
  // Only a controller has a bit rate; anything else is left running (a link taken down
  // would fail every socket on it, for a request the kernel then refuses).
  const auto link = link_info(iface);
  if (link && link->kind != "can")
    return iface + ": not a CAN controller (link kind \"" + link->kind + "\"): it has no bit rate";
  const int fd = ::socket(AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC, NETLINK_ROUTE);
  if (fd < 0) return failure(iface, "netlink socket", errno);
  std::string result;
  if (int e = request(fd, link_up_request(index, false, 1)))
    result = failure(iface, "link down", e);
  else if (int e2 = request(fd, bit_rate_request(index, bit_rate, 2)))
    result = failure(iface, "bit rate " + std::to_string(bit_rate) + " bit/s", e2);
  // Up again whatever happened: the node was running on it.
  if (int e = request(fd, link_up_request(index, true, 3)); e && result.empty())
    result = failure(iface, "link up", e);
  ::close(fd);
  return result;
}

}  // namespace stepnode::canio
