// Issue 13: the following error of CSP (60F4h against 6065h, time-out 6066h, CiA 402-2
// "Position control function") without polling. A drive woken only at its own deadlines
// (next_event), at the SYNCs and at the steps in the 1 ms batches of a node at step
// horizon 0 faults (8611h) 6066h after a tick at which the error really left the window:
// the per-tick trace of 60F4h (a reference drive advanced at every tick of the 4.9152 MHz
// timebase: the steps do not depend on when the drive looks) is inside at the tick before
// and outside at it. And no later than the drive polled every 1 ms as before issue 13.
#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <vector>

#include "node/profiles/cia402/tests/drive_harness.hpp"

namespace stepnode::cia402 {
namespace {

constexpr Tick kCycle = kClockHz / 1000;  // SYNC every 1 ms

struct Axis {
  RecordingMachine motor;
  motion::AxisCore core{{&motor}};
  Drive drive{core};
  Tick now = 0;
  std::optional<Tick> fault_at;
  unsigned wakeups = 0;
  std::vector<int32_t> trace;  // 60F4h after each advance (the reference: at every tick)

  explicit Axis(uint32_t max_velocity, uint32_t window, uint16_t timeout_ms) {
    Parameters& p = drive.parameters();
    p.max_velocity = max_velocity;
    p.following_error_window = window;
    p.following_error_timeout_ms = timeout_ms;
    p.interpolation_period = kCycle;
    drive.set_mode(Mode::CyclicSyncPosition, 0);
    for (uint16_t cw : {0x06, 0x07, 0x0F}) drive.controlword(cw, 0);
  }
  void advance(Tick t) {
    drive.advance(now = t);
    ++wakeups;
    trace.push_back(drive.following_error());
    if (!fault_at && drive.error_code() == 0x8611) fault_at = now;
  }
};

// The master's set-points: a ramp up to `speed` steps per cycle, held; SYNC k at k cycles.
std::vector<int32_t> set_points(int cycles, int speed) {
  std::vector<int32_t> p;
  int32_t x = 0;
  for (int k = 1; k <= cycles; ++k) p.push_back(x += std::min(k, speed));
  return p;
}

// Every tick (the rule's own definition), SYNCs at their ticks.
void run_every_tick(Axis& a, const std::vector<int32_t>& targets) {
  for (size_t k = 0; k < targets.size(); ++k) {
    const Tick sync = static_cast<Tick>(k + 1) * kCycle;
    while (a.now + 1 < sync) a.advance(a.now + 1);
    a.advance(sync);
    a.drive.set_target_position(targets[k]);
    a.drive.sync(sync, sync);
  }
  for (Tick end = a.now + 10 * kCycle; a.now < end;) a.advance(a.now + 1);
}

// As the node runs it: woken at the drive's next event (or polled every 1 ms, as before
// issue 13), or at the next step but at most once per 1 ms (step horizon 0's batch), or at
// a SYNC.
void run_event_driven(Axis& a, const std::vector<int32_t>& targets, bool poll = false) {
  const auto wake_before = [&a, poll](Tick limit) {
    for (;;) {
      Tick next = limit;
      if (const std::optional<Tick> e = a.drive.next_event(a.now)) next = std::min(next, *e);
      if (poll) next = std::min(next, a.now + ms(1));
      if (const std::optional<Tick> s = a.core.next_step_time())
        next = std::min(next, std::max(*s, a.now + kCycle));
      if (next >= limit) return;
      a.advance(next);
    }
  };
  for (size_t k = 0; k < targets.size(); ++k) {
    const Tick sync = static_cast<Tick>(k + 1) * kCycle;
    wake_before(sync);
    a.advance(sync);
    a.drive.set_target_position(targets[k]);
    a.drive.sync(sync, sync);
  }
  wake_before(a.now + 10 * kCycle);
}

struct Case {
  uint32_t max_velocity, window;
  uint16_t timeout_ms;
  int speed;  // the master's steps per cycle once ramped up
};

class FollowingErrorDeadline : public ::testing::TestWithParam<Case> {};

TEST_P(FollowingErrorDeadline, FaultsTheTimeOutAfterTheErrorLeftTheWindow) {
  const Case c = GetParam();
  const std::vector<int32_t> targets = set_points(40, c.speed);
  Axis reference(c.max_velocity, UINT32_MAX, 0);  // the trace only: no fault stops it
  Axis woken(c.max_velocity, c.window, c.timeout_ms);
  Axis polled(c.max_velocity, c.window, c.timeout_ms);
  run_every_tick(reference, targets);
  run_event_driven(woken, targets);
  run_event_driven(polled, targets, true);
  ASSERT_TRUE(woken.fault_at) << "the case must lag out of its window";
  ASSERT_TRUE(polled.fault_at);
  EXPECT_LE(*woken.fault_at, *polled.fault_at);
  const Tick left = *woken.fault_at - ms(c.timeout_ms);  // reference.trace[t - 1]: tick t
  ASSERT_GE(left, 2);
  EXPECT_GT(std::abs(reference.trace[static_cast<size_t>(left - 1)]), int32_t(c.window));
  EXPECT_LE(std::abs(reference.trace[static_cast<size_t>(left - 2)]), int32_t(c.window));
  // At most one wake-up per SYNC, per 1 ms batch of steps and per drive event.
  EXPECT_LT(woken.wakeups, 3 * targets.size() + 20);
}

// 607Fh below what the master asks (a ramp of 1 more step a cycle each cycle, to `speed`).
INSTANTIATE_TEST_SUITE_P(LaggingAxes, FollowingErrorDeadline,
                         ::testing::Values(Case{20'000, 50, 3, 25}, Case{20'000, 5, 0, 60},
                                           Case{20'000, 30, 1, 30}, Case{1'000, 20, 5, 5},
                                           Case{30'000, 30, 0, 60}));

TEST(FollowingErrorDeadlineSingle, TimeOutComes6066hAfterTheDemandLeftThe6065hWindow) {
  // One SYNC, no more (missed SYNCs): 500 steps in a cycle of 1 ms at most 99 steps, so the
  // demand runs ahead of the steps. It leaves the window of 50 at the first tick x at which
  // floor(500 x / c) exceeds floor(99 x / c) + 50: x = ceil(51 c / 401) or later, within a
  // tick of it (the floors); the fault 6066h (2 ms) later.
  Axis a(100'000, 50, 2);
  a.drive.set_target_position(500);
  a.drive.sync(0, 0);
  Tick first_outside = 0;
  for (Tick x = 1; x <= kCycle; ++x)
    if (500 * x / kCycle - 99 * x / kCycle > 50) {
      first_outside = x;
      break;
    }
  ASSERT_NEAR(static_cast<double>(first_outside), 51.0 * kCycle / 401, 13.0);
  ASSERT_EQ(a.drive.next_event(0), first_outside) << "the drive's deadline: the exit itself";
  a.advance(first_outside);
  EXPECT_EQ(a.drive.next_event(a.now), first_outside + ms(2)) << "then the time-out";
  a.advance(first_outside + ms(2) - 1);
  EXPECT_FALSE(a.fault_at);
  a.advance(first_outside + ms(2));
  EXPECT_EQ(a.fault_at, first_outside + ms(2));
  EXPECT_EQ(a.drive.statusword() & kStateMask, kFault);
}

TEST(FollowingErrorDeadlineSingle, AnAxisThatKeepsUpHasNoDeadline) {
  // 50 steps in the cycle, none capped: demand and steps agree at every tick.
  Axis a(1'000'000, 0, 0);
  a.drive.set_target_position(50);
  a.drive.sync(0, 0);
  EXPECT_EQ(a.drive.next_event(0), std::nullopt);
}

}  // namespace
}  // namespace stepnode::cia402
