// A small epoll loop: file descriptors with callbacks, periodic timerfds, and signals via
// signalfd so SIGINT/SIGTERM end the loop cleanly.
#pragma once
#include <cstdint>
#include <functional>
#include <map>
#include <vector>

namespace stepnode::canio {

class EventLoop {
 public:
  using Callback = std::function<void()>;
  EventLoop();
  ~EventLoop();
  EventLoop(const EventLoop&) = delete;
  EventLoop& operator=(const EventLoop&) = delete;

  void watch(int fd, Callback on_readable);
  // `on_writable` runs while `fd` (already watched) can take data and writability is wanted
  // (want_writable): a send queue waits for the kernel instead of polling it. Not wanted
  // at first, so a socket that is almost always writable does not wake the loop.
  void on_writable(int fd, Callback on_writable);
  void want_writable(int fd, bool wanted);
  // Calls `on_tick` every `period_us` (a timerfd; missed expirations are coalesced).
  void every(uint64_t period_us, Callback on_tick);
  // A one-shot timer on absolute CLOCK_MONOTONIC time (a timerfd with TFD_TIMER_ABSTIME):
  // `on_due` runs once the time given to arm_at() has come (at once if it has passed).
  // The caller re-arms it, usually for the earliest deadline of what it runs.
  int add_timer(Callback on_due);
  void arm_at(int timer, uint64_t at_us);
  // How often epoll_wait returned (the process woke), for figures.
  uint64_t wakeups() const { return wakeups_; }
  // Ends run() on SIGINT or SIGTERM (they are blocked for the whole process).
  void stop_on_signals();
  void run();
  void stop() { running_ = false; }

  static uint64_t now_us();  // CLOCK_MONOTONIC

 private:
  void dispatch(int fd, uint32_t events);

  int epoll_fd_ = -1;
  struct Watch {
    Callback readable, writable;
    bool writable_wanted = false;
  };
  std::map<int, Watch> callbacks_;
  std::vector<int> owned_fds_;
  bool running_ = false;
  uint64_t wakeups_ = 0;
};

}  // namespace stepnode::canio
