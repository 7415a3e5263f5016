// The synchronous window length 0x1007 (CiA 301 7.2.2.2, 7.5.2.8): synchronous PDOs are
// sent and accepted only within the window after a SYNC. A TPDO whose window has passed
// when the SYNC is handled is not sent in that cycle; synchronous RPDO data that arrives
// after the window is discarded. The window counts from the SYNC's arrival at the
// interface (the kernel timestamp), not from when the node came round to handle it.
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

class SyncWindowTest : public PdoHarness {
 protected:
  // A SYNC that reached the interface `late_us` before the node handles it (now).
  void late_sync(uint64_t late_us) { device->on_frame(CanFrame(0x80, {}), t, t - late_us); }
  // The expected TPDO: 0x2F00:1 (UNSIGNED32) little-endian, as mapped by kReg1.
  static CanFrame expected_tpdo(uint32_t v) { return u32_frame(kTpdo1, v); }
};

TEST_F(SyncWindowTest, TheObjectIsAnUnsigned32InMicrosecondsZeroByDefaultAndStored) {
  EXPECT_EQ(*sdo_read(0x1007, 0), 0u);
  ASSERT_EQ(sdo_write(0x1007, 0, 2500), 0u);
  ASSERT_EQ(sdo_write(0x1010, 2, 0x65766173), 0u);
  make();
  EXPECT_EQ(*sdo_read(0x1007, 0), 2500u);
}

TEST_F(SyncWindowTest, ACyclicTpdoIsNotSentInACycleWhoseWindowHasPassed) {
  map_tpdo(0, {kReg1}, 1);
  ASSERT_EQ(sdo_write(0x2F00, 1, 0x11223344), 0u);
  ASSERT_EQ(sdo_write(0x1007, 0, 2000), 0u);  // 2 ms
  nmt(0x01);
  size_t from = sent.size();
  sync();  // handled at its arrival: inside the window
  ASSERT_EQ(with_id(kTpdo1, from).size(), 1u);
  EXPECT_EQ(with_id(kTpdo1, from)[0], expected_tpdo(0x11223344));

  advance_ms(10);
  from = sent.size();
  late_sync(2001);  // 1 us after the window closed
  EXPECT_TRUE(with_id(kTpdo1, from).empty());
  late_sync(2000);  // the window's last microsecond still counts
  EXPECT_EQ(with_id(kTpdo1, from).size(), 1u);
  EXPECT_EQ(device->canopen().dictionary().get<uint32_t>(0x1007, 0), 2000u);
}

TEST_F(SyncWindowTest, EveryThirdSyncLosesTheCycleAndCountsAfreshForTheNext) {
  map_tpdo(0, {kReg1}, 3);
  ASSERT_EQ(sdo_write(0x1007, 0, 1000), 0u);
  nmt(0x01);
  size_t from = sent.size();
  sync();
  sync();
  late_sync(5000);  // the third: its TPDO is not sent
  EXPECT_TRUE(with_id(kTpdo1, from).empty());
  sync();
  sync();
  EXPECT_TRUE(with_id(kTpdo1, from).empty());
  sync();  // three SYNCs after the lost cycle
  EXPECT_EQ(with_id(kTpdo1, from).size(), 1u);
}

TEST_F(SyncWindowTest, AnAcyclicTpdoWhoseWindowPassedGoesOutAtTheNextSync) {
  map_tpdo(0, {kReg1}, 0);
  ASSERT_EQ(sdo_write(0x1007, 0, 1000), 0u);
  nmt(0x01);
  sync();  // the first transmission after start
  ASSERT_EQ(sdo_write(0x2F00, 1, 0xCAFE0001), 0u);
  size_t from = sent.size();
  late_sync(1500);
  EXPECT_TRUE(with_id(kTpdo1, from).empty());
  sync();
  ASSERT_EQ(with_id(kTpdo1, from).size(), 1u);
  EXPECT_EQ(with_id(kTpdo1, from)[0], expected_tpdo(0xCAFE0001));
}

TEST_F(SyncWindowTest, WithoutAWindowALateSyncStillSendsItsTpdos) {
  map_tpdo(0, {kReg1}, 1);
  nmt(0x01);
  size_t from = sent.size();
  late_sync(500'000);
  EXPECT_EQ(with_id(kTpdo1, from).size(), 1u);
}

TEST_F(SyncWindowTest, SynchronousRpdoDataAfterTheWindowIsDiscarded) {
  map_rpdo(0, {kReg1}, 1);
  ASSERT_EQ(sdo_write(0x2F00, 1, 7), 0u);
  ASSERT_EQ(sdo_write(0x1007, 0, 1000), 0u);
  nmt(0x01);
  // Before the first SYNC no window has opened: discarded.
  frame(u32_frame(kRpdo1, 0xAAAA0001));
  sync();
  EXPECT_EQ(*sdo_read(0x2F00, 1), 7u);

  advance_us(800, 100);
  frame(u32_frame(kRpdo1, 0xAAAA0002));  // 0.8 ms after the SYNC: accepted ...
  EXPECT_EQ(*sdo_read(0x2F00, 1), 7u);
  sync();  // ... and actuated at the next SYNC
  EXPECT_EQ(*sdo_read(0x2F00, 1), 0xAAAA0002u);

  advance_us(1001, 1);
  frame(u32_frame(kRpdo1, 0xAAAA0003));  // 1.001 ms after the SYNC: discarded
  sync();
  EXPECT_EQ(*sdo_read(0x2F00, 1), 0xAAAA0002u);
}

TEST_F(SyncWindowTest, AnRpdoCountsFromItsArrivalNotFromWhenTheNodeReadIt) {
  map_rpdo(0, {kReg1}, 1);
  ASSERT_EQ(sdo_write(0x1007, 0, 1000), 0u);
  nmt(0x01);
  sync();
  advance_us(1500, 100);
  // It reached the interface 0.9 ms after the SYNC; the node read it 0.6 ms later.
  device->on_frame(u32_frame(kRpdo1, 0xBBBB0001), t, t - 600);
  sync();
  EXPECT_EQ(*sdo_read(0x2F00, 1), 0xBBBB0001u);
}

TEST_F(SyncWindowTest, EventDrivenRpdosIgnoreTheWindow) {
  map_rpdo(0, {kReg1}, 255);
  ASSERT_EQ(sdo_write(0x1007, 0, 1000), 0u);
  nmt(0x01);
  frame(u32_frame(kRpdo1, 0xCCCC0001));  // no SYNC yet, no window: applied at once
  EXPECT_EQ(*sdo_read(0x2F00, 1), 0xCCCC0001u);
}

}  // namespace
}  // namespace stepnode::node::test
