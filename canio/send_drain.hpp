// A send queue drained by the socket's writability (issue 13, event-driven timing): while
// frames wait for the kernel, the loop watches for EPOLLOUT instead of retrying every 1 ms,
// so a blocked queue costs no wake-ups and drains as soon as the kernel takes frames again.
//
// SocketCAN says "writable" by the socket's own send buffer. A queue below the socket
// (the interface's qdisc, txqueuelen) that is full refuses a frame with ENOBUFS although
// the socket is writable: writability then says nothing, and waiting for it would spin.
// So if the kernel refuses frames right after saying writable, the queue is retried by the
// poll period (node/deadline.hpp) until it is empty, as before.
#pragma once
#include <functional>

#include "canio/event_loop.hpp"

namespace stepnode::canio {

class SendDrain {
 public:
  // `flush` sends what the kernel takes and returns true once nothing waits; `after` runs
  // after each flush this drain makes (the owner re-arms its timer, tells what was sent).
  SendDrain(EventLoop& loop, int fd, std::function<bool()> flush, std::function<void()> after);

  // After anything that may have queued or sent frames: `pending` frames wait.
  void update(bool pending);
  // Writability said nothing (the kernel refused frames right after it): retry by the poll.
  bool needs_poll() const { return polling_; }

 private:
  void writable();

  EventLoop& loop_;
  int fd_;
  std::function<bool()> flush_;
  std::function<void()> after_;
  bool polling_ = false;
};

}  // namespace stepnode::canio
