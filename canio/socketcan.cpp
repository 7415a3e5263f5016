#include "canio/socketcan.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <net/if_arp.h>
#include <spdlog/spdlog.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>
#include <stdexcept>

namespace stepnode::canio {
namespace {

[[noreturn]] void fail(const std::string& iface, const std::string& what) {
  throw std::runtime_error(iface + ": " + what + ": " + std::strerror(errno));
}

}  // namespace

SocketCan::SocketCan(const std::string& iface, bool receive_own) : iface_(iface) {
  if (iface.empty() || iface.size() >= IFNAMSIZ)
    throw InterfaceError("interface name '" + iface + "' is empty or too long");
  fd_ = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd_ < 0) fail(iface, "cannot open a CAN socket (is SocketCAN in this kernel?)");
  unsigned index = ::if_nametoindex(iface.c_str());
  if (index == 0) {
    // ENODEV: the name is wrong (bad input). Anything else (no descriptor left for the
    // lookup's own socket) is a runtime failure.
    int saved = errno;
    ::close(fd_);
    if (saved != ENODEV) {
      errno = saved;
      fail(iface, "if_nametoindex");
    }
    throw InterfaceError(iface + ": no such CAN interface");
  }
  // An interface of another kind (Ethernet, loopback) would fail at bind with a bare
  // "Invalid argument"; its hardware type says what is wrong.
  ifreq request{};
  std::memcpy(request.ifr_name, iface.c_str(), iface.size() + 1);
  if (::ioctl(fd_, SIOCGIFHWADDR, &request) == 0 && request.ifr_hwaddr.sa_family != ARPHRD_CAN) {
    ::close(fd_);
    throw InterfaceError(iface + ": not a CAN interface");
  }
  // Error frames: everything the controller reports (bus-off, passive, overflow...);
  // kernel receive timestamps; the receive queue's drop count; own frames or not.
  can_err_mask_t err_mask = CAN_ERR_MASK;
  int on = 1;
  int own = receive_own ? 1 : 0;
  set_option(SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask, "CAN_RAW_ERR_FILTER");
  set_option(SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on, "SO_TIMESTAMPNS");
  set_option(SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on, "SO_RXQ_OVFL");
  set_option(SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &own, sizeof own, "CAN_RAW_RECV_OWN_MSGS");
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0) {
    int saved = errno;
    ::close(fd_);
    errno = saved;
    fail(iface, "bind");
  }
}

void SocketCan::set_option(int level, int name, const void* value, size_t size, const char* what) {
  if (::setsockopt(fd_, level, name, value, static_cast<socklen_t>(size)) == 0) return;
  int saved = errno;
  ::close(fd_);
  fd_ = -1;
  errno = saved;
  fail(iface_, std::string("setsockopt ") + what);
}

SocketCan::~SocketCan() {
  if (fd_ >= 0) ::close(fd_);
}

void SocketCan::set_filters(const std::vector<Filter>& filters) {
  std::vector<can_filter> f;
  f.reserve(filters.size());
  // CAN_EFF_FLAG in the mask with it clear in the id: 11-bit frames only. CAN_RTR_FLAG in
  // the mask: data frames only. An exact 11-bit data-frame filter (mask 0x7FF with both
  // flags) is the kernel's fast case, a table lookup by identifier.
  for (const Filter& x : filters)
    f.push_back({x.id & CAN_SFF_MASK,
                 (x.mask & CAN_SFF_MASK) | CAN_EFF_FLAG | (x.remote_too ? 0 : CAN_RTR_FLAG)});
  if (f.empty()) f.push_back({0, 0});  // everything
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, f.data(),
                   static_cast<socklen_t>(f.size() * sizeof(can_filter))) != 0)
    fail(iface_, "setsockopt CAN_RAW_FILTER");
}

void SocketCan::set_error_filter(uint32_t classes) {
  can_err_mask_t mask = classes & CAN_ERR_MASK;
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &mask, sizeof mask) != 0)
    fail(iface_, "setsockopt CAN_RAW_ERR_FILTER");
}

size_t SocketCan::request_receive_buffer(size_t bytes) {
  // The kernel takes an int and doubles it (for its bookkeeping) up to INT_MAX.
  const int asked = static_cast<int>(std::min<size_t>(bytes, INT_MAX / 2));
  if (const size_t now = receive_buffer(); now >= 2 * static_cast<size_t>(asked)) return now;
  if (::setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &asked, sizeof asked) != 0 &&
      ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &asked, sizeof asked) != 0)
    spdlog::warn("{}: receive buffer of {} bytes refused: {}", iface_, bytes, std::strerror(errno));
  return receive_buffer();
}

size_t SocketCan::receive_buffer() const {
  int now = 0;
  socklen_t size = sizeof now;
  if (::getsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &now, &size) != 0) return 0;
  return static_cast<size_t>(now);
}

std::optional<ReceivedFrame> SocketCan::receive() {
  can_frame raw{};
  iovec iov{&raw, sizeof raw};
  char control[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(uint32_t)) + 64];
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  ssize_t n = ::recvmsg(fd_, &msg, 0);
  if (n < 0) {
    if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)
      spdlog::warn("{}: receive failed: {}", iface_, std::strerror(errno));
    return std::nullopt;
  }
  if (n != static_cast<ssize_t>(sizeof raw)) return std::nullopt;  // CAN FD frames: not ours
  ReceivedFrame r;
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_TIMESTAMPNS) {
      timespec ts;
      std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
      r.kernel_time_ns =
          static_cast<uint64_t>(ts.tv_sec) * 1'000'000'000u + static_cast<uint64_t>(ts.tv_nsec);
    } else if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
      std::memcpy(&rx_overruns_, CMSG_DATA(c), sizeof rx_overruns_);
    }
  }
  if (raw.can_id & CAN_ERR_FLAG) {
    r.error_frame = true;
    r.error_class = raw.can_id & CAN_ERR_MASK;
    r.controller_status = raw.data[1];
    r.protocol_status = raw.data[2];
    return r;
  }
  if (raw.can_id & CAN_EFF_FLAG) return std::nullopt;  // CANopen uses 11-bit IDs only
  r.frame.id = raw.can_id & CAN_SFF_MASK;
  r.frame.rtr = (raw.can_id & CAN_RTR_FLAG) != 0;
  r.frame.dlc = std::min<uint8_t>(raw.len, 8);
  std::memcpy(r.frame.data.data(), raw.data, r.frame.dlc);
  return r;
}

void SocketCan::send(const od::CanFrame& frame) {
  if (queue_.size() >= kMaxQueue) {
    queue_.pop_front();  // a dead bus must not grow memory without bound
    ++dropped_;
  }
  queue_.push_back(frame);
  flush();
}

bool SocketCan::flush() {
  while (!queue_.empty()) {
    const od::CanFrame& f = queue_.front();
    can_frame raw{};
    raw.can_id = f.id | (f.rtr ? CAN_RTR_FLAG : 0);
    raw.len = f.dlc;
    std::memcpy(raw.data, f.data.data(), f.dlc);
    ssize_t n = ::write(fd_, &raw, sizeof raw);
    if (n == static_cast<ssize_t>(sizeof raw)) {
      queue_.pop_front();
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS || errno == EINTR))
      return false;  // the controller queue is full: retry when writable
    // ENETDOWN (interface down, bus-off): keep the frame and retry on the next tick.
    if (n < 0 && errno == ENETDOWN) return false;
    spdlog::warn("{}: send failed: {}", iface_, std::strerror(errno));
    queue_.pop_front();
    ++dropped_;
  }
  return true;
}

}  // namespace stepnode::canio
