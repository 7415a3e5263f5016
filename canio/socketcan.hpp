// SocketCAN raw transport: a non-blocking CAN_RAW socket with kernel receive timestamps,
// error frames, and a send queue that absorbs a full controller queue (ENOBUFS/EAGAIN).
#pragma once
#include <cstdint>
#include <deque>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "od/can_frame.hpp"

namespace stepnode::canio {

struct ReceivedFrame {
  od::CanFrame frame;
  uint64_t kernel_time_ns = 0;  // CLOCK_REALTIME receive timestamp from the kernel
  bool error_frame = false;
  uint32_t error_class = 0;       // CAN_ERR_* bits of an error frame
  uint8_t controller_status = 0;  // data[1] of a CAN_ERR_CRTL error frame
  uint8_t protocol_status = 0;
};

// The interface named is not one this process can use as a CAN bus: no such interface, a
// name that cannot be one, or an interface that is not CAN (e.g. "lo"). Bad input: the
// processes exit with status 2 for it, and 1 for the other (runtime) failures.
struct InterfaceError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A kernel receive filter: the 11-bit data frames whose CAN-ID matches `id` in the bits
// of `mask`, and remote frames too if `remote_too`.
struct Filter {
  uint32_t id = 0;
  uint32_t mask = 0x7FF;
  bool remote_too = false;
};

class SocketCan {
 public:
  // Opens and binds a raw socket on `iface`. Throws InterfaceError for an interface that is
  // missing or not CAN, std::runtime_error naming the interface and the failing call for the
  // rest (no SocketCAN in the kernel, a socket option refused, bind).
  explicit SocketCan(const std::string& iface, bool receive_own = false);
  ~SocketCan();
  SocketCan(const SocketCan&) = delete;
  SocketCan& operator=(const SocketCan&) = delete;

  int fd() const { return fd_; }
  const std::string& iface() const { return iface_; }
  // Kernel acceptance filters (CAN_RAW_FILTER, at most 512); an empty list means every
  // frame again (to the kernel itself, no filter would mean none). Frames already queued
  // stay queued. A listed filter passes no extended (29-bit) frame.
  void set_filters(const std::vector<Filter>& filters);
  // The error frame classes (CAN_ERR_* bits) the socket receives; all by default.
  void set_error_filter(uint32_t classes);
  // Asks for a receive queue of `bytes`, so a burst of frames (many nodes behind one
  // socket) is queued rather than dropped: SO_RCVBUFFORCE (CAP_NET_ADMIN, may exceed
  // net.core.rmem_max), else SO_RCVBUF (capped by the kernel at rmem_max). Never fails: the
  // queue keeps what the kernel granted. Returns the size the socket has now, as the kernel
  // counts it (getsockopt SO_RCVBUF: about twice what was asked, its overhead included).
  // Asks nothing where the socket already has that much: it never shrinks the queue.
  size_t request_receive_buffer(size_t bytes);
  // The receive queue's size as the kernel counts it (getsockopt SO_RCVBUF; a new socket's
  // is net.core.rmem_default), 0 if it cannot be read.
  size_t receive_buffer() const;

  // Reads one frame if one is waiting.
  std::optional<ReceivedFrame> receive();
  // Queues and sends as far as the kernel accepts; the rest waits for flush().
  void send(const od::CanFrame& frame);
  // Sends queued frames; returns true when the queue is empty.
  bool flush();
  bool has_pending() const { return !queue_.empty(); }
  uint64_t dropped() const { return dropped_; }
  // Received frames the kernel dropped because this socket's queue was full, since it was
  // opened (SO_RXQ_OVFL; the count arrives with the next frame that is received).
  uint32_t receive_overruns() const { return rx_overruns_; }

 private:
  void set_option(int level, int name, const void* value, size_t size, const char* what);

  int fd_ = -1;
  std::string iface_;
  std::deque<od::CanFrame> queue_;
  uint64_t dropped_ = 0;
  uint32_t rx_overruns_ = 0;
  static constexpr size_t kMaxQueue = 4096;
};

}  // namespace stepnode::canio
