// SYNC (CiA 301 7.2.5, objects 0x1005, 0x1006, 0x1019): the producer with and without a
// counter, the counter restart when leaving stopped, SYNCs of the wrong length (EMCY
// 0x8240), and the TPDO SYNC start value (0x18xx:6) that goes with the counter.
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

class SyncTest : public PdoHarness {};

TEST_F(SyncTest, ProducerWithoutAndWithCounter) {
  map_tpdo(0, {kReg1}, 1);
  nmt(0x01);
  ASSERT_EQ(sdo_write(0x1006, 0, 10'000), 0u);  // 10 ms
  size_t from = sent.size();
  advance_ms(100);
  EXPECT_TRUE(with_id(0x80, from).empty());  // bit 30 of 0x1005 not set: consumer only
  ASSERT_EQ(sdo_write(0x1005, 0, 0x40000080), 0u);
  from = sent.size();
  advance_ms(100);
  auto syncs = with_id(0x80, from);
  EXPECT_GE(syncs.size(), 9u);
  EXPECT_LE(syncs.size(), 10u);
  for (const auto& f : syncs) EXPECT_EQ(f.dlc, 0);
  auto times = times_of(0x80, from);
  for (size_t i = 1; i < times.size(); ++i) EXPECT_EQ(times[i] - times[i - 1], 10'000u);
  // The node's own SYNC drives its synchronous PDOs.
  EXPECT_EQ(with_id(kTpdo1, from).size(), syncs.size());

  // The counter overflow may only change while the period is 0 (7.5.2.22).
  EXPECT_EQ(sdo_write(0x1019, 0, 3, 1), 0x08000022u);
  ASSERT_EQ(sdo_write(0x1006, 0, 0), 0u);
  from = sent.size();
  advance_ms(100);
  EXPECT_TRUE(with_id(0x80, from).empty());  // period 0: no SYNC
  ASSERT_EQ(sdo_write(0x1019, 0, 3, 1), 0u);
  ASSERT_EQ(sdo_write(0x1006, 0, 10'000), 0u);
  from = sent.size();
  advance_ms(75);
  std::vector<uint8_t> counters;
  for (const auto& f : with_id(0x80, from)) {
    EXPECT_EQ(f.dlc, 1);
    counters.push_back(f.data[0]);
  }
  EXPECT_EQ(counters, (std::vector<uint8_t>{1, 2, 3, 1, 2, 3, 1}));
}

TEST_F(SyncTest, ProducerIsSilentInStoppedAndRestartsTheCounterAfterwards) {
  ASSERT_EQ(sdo_write(0x1019, 0, 5, 1), 0u);
  ASSERT_EQ(sdo_write(0x1006, 0, 10'000), 0u);
  ASSERT_EQ(sdo_write(0x1005, 0, 0x40000080), 0u);
  advance_ms(25);  // counters 1, 2
  nmt(0x02);
  size_t from = sent.size();
  advance_ms(100);
  EXPECT_TRUE(with_id(0x80, from).empty());
  // CiA 301 7.2.5: the counter restarts at 1 when the device leaves stopped.
  nmt(0x80);
  from = sent.size();
  advance_ms(25);
  auto syncs = with_id(0x80, from);
  ASSERT_FALSE(syncs.empty());
  EXPECT_EQ(syncs[0].data[0], 1);
}

TEST_F(SyncTest, WrongLengthRaisesEmcy8240AndIsNotProcessed) {
  map_tpdo(0, {kReg1}, 1);
  nmt(0x01);
  size_t from = sent.size();
  sync(7);  // no counter configured: a SYNC has no data
  auto e = emcys(from);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(emcy_code(e[0]), 0x8240);
  EXPECT_TRUE(with_id(kTpdo1, from).empty());
  // With a counter configured, a SYNC without it is the wrong length.
  nmt(0x80);
  ASSERT_EQ(sdo_write(0x1019, 0, 10, 1), 0u);
  nmt(0x01);
  from = sent.size();
  sync();
  frame(CanFrame(0x80, {1, 2}));
  e = emcys(from);
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(emcy_code(e[0]), 0x8240);
  EXPECT_TRUE(with_id(kTpdo1, from).empty());
  sync(1);
  EXPECT_EQ(with_id(kTpdo1, from).size(), 1u);
}

TEST_F(SyncTest, StartValueWaitsForItsCounter) {
  ASSERT_EQ(sdo_write(0x1019, 0, 6, 1), 0u);
  map_tpdo(0, {kReg1}, 2);
  ASSERT_EQ(sdo_write(0x1800, 1, 0xC0000185), 0u);
  ASSERT_EQ(sdo_write(0x1800, 6, 3, 1), 0u);
  ASSERT_EQ(sdo_write(0x1800, 1, 0x40000185), 0u);
  nmt(0x01);
  size_t from = sent.size();
  std::vector<uint8_t> on;
  for (uint8_t c : {1, 2, 3, 4, 5, 6, 1, 2, 3}) {
    size_t before = with_id(kTpdo1, from).size();
    sync(c);
    if (with_id(kTpdo1, from).size() > before) on.push_back(c);
  }
  // The SYNC whose counter equals the start value is the first one; then every 2nd.
  EXPECT_EQ(on, (std::vector<uint8_t>{3, 5, 1, 3}));
}

TEST_F(SyncTest, StartValueIsIgnoredWithoutASyncCounter) {
  // CiA 301 (TPDO sub-index 06h): with no counter in the SYNC (0x1019 = 0) it is ignored.
  map_tpdo(0, {kReg1}, 2);
  ASSERT_EQ(sdo_write(0x1800, 1, 0xC0000185), 0u);
  ASSERT_EQ(sdo_write(0x1800, 6, 3, 1), 0u);
  ASSERT_EQ(sdo_write(0x1800, 1, 0x40000185), 0u);
  nmt(0x01);
  size_t from = sent.size();
  for (int i = 0; i < 6; ++i) sync();
  EXPECT_EQ(with_id(kTpdo1, from).size(), 3u);
}

}  // namespace
}  // namespace stepnode::node::test
