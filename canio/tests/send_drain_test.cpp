// SendDrain (issue 13): a send queue that waits for the socket's writability. On a datagram
// socketpair whose peer does not read, the writer's queue blocks (EAGAIN, the socket says
// not writable): the loop does not wake for it, and once the peer reads, the queue drains
// from the writable callback alone (no timer retries it). A kernel that refuses frames
// while the socket says writable (ENOBUFS below a SocketCAN socket) turns the drain to the
// poll period instead of spinning. No timing is asserted: wake-ups are counted, and an
// alarm of 20 s ends a loop that would hang.
#include "canio/send_drain.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>

namespace stepnode::canio {
namespace {

class SendDrainTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ::alarm(20);
    ASSERT_EQ(::socketpair(AF_UNIX, SOCK_DGRAM | SOCK_NONBLOCK, 0, fds.data()), 0);
  }
  void TearDown() override {
    ::alarm(0);
    ::close(fds[0]);
    ::close(fds[1]);
  }
  // The writer's queue: `queued` datagrams of 16 bytes; true once all are written.
  bool flush() {
    const std::array<char, 16> frame{};
    while (queued > 0) {
      if (::send(fds[0], frame.data(), frame.size(), 0) < 0) return false;
      --queued;
    }
    return true;
  }
  int read_all() {
    std::array<char, 16> buf{};
    int n = 0;
    while (::recv(fds[1], buf.data(), buf.size(), 0) > 0) ++n;
    return n;
  }
  std::array<int, 2> fds{};
  int queued = 0;
};

TEST_F(SendDrainTest, ABlockedQueueCostsNoWakeUpsAndDrainsWhenThePeerReads) {
  EventLoop loop;
  int flushes_after = 0;
  loop.watch(fds[0], [] {});
  SendDrain drain(
      loop, fds[0], [this] { return flush(); }, [&] { ++flushes_after; });
  queued = 1000;  // far more than a datagram socket queues
  ASSERT_FALSE(flush()) << "the peer's queue is full";
  const int blocked_at = queued;
  drain.update(true);
  EXPECT_FALSE(drain.needs_poll());
  int ticks = 0, received = 0;
  uint64_t wakeups_blocked = 0;
  loop.every(2000, [&] {
    ++ticks;
    if (ticks == 5) wakeups_blocked = loop.wakeups();
    if (ticks >= 5) received += read_all();  // the peer reads from then on
    if (queued == 0 && received == 1000) loop.stop();
    drain.update(queued > 0);
  });
  loop.run();
  EXPECT_EQ(queued, 0);
  EXPECT_EQ(received, 1000);
  EXPECT_LT(blocked_at, 1000);
  // While blocked only the timer woke the loop (its 4 periods before the 5th).
  EXPECT_LE(wakeups_blocked, 5u) << "a blocked queue woke the loop";
  EXPECT_GT(flushes_after, 0) << "the queue drained from the writable callback";
}

TEST_F(SendDrainTest, RefusedWhileWritableFallsBackToThePoll) {
  EventLoop loop;
  loop.watch(fds[0], [] {});
  int writable_calls = 0;
  // A kernel that refuses (ENOBUFS) though the socket has room.
  SendDrain drain(
      loop, fds[0],
      [&] {
        ++writable_calls;
        return false;
      },
      [] {});
  drain.update(true);
  int ticks = 0;
  loop.every(1000, [&] {
    drain.update(true);
    if (++ticks == 5) loop.stop();
  });
  loop.run();
  EXPECT_EQ(writable_calls, 1) << "writability said nothing: no second try by it";
  EXPECT_TRUE(drain.needs_poll());
  drain.update(false);  // the queue emptied (by the poll): writability is tried again
  EXPECT_FALSE(drain.needs_poll());
}

}  // namespace
}  // namespace stepnode::canio
