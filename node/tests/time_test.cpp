// TIME (CiA 301 7.2.6, 0x1012): the consumer keeps the network time from TIME_OF_DAY stamps
// and shows it in 0x2F12; the producer sends the node's wall clock. The frames are written
// from the standard: 6 bytes, little-endian, milliseconds after midnight in the low 28
// bits of the first four, days since 1984-01-01 in the last two.
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

// 2024-06-15 12:34:56.789 UTC: day 14776 (0x39B8) since 1984-01-01, 45,296,789 ms
// (0x02B32C95) after midnight; 1,718,454,896,789 ms since 1970.
const CanFrame kJune15(0x100, {0x95, 0x2C, 0xB3, 0x02, 0xB8, 0x39});
constexpr uint32_t kJune15Ms = 45'296'789;
constexpr uint16_t kJune15Day = 14776;
constexpr uint64_t kJune15Unix = 1'718'454'896'789;

class TimeTest : public NodeHarness {
 protected:
  uint64_t unix_ms() {
    od::SdoResult r = transfer(false, 0x2F12, 3);
    EXPECT_TRUE(r.ok());
    return od::decode<uint64_t>(r.data);
  }
};

TEST_F(TimeTest, TheDefaultConsumesTimeOn0x100) {
  EXPECT_EQ(*sdo_read(0x1012, 0), 0x80000100u);  // bit 31: consumer
  EXPECT_EQ(*sdo_read(0x2F12, 4), 0u);           // no network time yet
  EXPECT_EQ(*sdo_read(0x2F12, 1), 0u);
  frame(kJune15);
  EXPECT_EQ(*sdo_read(0x2F12, 1), kJune15Ms);
  EXPECT_EQ(*sdo_read(0x2F12, 2), kJune15Day);
  EXPECT_EQ(unix_ms(), kJune15Unix);
  EXPECT_EQ(*sdo_read(0x2F12, 4), 1u);  // consumed
}

TEST_F(TimeTest, TheNodesClockRunsTheTimeOnBetweenStamps) {
  frame(kJune15);
  advance_ms(1500);
  EXPECT_EQ(*sdo_read(0x2F12, 1), kJune15Ms + 1500);
  EXPECT_EQ(unix_ms(), kJune15Unix + 1500);
}

TEST_F(TimeTest, TheStampIsTheTimeTheFrameArrived) {
  // Read by the node 30 ms after it reached the interface: the 30 ms have passed already.
  device->on_frame(kJune15, t, t - 30'000);
  EXPECT_EQ(*sdo_read(0x2F12, 1), kJune15Ms + 30);
}

TEST_F(TimeTest, MidnightStartsTheNextDay) {
  // 23:59:59.500 of day 14776: 86,399,500 ms = 0x05265A0C.
  frame(CanFrame(0x100, {0x0C, 0x5A, 0x26, 0x05, 0xB8, 0x39}));
  advance_ms(1000);
  EXPECT_EQ(*sdo_read(0x2F12, 1), 500u);
  EXPECT_EQ(*sdo_read(0x2F12, 2), kJune15Day + 1u);
}

TEST_F(TimeTest, TheFourReservedBitsAreIgnoredAndBadFramesAreNot) {
  frame(CanFrame(0x100, {0x95, 0x2C, 0xB3, 0xF2, 0xB8, 0x39}));  // bits 28..31 set
  EXPECT_EQ(*sdo_read(0x2F12, 1), kJune15Ms);
  frame(CanFrame(0x100, {0x00, 0x00, 0x00, 0x00}));              // 4 bytes: no TIME_OF_DAY
  frame(CanFrame(0x100, {0x00, 0x5C, 0x26, 0x05, 0x00, 0x00}));  // 86,400,000 ms: no time of day
  EXPECT_EQ(*sdo_read(0x2F12, 1), kJune15Ms);
}

TEST_F(TimeTest, WithoutTheConsumerBitTimeIsIgnored) {
  ASSERT_EQ(sdo_write(0x1012, 0, 0x00000100), 0u);
  frame(kJune15);
  EXPECT_EQ(*sdo_read(0x2F12, 4), 0u);
  EXPECT_EQ(*sdo_read(0x2F12, 1), 0u);
}

TEST_F(TimeTest, NotConsumedInStopped) {
  nmt(0x02);
  frame(kJune15);
  nmt(0x80);
  EXPECT_EQ(*sdo_read(0x2F12, 4), 0u);
}

TEST_F(TimeTest, TheCanIdChangesOnlyWhileTimeIsNeitherConsumedNorProduced) {
  EXPECT_EQ(sdo_write(0x1012, 0, 0x80000101), 0x06090030u);
  EXPECT_EQ(sdo_write(0x1012, 0, 0x20000100), 0x06090030u);  // 29-bit CAN-ID
  ASSERT_EQ(sdo_write(0x1012, 0, 0x00000100), 0u);
  EXPECT_EQ(sdo_write(0x1012, 0, 0x00000101), 0x06090030u);  // restricted (CiA 301 7.3.5)
  ASSERT_EQ(sdo_write(0x1012, 0, 0x000000F0), 0u);
  ASSERT_EQ(sdo_write(0x1012, 0, 0x800000F0), 0u);
  frame(CanFrame(0x0F0, {0x95, 0x2C, 0xB3, 0x02, 0xB8, 0x39}));
  EXPECT_EQ(*sdo_read(0x2F12, 1), kJune15Ms);
  ASSERT_EQ(sdo_write(0x1010, 2, 0x65766173), 0u);  // stored with the communication group
  make();
  EXPECT_EQ(*sdo_read(0x1012, 0), 0x800000F0u);
}

class TimeProducerTest : public NodeHarness {
 protected:
  void SetUp() override {
    NodeOptions o;
    o.device.node_id = kId;
    o.state_dir = dir.path;
    // The node's wall clock reads 2024-06-15 12:34:56.789 UTC at the start.
    const uint64_t start = t;
    o.wall_clock = [this, start] { return kJune15Unix * 1000 + (t - start); };
    make(o);
  }
};

TEST_F(TimeProducerTest, ProducesItsWallClockEveryPeriod) {
  size_t from = sent.size();
  advance_ms(3000);
  EXPECT_TRUE(with_id(0x100, from).empty());  // consumer only by default
  from = sent.size();
  const uint64_t at = t;
  ASSERT_EQ(sdo_write(0x1012, 0, 0x40000100), 0u);  // bit 30: producer
  advance_ms(2500);
  auto stamps = with_id(0x100, from);
  ASSERT_EQ(stamps.size(), 3u);  // at once, then every 1000 ms (0x2F12:5)
  // The first: 3000 ms after the start, 12:34:59.789 = 45,299,789 ms = 0x02B3384D.
  EXPECT_EQ(stamps[0], CanFrame(0x100, {0x4D, 0x38, 0xB3, 0x02, 0xB8, 0x39}));
  auto times = times_of(0x100, from);
  EXPECT_EQ(times[0], at);  // with the write's answer
  EXPECT_EQ(times[1] - times[0], 1'000'000u);
  EXPECT_EQ(od::get_u32(stamps[1].data.data()), 45'299'789u + 1000);
  EXPECT_EQ(*sdo_read(0x2F12, 4), 2u);  // produced
}

TEST_F(TimeProducerTest, ThePeriodIsAnObjectAndZeroStopsTheProducer) {
  ASSERT_EQ(sdo_write(0x2F12, 5, 250, 2), 0u);
  ASSERT_EQ(sdo_write(0x1012, 0, 0x40000100), 0u);
  size_t from = sent.size();
  advance_ms(1000);
  EXPECT_EQ(with_id(0x100, from).size(), 4u);
  ASSERT_EQ(sdo_write(0x2F12, 5, 0, 2), 0u);
  from = sent.size();
  advance_ms(1000);
  EXPECT_TRUE(with_id(0x100, from).empty());
}

TEST_F(TimeTest, AProducerWithoutAClockOrAStampSendsNothing) {
  ASSERT_EQ(sdo_write(0x1012, 0, 0x40000100), 0u);
  size_t from = sent.size();
  advance_ms(3000);
  EXPECT_TRUE(with_id(0x100, from).empty());
}

}  // namespace
}  // namespace stepnode::node::test
