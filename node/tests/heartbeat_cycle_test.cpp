// The heartbeat producer's cycle when a heartbeat goes out late (issue 13: "heartbeat phase
// keeping sends the heartbeat after a late one early"). CiA 301 7.2.8.3.2.2: the producer
// sends every 0x1017 ms, and a consumer watches only that no gap is longer than its
// consumer time. What a consumer sees here: a heartbeat late by at most a tenth of 0x1017
// (the loop's latency) keeps the cycle, so the heartbeat does not drift; a later one restarts
// the cycle, so no two heartbeats come closer than 0.9 × 0x1017 (no burst after a stall).
#include <random>

#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

constexpr uint64_t kPeriodUs = 100'000;  // 0x1017 = 100 ms

class HeartbeatCycleTest : public NodeHarness {
 protected:
  void SetUp() override {
    NodeHarness::SetUp();
    EXPECT_EQ(sdo_write(0x1017, 0, kPeriodUs / 1000, 2), 0u);
    advance_ms(300);  // the 100 ms cycle has taken over
    from_ = sent.size();
    last_ = times_of(kHeartbeatId).back();
  }
  // The one tick of the node at `late_us` after the next heartbeat is due: the heartbeat
  // goes out then.
  void tick_late(uint64_t late_us) {
    t = last_ + kPeriodUs + late_us;
    device->on_tick(t);
    ASSERT_EQ(times_of(kHeartbeatId, from_).back(), t);
  }
  // The heartbeats after SetUp's last, on 1 ms ticks up to `until`.
  std::vector<uint64_t> run_until(uint64_t until) {
    advance_us(until - t);
    return times_of(kHeartbeatId, from_);
  }
  void expect_gaps(uint64_t seed, uint64_t longest_gap_us, bool on_cycle);
  size_t from_ = 0;
  uint64_t last_ = 0;  // SetUp's last heartbeat, on the cycle
};

TEST_F(HeartbeatCycleTest, LateByATenthOfThePeriodKeepsTheCycle) {
  tick_late(kPeriodUs / 10);  // 10 ms late, the most that keeps the cycle
  const std::vector<uint64_t> at = run_until(last_ + 3 * kPeriodUs);
  // Due at last + 100 ms, sent at +110 ms; the next ones on the cycle, at +200 and +300 ms.
  EXPECT_EQ(at, (std::vector<uint64_t>{last_ + 110'000, last_ + 200'000, last_ + 300'000}));
}

TEST_F(HeartbeatCycleTest, LaterThanATenthRestartsTheCycleAtTheLateOne) {
  tick_late(kPeriodUs / 10 + 1'000);  // 11 ms late
  const std::vector<uint64_t> at = run_until(last_ + 3 * kPeriodUs + 11'000);
  // Not 89 ms after the late one (the old cycle), a whole period: +111, +211, +311 ms.
  EXPECT_EQ(at, (std::vector<uint64_t>{last_ + 111'000, last_ + 211'000, last_ + 311'000}));
}

TEST_F(HeartbeatCycleTest, NoBurstAfterAStallOfSeveralPeriods) {
  tick_late(2 * kPeriodUs + 5'000);  // three heartbeats due, one goes out, 205 ms late
  const std::vector<uint64_t> at = run_until(last_ + 5 * kPeriodUs);
  EXPECT_EQ(at, (std::vector<uint64_t>{last_ + 305'000, last_ + 405'000}));
}

// Ticks at random gaps (a loaded process's wake-ups): every heartbeat gap is at least
// 0.9 × 0x1017 and at most 0x1017 + the longest tick gap, whatever the lateness; with every
// lateness within a tenth of 0x1017, the n-th heartbeat stays within a tick gap of its
// place on the cycle (no drift over 1,000 periods).
void HeartbeatCycleTest::expect_gaps(uint64_t seed, uint64_t longest_gap_us, bool on_cycle) {
  const uint64_t first_due = last_ + kPeriodUs;
  std::mt19937_64 rng(seed);
  const uint64_t end = t + 1'000 * kPeriodUs;
  while (t < end) {
    t += 1 + rng() % longest_gap_us;
    device->on_tick(t);
  }
  const std::vector<uint64_t> at = times_of(kHeartbeatId, from_);
  ASSERT_GT(at.size(), 800u);
  for (size_t i = 1; i < at.size(); ++i) {
    EXPECT_GE(at[i] - at[i - 1], kPeriodUs * 9 / 10) << "heartbeat " << i;
    EXPECT_LE(at[i] - at[i - 1], kPeriodUs + longest_gap_us) << "heartbeat " << i;
  }
  if (!on_cycle) return;
  for (size_t i = 0; i < at.size(); ++i) {
    EXPECT_GE(at[i], first_due + i * kPeriodUs) << "heartbeat " << i;
    EXPECT_LT(at[i], first_due + i * kPeriodUs + longest_gap_us) << "heartbeat " << i;
  }
}

TEST_F(HeartbeatCycleTest, RandomLatenessWithinATenthStaysOnTheCycle) {
  expect_gaps(1017, kPeriodUs / 10, true);
}

TEST_F(HeartbeatCycleTest, RandomLatenessBeyondATenthNeverBunchesHeartbeats) {
  expect_gaps(7, kPeriodUs / 2, false);
}

}  // namespace
}  // namespace stepnode::node::test
