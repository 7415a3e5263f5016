#include "canio/send_drain.hpp"

#include <poll.h>

#include <utility>

namespace stepnode::canio {
namespace {

// The socket says it can take data now (its own send buffer has room).
bool says_writable(int fd) {
  pollfd p{fd, POLLOUT, 0};
  return ::poll(&p, 1, 0) == 1 && (p.revents & POLLOUT);
}

}  // namespace

SendDrain::SendDrain(EventLoop& loop, int fd, std::function<bool()> flush,
                     std::function<void()> after)
    : loop_(loop), fd_(fd), flush_(std::move(flush)), after_(std::move(after)) {
  loop_.on_writable(fd_, [this] { writable(); });
}

void SendDrain::update(bool pending) {
  if (!pending) polling_ = false;  // the next blocked queue tries writability again
  loop_.want_writable(fd_, pending && !polling_);
}

void SendDrain::writable() {
  const bool empty = flush_();
  // Refused while the socket still says writable: a queue below it is full (ENOBUFS), and
  // EPOLLOUT would report the same at once. A socket whose own buffer is full says not
  // writable until the kernel has sent frames: the next EPOLLOUT means room.
  polling_ = !empty && says_writable(fd_);
  loop_.want_writable(fd_, !empty && !polling_);
  if (after_) after_();
}

}  // namespace stepnode::canio
