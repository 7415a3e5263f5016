#include "canio/event_loop.hpp"

#include <sys/epoll.h>
#include <sys/signalfd.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <ctime>
#include <stdexcept>
#include <string>

namespace stepnode::canio {
namespace {

// A failed system call, named, with errno's text.
[[noreturn]] void throw_system_error(const char* call) {
  throw std::runtime_error(std::string(call) + ": " + std::strerror(errno));
}

timespec to_timespec(uint64_t us) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(us / 1'000'000);
  ts.tv_nsec = static_cast<long>((us % 1'000'000) * 1000);
  return ts;
}

}  // namespace

EventLoop::EventLoop() : epoll_fd_(::epoll_create1(EPOLL_CLOEXEC)) {
  if (epoll_fd_ < 0) throw_system_error("epoll_create1");
}

EventLoop::~EventLoop() {
  for (int fd : owned_fds_) ::close(fd);
  ::close(epoll_fd_);
}

uint64_t EventLoop::now_us() {
  timespec ts;
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1'000'000u + static_cast<uint64_t>(ts.tv_nsec) / 1000;
}

void EventLoop::watch(int fd, Callback on_readable) {
  epoll_event ev{};
  ev.events = EPOLLIN;
  ev.data.fd = fd;
  if (::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd, &ev) < 0) throw_system_error("epoll_ctl");
  callbacks_[fd].readable = std::move(on_readable);
}

void EventLoop::on_writable(int fd, Callback on_writable) {
  callbacks_[fd].writable = std::move(on_writable);
}

void EventLoop::want_writable(int fd, bool wanted) {
  Watch& w = callbacks_[fd];
  if (w.writable_wanted == wanted) return;
  epoll_event ev{};
  ev.events = EPOLLIN | (wanted ? EPOLLOUT : 0u);
  ev.data.fd = fd;
  if (::epoll_ctl(epoll_fd_, EPOLL_CTL_MOD, fd, &ev) < 0) throw_system_error("epoll_ctl");
  w.writable_wanted = wanted;
}

void EventLoop::every(uint64_t period_us, Callback on_tick) {
  const int fd = add_timer(std::move(on_tick));
  itimerspec spec{};
  spec.it_interval = to_timespec(period_us);
  spec.it_value = spec.it_interval;
  ::timerfd_settime(fd, 0, &spec, nullptr);
}

int EventLoop::add_timer(Callback on_due) {
  int fd = ::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
  if (fd < 0) throw_system_error("timerfd_create");
  owned_fds_.push_back(fd);
  watch(fd, [fd, cb = std::move(on_due)] {
    uint64_t expirations = 0;
    if (::read(fd, &expirations, sizeof expirations) > 0) cb();
  });
  return fd;
}

// A member although it uses no member: the timer is this loop's (add_timer), armed through it.
// NOLINTNEXTLINE(readability-convert-member-functions-to-static)
void EventLoop::arm_at(int timer, uint64_t at_us) {
  itimerspec spec{};  // no interval: one expiry
  // An it_value of zero would disarm the timer: a time long past is 1 ns, due at once.
  spec.it_value = to_timespec(at_us);
  if (spec.it_value.tv_sec == 0 && spec.it_value.tv_nsec == 0) spec.it_value.tv_nsec = 1;
  if (::timerfd_settime(timer, TFD_TIMER_ABSTIME, &spec, nullptr) < 0)
    throw_system_error("timerfd_settime");
}

void EventLoop::stop_on_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  ::sigprocmask(SIG_BLOCK, &set, nullptr);
  int fd = ::signalfd(-1, &set, SFD_NONBLOCK | SFD_CLOEXEC);
  if (fd < 0) throw_system_error("signalfd");
  owned_fds_.push_back(fd);
  watch(fd, [this, fd] {
    signalfd_siginfo info;
    if (::read(fd, &info, sizeof info) > 0) stop();
  });
}

void EventLoop::dispatch(int fd, uint32_t events) {
  // Looked up for each callback: a callback may change what is watched.
  if (events & (EPOLLIN | EPOLLERR | EPOLLHUP)) {
    auto it = callbacks_.find(fd);
    if (it != callbacks_.end() && it->second.readable) it->second.readable();
  }
  if (events & EPOLLOUT) {
    auto it = callbacks_.find(fd);
    if (it != callbacks_.end() && it->second.writable_wanted && it->second.writable)
      it->second.writable();
  }
}

void EventLoop::run() {
  running_ = true;
  epoll_event events[16];
  while (running_) {
    int n = ::epoll_wait(epoll_fd_, events, 16, -1);
    ++wakeups_;
    if (n < 0) {
      if (errno == EINTR) continue;
      throw_system_error("epoll_wait");
    }
    for (int i = 0; i < n && running_; ++i) dispatch(events[i].data.fd, events[i].events);
  }
}

}  // namespace stepnode::canio
