// Heartbeat into NMT state, loss (3 x the interval, at least 1 s, or the configured
// timeout) into LOST with the axes disposed, re-discovery when it comes back, and NodeHealth
// on every change and at least every health period.
#include <gtest/gtest.h>

#include "bridge/observer/heartbeat_monitor.hpp"
#include "test_bus.hpp"

namespace stepnode::bridge::test {
namespace {

struct Beating : ::testing::Test {
  TestBus bus;
  FakeNode node{{.id = 5, .axes = 3}};
  void SetUp() override {
    bus.add(node, 100);
    bus.boot(node);
    bus.run_ms(350);
    ASSERT_TRUE(bus.observer.node_health(5, bus.now_us).discovered);
  }
};

TEST_F(Beating, NmtStateFollowsTheHeartbeat) {
  EXPECT_EQ(bus.observer.node_health(5, bus.now_us).state, NodeState::PreOperational);
  bus.sink.clear();
  bus.beat_of(node).state = 0x05;
  bus.run_ms(100);
  ASSERT_FALSE(bus.sink.healths.empty()) << "a state change is published at once";
  EXPECT_EQ(bus.sink.healths.front().state, NodeState::Operational);
  bus.sink.clear();
  bus.run_ms(500);
  EXPECT_TRUE(bus.sink.healths.empty()) << "same state, within the health period: nothing new";
  bus.beat_of(node).state = 0x04;
  bus.run_ms(100);
  ASSERT_FALSE(bus.sink.healths.empty());
  EXPECT_EQ(bus.sink.healths.back().state, NodeState::Stopped);
}

TEST_F(Beating, LossAfterThreeIntervalsButAtLeastOneSecond) {
  bus.sink.clear();
  bus.beat_of(node).beating = false;
  const uint64_t last_beat_us = bus.beat_of(node).next_us - 100'000;
  while (bus.now_us < last_beat_us + 999'000) bus.run_ms(1);
  EXPECT_EQ(bus.observer.node_health(5, bus.now_us).state, NodeState::PreOperational)
      << "3 x 100 ms is below the 1 s floor";
  EXPECT_TRUE(bus.sink.disposed.empty());
  bus.run_ms(2);
  EXPECT_EQ(bus.observer.node_health(5, bus.now_us).state, NodeState::Lost);
  ASSERT_EQ(bus.sink.disposed.size(), 1u);
  EXPECT_EQ(bus.sink.disposed[0], std::make_pair(uint8_t{5}, uint8_t{3}));
  ASSERT_NE(bus.sink.last_health(5), nullptr);
  EXPECT_EQ(bus.sink.last_health(5)->state, NodeState::Lost);
  EXPECT_GE(bus.sink.last_health(5)->heartbeat_age_ms, 1000u);
  // Lost is said once, and disposing once is enough.
  bus.run_ms(3000);
  EXPECT_EQ(bus.sink.disposed.size(), 1u);
}

// A master changes the node's heartbeat period: the interval measured before (100 ms, so
// a 1 s timeout) must not turn the slower heartbeat into a loss.
TEST_F(Beating, AMasterSlowingTheHeartbeatIsNoLoss) {
  bus.master_start(5);
  bus.master_download(0x1017, 0, od::encode<uint16_t>(2000));
  ASSERT_TRUE(bus.master->done());
  ASSERT_TRUE(bus.master->result().ok());
  bus.beat_of(node).period_us = 2'000'000;
  bus.beat_of(node).next_us = bus.now_us + 2'000'000;
  bus.sink.clear();
  bus.run_ms(10'000);
  EXPECT_NE(bus.observer.node_health(5, bus.now_us).state, NodeState::Lost);
  EXPECT_TRUE(bus.sink.disposed.empty());
  EXPECT_TRUE(bus.observer.node_health(5, bus.now_us).discovered) << "read again after the change";
}

// Switched off (0x1017 = 0): no heartbeat to miss, so no verdict at all.
TEST_F(Beating, AMasterSwitchingTheHeartbeatOffIsNoLoss) {
  bus.master_start(5);
  bus.master_download(0x1017, 0, od::encode<uint16_t>(0));
  ASSERT_TRUE(bus.master->result().ok());
  bus.beat_of(node).beating = false;
  bus.sink.clear();
  bus.run_ms(10'000);
  EXPECT_NE(bus.observer.node_health(5, bus.now_us).state, NodeState::Lost);
  EXPECT_TRUE(bus.sink.disposed.empty());
}

TEST_F(Beating, TpdosOfALostNodeAreNotPublished) {
  bus.beat_of(node).beating = false;
  bus.run_ms(1200);
  ASSERT_EQ(bus.observer.node_health(5, bus.now_us).state, NodeState::Lost);
  bus.sink.clear();
  node.set_position(0, 5, 5);
  bus.send(node.tpdo(1));
  EXPECT_TRUE(bus.sink.positions.empty()) << "would bring back a disposed instance";
}

TEST_F(Beating, AHeartbeatAfterLossRediscovers) {
  bus.beat_of(node).beating = false;
  bus.run_ms(1200);
  const size_t reads = bus.observer_sent.size();
  bus.beat_of(node).beating = true;
  bus.beat_of(node).next_us = bus.now_us + 1000;
  bus.run_ms(50);
  EXPECT_GT(bus.observer_sent.size(), reads) << "read again after the loss";
  const NodeHealthSample h = bus.observer.node_health(5, bus.now_us);
  EXPECT_EQ(h.state, NodeState::PreOperational);
  EXPECT_TRUE(h.discovered);
  node.set_position(0, 7, 8);
  bus.sink.clear();
  bus.send(node.tpdo(1));
  EXPECT_EQ(bus.sink.positions.size(), 1u);
}

TEST_F(Beating, ConfiguredTimeoutWins) {
  ObserverConfig cfg;
  cfg.heartbeat_timeout_ms = 250;
  TestBus b(cfg);
  FakeNode n({.id = 6, .axes = 1});
  b.add(n, 100);
  b.boot(n);
  b.run_ms(350);
  b.beat_of(n).beating = false;  // the last heartbeat was at 300 ms
  b.run_ms(150);
  EXPECT_NE(b.observer.node_health(6, b.now_us).state, NodeState::Lost);
  b.run_ms(100);
  EXPECT_EQ(b.observer.node_health(6, b.now_us).state, NodeState::Lost);
  ASSERT_EQ(b.sink.disposed.size(), 1u);
  EXPECT_EQ(b.sink.disposed[0].second, 1);
}

TEST_F(Beating, HealthIsRepublishedEveryPeriodWithTheHeartbeatAge) {
  bus.sink.clear();
  bus.run_ms(3000);
  std::vector<const NodeHealthSample*> mine;
  for (const auto& h : bus.sink.healths)
    if (h.node == 5) mine.push_back(&h);
  EXPECT_GE(mine.size(), 3u);
  EXPECT_LE(mine.size(), 4u);
  for (const auto* h : mine) EXPECT_LT(h->heartbeat_age_ms, 101u);
  EXPECT_GT(mine.back()->bus.frames, mine.front()->bus.frames) << "bus counters travel along";
  EXPECT_LE(mine.back()->bus.frames, bus.observer.counters().frames);
}

TEST(HeartbeatMonitor, TimeoutRules) {
  HeartbeatMonitor m;
  EXPECT_EQ(m.timeout_us(0, 0, false), 3'000'000u) << "nothing known: 3 x an assumed 1 s";
  EXPECT_EQ(m.timeout_us(0, 2000, true), 6'000'000u) << "0x1017 before a second heartbeat";
  EXPECT_EQ(m.timeout_us(0, 0, true), 0u) << "producer off: no verdict";
  m.on_heartbeat(NodeState::BootUp, 1'000'000);
  m.on_heartbeat(NodeState::PreOperational, 1'050'000);
  EXPECT_EQ(m.interval_us(), 0u) << "boot-up to the first heartbeat is no interval";
  m.on_heartbeat(NodeState::PreOperational, 1'550'000);
  EXPECT_EQ(m.interval_us(), 500'000u);
  EXPECT_EQ(m.timeout_us(0, 2000, true), 1'500'000u) << "the observed interval wins";
  EXPECT_EQ(m.timeout_us(700, 2000, true), 700'000u);
  EXPECT_FALSE(m.check_lost(3'049'000, 0, 0, false));
  EXPECT_TRUE(m.check_lost(3'050'000, 0, 0, false));
  EXPECT_FALSE(m.check_lost(9'000'000, 0, 0, false)) << "once";
  const auto c = m.on_heartbeat(NodeState::Operational, 9'100'000);
  EXPECT_TRUE(c.was_lost);
  EXPECT_TRUE(c.state_changed);
  EXPECT_EQ(nmt_state_from_byte(0x85), NodeState::Operational) << "guarding toggle ignored";
  EXPECT_FALSE(nmt_state_from_byte(0x01).has_value());
}

TEST(Heartbeat, MalformedHeartbeatIsBad) {
  TestBus bus;
  bus.send(od::CanFrame(0x705, {0x05, 0x00}));
  bus.send(od::CanFrame(0x705, {0x33}));
  EXPECT_EQ(bus.observer.counters().bad_frames, 2u);
  EXPECT_EQ(bus.observer.node_health(5, bus.now_us).state, NodeState::Unknown);
}

}  // namespace
}  // namespace stepnode::bridge::test

namespace stepnode::bridge::test {
namespace {

TEST(AxisInstances, ANodeBackWithFewerAxesHasTheGoneOnesDisposed) {
  TestBus bus;
  FakeNode three({.id = 5, .axes = 3});
  FakeNode one({.id = 5, .axes = 1});
  bus.add(three);
  bus.boot(three);
  bus.run_ms(50);
  ASSERT_EQ(bus.observer.node_health(5, bus.now_us).axes, 3);
  EXPECT_TRUE(bus.sink.disposed.empty());
  bus.nodes[0].node = &one;  // same node id, reconfigured to one axis, restarts
  bus.sink.clear();
  bus.boot(one);
  bus.run_ms(50);
  EXPECT_EQ(bus.observer.node_health(5, bus.now_us).axes, 1);
  ASSERT_EQ(bus.sink.disposed.size(), 1u);
  EXPECT_EQ(bus.sink.disposed[0], std::make_pair(uint8_t{5}, uint8_t{3}));
  ASSERT_EQ(bus.sink.statuses.size(), 1u) << "axis 1 published again after the dispose";
  EXPECT_EQ(bus.sink.statuses[0].axis, 1);
  // A later loss disposes the one axis that is left.
  bus.beat_of(one).beating = false;
  bus.run_ms(3500);
  ASSERT_EQ(bus.sink.disposed.size(), 2u);
  EXPECT_EQ(bus.sink.disposed[1], std::make_pair(uint8_t{5}, uint8_t{1}));
}

TEST(AxisInstances, DisposeAllAtShutdown) {
  TestBus bus;
  FakeNode a({.id = 5, .axes = 2}), io({.id = 0x20, .stepnode = false});
  bus.add(a);
  bus.add(io);
  bus.boot(a);
  bus.boot(io);
  bus.run_ms(50);
  bus.observer.dispose_all();
  ASSERT_EQ(bus.sink.disposed.size(), 1u) << "only nodes with axes";
  EXPECT_EQ(bus.sink.disposed[0], std::make_pair(uint8_t{5}, uint8_t{2}));
  bus.observer.dispose_all();
  EXPECT_EQ(bus.sink.disposed.size(), 1u) << "once";
}

}  // namespace
}  // namespace stepnode::bridge::test
