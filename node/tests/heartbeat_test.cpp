// Heartbeat producer (0x1017) and consumer (0x1016), CiA 301 7.2.8.3.2 and 7.5.2.18/19,
// in virtual time.
#include "node/tests/node_harness.hpp"
#include "node/tests/recording_application.hpp"

namespace stepnode::node::test {
namespace {

class HeartbeatTest : public NodeHarness {
 protected:
  std::vector<uint64_t> intervals(const std::vector<uint64_t>& times) const {
    std::vector<uint64_t> out;
    for (size_t i = 1; i < times.size(); ++i) out.push_back(times[i] - times[i - 1]);
    return out;
  }
};

TEST_F(HeartbeatTest, ProducerSendsEveryPeriodFromTheStateChange) {
  uint64_t t0 = t;  // boot-up and the first heartbeat went out at t0
  advance_ms(5000);
  auto times = times_of(kHeartbeatId);
  ASSERT_EQ(times.size(), 7u);  // boot-up, 7F at t0, then 1000 ms apart
  EXPECT_EQ(times[1], t0);
  for (size_t i = 2; i < times.size(); ++i) EXPECT_EQ(times[i], t0 + (i - 1) * 1'000'000);
  for (const auto& f : with_id(kHeartbeatId, 1)) EXPECT_EQ(f, CanFrame(0x705, {0x7F}));
}

TEST_F(HeartbeatTest, ProducerKeepsItsPeriodWithCoarseTicks) {
  ASSERT_EQ(sdo_write(0x1017, 0, 100, 2), 0u);
  size_t from = sent.size();
  advance_ms(10'000, 7000);  // 7 ms ticks: each heartbeat late by < 7 ms, no drift
  auto n = with_id(kHeartbeatId, from).size();
  EXPECT_GE(n, 99u);
  EXPECT_LE(n, 101u);
}

TEST_F(HeartbeatTest, ProducerPeriodChangesAtRunTime) {
  ASSERT_EQ(sdo_write(0x1017, 0, 100, 2), 0u);
  advance_ms(300);  // the new period has taken over
  size_t from = sent.size();
  advance_ms(1000);
  auto times = times_of(kHeartbeatId, from);
  ASSERT_EQ(times.size(), 10u);
  for (uint64_t d : intervals(times)) EXPECT_EQ(d, 100'000u);

  // 0 switches the producer off...
  ASSERT_EQ(sdo_write(0x1017, 0, 0, 2), 0u);
  from = sent.size();
  advance_ms(5000);
  EXPECT_TRUE(with_id(kHeartbeatId, from).empty());
  // ...also for state changes (the heartbeat confirms a state only when produced).
  nmt(0x01);
  EXPECT_TRUE(with_id(kHeartbeatId, from).empty());

  // And a new value switches it on again, in the current state.
  ASSERT_EQ(sdo_write(0x1017, 0, 250, 2), 0u);
  advance_ms(300);
  from = sent.size();
  advance_ms(1000);
  times = times_of(kHeartbeatId, from);
  ASSERT_EQ(times.size(), 4u);
  for (uint64_t d : intervals(times)) EXPECT_EQ(d, 250'000u);
  for (const auto& f : with_id(kHeartbeatId, from)) EXPECT_EQ(f, CanFrame(0x705, {0x05}));
}

TEST_F(HeartbeatTest, BootUpIsSentEvenWithTheProducerOff) {
  ASSERT_EQ(sdo_write(0x1017, 0, 0, 2), 0u);
  ASSERT_EQ(sdo_write(0x1010, 2, od::kSaveSignature), 0u);
  make();  // restart with 0x1017 = 0 stored
  EXPECT_EQ(od().get<uint16_t>(0x1017, 0), 0);
  EXPECT_EQ(with_id(kHeartbeatId), (std::vector<CanFrame>{CanFrame(0x705, {0x00})}));
  advance_ms(3000);
  EXPECT_EQ(with_id(kHeartbeatId).size(), 1u);
}

TEST_F(HeartbeatTest, EachStateShowsInThePeriodicHeartbeat) {
  struct {
    uint8_t cs;
    uint8_t state;
  } steps[] = {{0x01, 0x05}, {0x02, 0x04}, {0x80, 0x7F}};
  for (auto s : steps) {
    nmt(s.cs);
    size_t from = sent.size();
    advance_ms(2000);
    auto hb = with_id(kHeartbeatId, from);
    ASSERT_EQ(hb.size(), 2u);
    for (const auto& f : hb) EXPECT_EQ(f, CanFrame(0x705, {s.state}));
  }
}

// Consumer: node 0x20 watched with 300 ms.
class HeartbeatConsumerTest : public HeartbeatTest {
 protected:
  void SetUp() override {
    HeartbeatTest::SetUp();
    node->set_application(&app);
    ASSERT_EQ(sdo_write(0x1016, 1, (0x20u << 16) | 300), 0u);
  }
  void heartbeat_of(uint8_t n, uint8_t state = 0x05) { frame(CanFrame(0x700u + n, {state})); }
  RecordingApplication app;
  std::vector<uint8_t>& lost = app.lost;
};

TEST_F(HeartbeatConsumerTest, MonitoringStartsWithTheFirstHeartbeat) {
  advance_ms(5000);  // nothing heard from node 0x20 yet: not an error (7.2.8.3.2.2)
  EXPECT_TRUE(lost.empty());
  EXPECT_TRUE(emcys().empty());
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0);
}

TEST_F(HeartbeatConsumerTest, TimeoutRaisesEmcy8130AndRecoveryClearsIt) {
  heartbeat_of(0x20);
  uint64_t heard = t;
  advance_ms(300);  // exactly the consumer time: still fine
  EXPECT_TRUE(lost.empty());
  EXPECT_TRUE(emcys().empty());
  advance_ms(1);
  EXPECT_EQ(lost, (std::vector<uint8_t>{0x20}));
  auto e = emcys();
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].dlc, 8);
  EXPECT_EQ(emcy_code(e[0]), 0x8130);
  EXPECT_EQ(e[0].data[2] & 0x10, 0x10);  // error register bit 4: communication error
  EXPECT_EQ(e[0].data[2] & 0x01, 0x01);  // bit 0: generic, set with any error
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0x11);
  EXPECT_EQ(od().get<uint32_t>(0x1003, 1) & 0xFFFF, 0x8130u);
  EXPECT_GT(t, heard + 300'000);

  // Once lost, it stays one event (no repeat, no second hook call).
  advance_ms(2000);
  EXPECT_EQ(lost.size(), 1u);
  EXPECT_EQ(emcys().size(), 1u);

  // The node is back: EMCY "error reset" (code 0000) with the register now 0.
  size_t from = sent.size();
  heartbeat_of(0x20);
  e = emcys(from);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], CanFrame(kEmcyId, {0, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0);

  // Monitoring goes on: a second loss is a second event.
  advance_ms(400);
  EXPECT_EQ(lost.size(), 2u);
}

TEST_F(HeartbeatConsumerTest, AnyHeartbeatOfTheNodeKeepsItAliveOthersDoNot) {
  heartbeat_of(0x20, 0x7F);
  for (int i = 0; i < 20; ++i) {
    advance_ms(250);
    heartbeat_of(0x21);          // another node
    frame(CanFrame(0x720, {}));  // not a heartbeat: no data byte
    heartbeat_of(0x20, i % 2 ? 0x05 : 0x04);
  }
  EXPECT_TRUE(lost.empty());
  for (int i = 0; i < 5; ++i) {
    advance_ms(100);
    heartbeat_of(0x21);
  }
  EXPECT_EQ(lost, (std::vector<uint8_t>{0x20}));
}

TEST_F(HeartbeatConsumerTest, TwoLostNodesClearOnlyWhenBothAreBack) {
  ASSERT_EQ(sdo_write(0x1016, 2, (0x30u << 16) | 200), 0u);
  // The same node twice is refused (CiA 301 7.5.2.18).
  EXPECT_EQ(sdo_write(0x1016, 3, (0x30u << 16) | 500), 0x06040043u);
  heartbeat_of(0x20);
  heartbeat_of(0x30);
  advance_ms(500);
  EXPECT_EQ(lost.size(), 2u);
  EXPECT_EQ(emcys().size(), 1u);  // one active condition, one EMCY
  size_t from = sent.size();
  heartbeat_of(0x20);
  EXPECT_TRUE(emcys(from).empty());
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0x11);
  heartbeat_of(0x30);
  ASSERT_EQ(emcys(from).size(), 1u);
  EXPECT_EQ(emcy_code(emcys(from)[0]), 0x0000);
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0);
}

TEST_F(HeartbeatConsumerTest, ConfiguringAnotherEntryKeepsMonitoringTheFirst) {
  heartbeat_of(0x20);
  advance_ms(400);
  ASSERT_EQ(lost.size(), 1u);
  ASSERT_EQ(od().get<uint8_t>(0x1001, 0), 0x11);
  // The master adds a second consumer entry while node 0x20 is lost...
  ASSERT_EQ(sdo_write(0x1016, 2, (0x30u << 16) | 500), 0u);
  // ...node 0x20 comes back: its error is over.
  size_t from = sent.size();
  heartbeat_of(0x20);
  auto e = emcys(from);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(emcy_code(e[0]), 0x0000);
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0);
  // And its monitoring went on without a pause: a loss is found at once.
  advance_ms(301);
  EXPECT_EQ(lost.size(), 2u);
}

TEST_F(HeartbeatConsumerTest, RemovingTheEntryOfALostNodeEndsItsError) {
  heartbeat_of(0x20);
  advance_ms(400);
  ASSERT_EQ(od().get<uint8_t>(0x1001, 0), 0x11);
  size_t from = sent.size();
  ASSERT_EQ(sdo_write(0x1016, 1, 0), 0u);  // no longer monitored
  auto e = emcys(from);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(emcy_code(e[0]), 0x0000);
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0);
}

TEST_F(HeartbeatConsumerTest, ConsumerTimeZeroOrNodeZeroIsNotMonitored) {
  ASSERT_EQ(sdo_write(0x1016, 1, (0x20u << 16) | 0), 0u);
  ASSERT_EQ(sdo_write(0x1016, 2, (0x00u << 16) | 100), 0u);
  heartbeat_of(0x20);
  advance_ms(2000);
  EXPECT_TRUE(lost.empty());
  EXPECT_TRUE(emcys().empty());
}

TEST_F(HeartbeatConsumerTest, ConsumerRunsInEveryState) {
  nmt(0x01);
  heartbeat_of(0x20);
  advance_ms(400);
  EXPECT_EQ(lost.size(), 1u);
  heartbeat_of(0x20);
  nmt(0x02);  // stopped: error control still runs (CiA 301 table 85)
  heartbeat_of(0x20);
  advance_ms(400);
  EXPECT_EQ(lost.size(), 2u);
}

}  // namespace
}  // namespace stepnode::node::test
