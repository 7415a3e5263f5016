// The mapping follows the node: another master remapping a TPDO mid-run (CiA 301 7.5.2.36
// procedure over SDO) and a boot-up (stored mapping back) both make the bridge read the
// TPDO parameters again; in between, a TPDO is not decoded with a layout that may be stale.
#include <gtest/gtest.h>

#include "test_bus.hpp"

namespace stepnode::bridge::test {
namespace {

struct Running : ::testing::Test {
  TestBus bus;
  FakeNode node{{.id = 5, .axes = 1}};
  void SetUp() override {
    bus.add(node).state = 0x05;
    bus.boot(node);
    bus.run_ms(300);
    ASSERT_TRUE(bus.observer.node_health(5, bus.now_us).discovered);
    bus.master_start(5);
    bus.sink.clear();
  }
  void write(uint16_t index, uint8_t sub, uint32_t value, size_t size = 4) {
    od::Bytes b = od::encode<uint32_t>(value);
    b.resize(size);
    bus.master_download(index, sub, b);
    ASSERT_TRUE(bus.master->done());
    ASSERT_TRUE(bus.master->result().ok()) << std::hex << index << ":" << int(sub) << " refused";
    bus.run_ms(5);
  }
  // TPDO2 becomes {velocity, motor position} of axis 1, on `cob`.
  void remap_tpdo2(uint32_t cob) {
    write(0x1801, 1, 0xC0000000u | 0x285);
    write(0x1A01, 0, 0, 1);
    write(0x1A01, 1, 0x20070020);
    write(0x1A01, 2, 0x20050020);
    write(0x1A01, 0, 2, 1);
    write(0x1801, 1, 0x40000000u | cob);
  }
};

TEST_F(Running, AMasterRemappingATpdoIsFollowed) {
  const size_t reads_before = bus.observer_sent.size();
  remap_tpdo2(0x285);
  node.set_position(0, 1234, 55);
  node.set_velocity(0, 800, 2);
  bus.send(node.tpdo(1));
  EXPECT_TRUE(bus.sink.positions.empty())
      << "right after the remap the old layout would read velocity as the motor position";
  EXPECT_EQ(bus.observer_sent.size(), reads_before)
      << "the bridge waits for the channel to be quiet";

  bus.run_ms(400);  // quiet for 300 ms, then the TPDO parameters are read again
  EXPECT_GT(bus.observer_sent.size(), reads_before);
  bus.send(node.tpdo(1));
  ASSERT_EQ(bus.sink.positions.size(), 1u);
  EXPECT_EQ(bus.sink.positions[0].velocity, 800);
  EXPECT_EQ(bus.sink.positions[0].motor_position, 1234);
  EXPECT_EQ(bus.observer.node_health(5, bus.now_us).sdo_failures, 0u);
}

TEST_F(Running, ANewCobIdIsFollowedAndTheOldOneDropped) {
  remap_tpdo2(0x1F0);
  bus.run_ms(400);
  node.set_velocity(0, -5, 3);
  const od::CanFrame f = node.tpdo(1);
  ASSERT_EQ(f.id, 0x1F0u);
  bus.send(f);
  ASSERT_EQ(bus.sink.positions.size(), 1u);
  EXPECT_EQ(bus.sink.positions[0].velocity, -5);
  const uint64_t undecoded = bus.observer.counters().undecoded;
  bus.send(od::CanFrame(0x285, {1, 2, 3, 4, 5, 6, 7, 8}));
  EXPECT_EQ(bus.observer.counters().undecoded, undecoded + 1);
  EXPECT_EQ(bus.sink.positions.size(), 1u);
}

TEST_F(Running, AWriteOutsideThePdoParametersDoesNotReread) {
  const size_t reads_before = bus.observer_sent.size();
  write(0x2F00, 1, 99);  // a user register
  bus.run_ms(500);
  EXPECT_EQ(bus.observer_sent.size(), reads_before);
  node.set_position(0, 9, 9);
  bus.send(node.tpdo(1));
  EXPECT_EQ(bus.sink.positions.size(), 1u) << "other TPDOs keep being decoded";
}

TEST_F(Running, ARefusedWriteIsNoRemap) {
  const size_t reads_before = bus.observer_sent.size();
  bus.master_download(0x1A01, 1, od::encode<uint32_t>(0x20070020));  // PDO valid: refused
  ASSERT_FALSE(bus.master->result().ok());
  bus.run_ms(500);
  EXPECT_EQ(bus.observer_sent.size(), reads_before);
}

TEST_F(Running, SegmentedAndBlockDownloadsCountToo) {
  for (od::SdoClient::Mode mode : {od::SdoClient::Mode::Segmented, od::SdoClient::Mode::Block}) {
    const size_t reads_before = bus.observer_sent.size();
    std::vector<od::CanFrame> out;
    // Making TPDO2 invalid is the first step of every remap.
    bus.master->start_download(0x1801, 1, od::encode<uint32_t>(0xC0000285), mode, bus.now_us, out);
    for (const od::CanFrame& f : out) bus.send(f);  // (the master's frames, in order)
    bus.run_ms(5);
    ASSERT_TRUE(bus.master->done());
    ASSERT_TRUE(bus.master->result().ok());
    bus.run_ms(400);
    EXPECT_GT(bus.observer_sent.size(), reads_before) << static_cast<int>(mode);
    write(0x1801, 1, 0x40000285);
    bus.run_ms(400);
  }
}

TEST_F(Running, AnotherMasterReadingTheMappingIsNoRemap) {
  const size_t reads_before = bus.observer_sent.size();
  bus.master_upload(0x1A01, 1);
  ASSERT_TRUE(bus.master->result().ok());
  bus.run_ms(500);
  EXPECT_EQ(bus.observer_sent.size(), reads_before);
}

TEST_F(Running, BootUpReadsEverythingAgain) {
  node.set_status(0, 0x0180);
  bus.send(node.tpdo(0));
  ASSERT_EQ(bus.sink.statuses.size(), 1u);
  bus.sink.positions.clear();  // TPDO1 carries a position too
  // The node restarts with another stored mapping for TPDO2 (velocity only).
  auto& d = node.dictionary();
  d.put<uint8_t>(0x1A01, 0, 1);
  d.put<uint32_t>(0x1A01, 1, 0x20070020);
  const size_t reads_before = bus.observer_sent.size();
  node.hold = true;  // the node is slow to answer: the re-read takes a while
  bus.boot(node);
  ASSERT_GT(bus.observer_sent.size(), reads_before);
  EXPECT_EQ(od::get_u16(&bus.observer_sent[reads_before].data[1]), 0x1017) << "from the first read";
  EXPECT_FALSE(bus.observer.node_health(5, bus.now_us).discovered);
  node.set_velocity(0, 42, 0);
  bus.send(node.tpdo(1));
  EXPECT_TRUE(bus.sink.positions.empty()) << "not decoded before the mapping is read again";
  bus.release(node);
  EXPECT_TRUE(bus.observer.node_health(5, bus.now_us).discovered);
  // The same status as before the reset is published again (from discovery's snapshot):
  // subscribers learn it is current.
  EXPECT_EQ(bus.sink.statuses.size(), 2u);
  bus.sink.positions.clear();
  bus.send(node.tpdo(1));
  ASSERT_EQ(bus.sink.positions.size(), 1u);
  EXPECT_EQ(bus.sink.positions[0].velocity, 42);
  bus.send(node.tpdo(0));
  EXPECT_EQ(bus.sink.statuses.size(), 2u) << "unchanged since the snapshot";
  EXPECT_TRUE(bus.sink.disposed.empty()) << "a boot-up is no loss";
}

}  // namespace
}  // namespace stepnode::bridge::test
