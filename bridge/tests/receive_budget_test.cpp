// The bridge's loop under a flood (issue 13): stepbridge's socket handler, bounded by
// handle_frames, on canio's epoll loop with a 1 ms timer and SIGTERM, fed by a socket that
// never runs dry (each frame handled puts another in). The timer must run and SIGTERM must
// end the loop while the flood goes on; with an unbounded drain neither happens until the
// flood stops by itself, which the second test shows (so the first can fail).
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <csignal>
#include <cstdint>
#include <limits>
#include <optional>

#include "bridge/observer/receive_budget.hpp"
#include "canio/event_loop.hpp"

namespace stepnode::bridge {
namespace {

constexpr uint64_t kFloodEnd = 200'000;  // frames after which the flood stops by itself

struct Flood {
  int fds[2] = {-1, -1};
  uint64_t handled = 0;
  uint64_t handled_at_first_tick = 0;
  unsigned ticks = 0;
  Flood() {
    if (::socketpair(AF_UNIX, SOCK_DGRAM | SOCK_NONBLOCK, 0, fds) != 0)
      throw std::runtime_error("socketpair");
    for (int i = 0; i < 16; ++i) put();  // a queue that is never empty
  }
  ~Flood() {
    ::close(fds[0]);
    ::close(fds[1]);
  }
  void put() {
    const uint8_t frame[16] = {};
    (void)!::send(fds[1], frame, sizeof frame, 0);
  }
  std::optional<int> receive() {
    uint8_t frame[16];
    if (::recv(fds[0], frame, sizeof frame, 0) <= 0) return std::nullopt;
    return 0;
  }
};

// Runs the loop as bridge/main.cpp builds it; returns when SIGTERM (sent at the first
// timer tick) ended it.
void run(Flood& flood, size_t budget) {
  canio::EventLoop loop;
  loop.stop_on_signals();
  loop.watch(flood.fds[0], [&] {
    handle_frames([&] { return flood.receive(); },
                  [&](int) {
                    if (++flood.handled < kFloodEnd) flood.put();
                  },
                  budget);
  });
  loop.every(1000, [&] {
    if (flood.ticks++ == 0) {
      flood.handled_at_first_tick = flood.handled;
      ::kill(::getpid(), SIGTERM);
    }
  });
  loop.run();
}

TEST(ReceiveBudget, TimersAndSigtermAreServedDuringAFlood) {
  Flood flood;
  run(flood, kFramesPerTurn);
  EXPECT_GE(flood.ticks, 1u);
  EXPECT_LT(flood.handled_at_first_tick, kFloodEnd) << "the timer ran while frames kept coming";
  EXPECT_LT(flood.handled, kFloodEnd) << "SIGTERM ended the loop while frames kept coming";
}

TEST(ReceiveBudget, AnUnboundedDrainStarvesTheTimerUntilTheFloodEnds) {
  Flood flood;
  run(flood, std::numeric_limits<size_t>::max());
  EXPECT_GE(flood.handled_at_first_tick, kFloodEnd) << "the timer waited for the whole flood";
}

TEST(ReceiveBudget, HandlesAtMostTheBudgetAndStopsWhenEmpty) {
  int left = 100;
  auto receive = [&]() -> std::optional<int> {
    return left-- > 0 ? std::optional<int>(left) : std::nullopt;
  };
  int seen = 0;
  EXPECT_EQ(handle_frames(
                receive, [&](int) { ++seen; }, 64),
            64u);
  EXPECT_EQ(handle_frames(
                receive, [&](int) { ++seen; }, 64),
            36u);
  EXPECT_EQ(handle_frames(
                receive, [&](int) { ++seen; }, 64),
            0u);
  EXPECT_EQ(seen, 100);
}

}  // namespace
}  // namespace stepnode::bridge
