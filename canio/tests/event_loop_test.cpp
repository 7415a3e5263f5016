// EventLoop's timers: a periodic timer keeps firing, a one-shot timer armed for a time
// that has passed (or for 0, which timerfd would read as "disarm") fires once, and a
// watched descriptor's callback runs when it is readable. No timing is asserted: each
// test stops the loop from a callback, and a callback that never runs would hang the
// loop, so an alarm of a generous 20 s ends such a process (a failed test, not a hang).
#include "canio/event_loop.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>

namespace stepnode::canio {
namespace {

class EventLoopTest : public ::testing::Test {
 protected:
  void SetUp() override { ::alarm(20); }
  void TearDown() override { ::alarm(0); }
};

TEST_F(EventLoopTest, PeriodicTimerFiresUntilStopped) {
  EventLoop loop;
  int ticks = 0;
  loop.every(1000, [&] {
    if (++ticks == 3) loop.stop();
  });
  loop.run();
  EXPECT_EQ(ticks, 3);
}

TEST_F(EventLoopTest, OneShotTimerInThePastFiresOnce) {
  EventLoop loop;
  int due = 0;
  const int timer = loop.add_timer([&] { ++due; });
  loop.arm_at(timer, EventLoop::now_us() - 1);
  // A second, periodic timer ends the loop after a few periods: the one-shot must not repeat.
  int ticks = 0;
  loop.every(1000, [&] {
    if (++ticks == 5) loop.stop();
  });
  loop.run();
  EXPECT_EQ(due, 1);
}

TEST_F(EventLoopTest, OneShotTimerArmedAtZeroStillFires) {
  EventLoop loop;
  int due = 0;
  const int timer = loop.add_timer([&] {
    ++due;
    loop.stop();
  });
  loop.arm_at(timer, 0);
  loop.run();
  EXPECT_EQ(due, 1);
}

TEST_F(EventLoopTest, RearmedTimerFiresAgain) {
  EventLoop loop;
  int due = 0;
  int timer = -1;
  timer = loop.add_timer([&] {
    if (++due == 2) loop.stop();
    else loop.arm_at(timer, EventLoop::now_us());
  });
  loop.arm_at(timer, EventLoop::now_us());
  loop.run();
  EXPECT_EQ(due, 2);
}

TEST_F(EventLoopTest, WatchedDescriptorRunsItsCallbackWhenReadable) {
  std::array<int, 2> fds{};
  ASSERT_EQ(::pipe(fds.data()), 0);
  EventLoop loop;
  char got = 0;
  loop.watch(fds[0], [&] {
    ASSERT_EQ(::read(fds[0], &got, 1), 1);
    loop.stop();
  });
  const char sent = 'x';
  ASSERT_EQ(::write(fds[1], &sent, 1), 1);
  loop.run();
  EXPECT_EQ(got, 'x');
  ::close(fds[0]);
  ::close(fds[1]);
}

}  // namespace
}  // namespace stepnode::canio
