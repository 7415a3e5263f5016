// A bridge that starts after the nodes: event-driven TPDOs of an idle axis never come, so
// discovery ends with a snapshot of every axis read over SDO (status, DONE?, HP error,
// positions). A TPDO that arrives meanwhile is newer and wins.
#include <gtest/gtest.h>

#include "test_bus.hpp"

namespace stepnode::bridge::test {
namespace {

TEST(Snapshot, IdleAxesArePublishedWithoutAnyTpdo) {
  TestBus bus;
  FakeNode node({.id = 5, .axes = 2, .pscale = 2.0, .hp_objects = true});
  node.set_status(0, 0x1100);  // at home, position valid
  node.set_position(0, 0, 0);
  node.set_status(1, 0x0180);
  node.set_position(1, 5000, 4990);
  node.dictionary().put<int8_t>(0x2118, 0, 2);
  bus.add(node).state = 0x05;
  bus.send(node.heartbeat(0x05));  // the bridge starts: the node is already running
  bus.run_ms(50);
  ASSERT_TRUE(bus.observer.node_health(5, bus.now_us).discovered);
  ASSERT_EQ(bus.sink.statuses.size(), 2u);
  EXPECT_EQ(bus.sink.statuses[0].axis, 1);
  EXPECT_EQ(bus.sink.statuses[0].status_bits, 0x1100);
  EXPECT_EQ(bus.sink.statuses[1].axis, 2);
  EXPECT_EQ(bus.sink.statuses[1].status_bits, 0x0180);
  EXPECT_EQ(bus.sink.statuses[1].done_code, 2);
  ASSERT_EQ(bus.sink.positions.size(), 2u);
  EXPECT_EQ(bus.sink.positions[1].motor_position, 5000);
  EXPECT_EQ(bus.sink.positions[1].encoder_position, 4990);
  EXPECT_DOUBLE_EQ(bus.sink.positions[1].motor_user_units, 10000.0);
  // The reads that made the snapshot, for axis 2: 0x2101, 0x2118, 0x2119, 0x2105, 0x2106.
  std::vector<uint16_t> reads;
  for (const od::CanFrame& f : bus.observer_sent)
    if (f.data[0] == 0x40) reads.push_back(od::get_u16(&f.data[1]));
  ASSERT_GE(reads.size(), 5u);
  EXPECT_EQ(std::vector<uint16_t>(reads.end() - 5, reads.end()),
            (std::vector<uint16_t>{0x2101, 0x2118, 0x2119, 0x2105, 0x2106}));
}

TEST(Snapshot, ATpdoDuringTheSnapshotWins) {
  TestBus bus;
  FakeNode node({.id = 5, .axes = 1});
  node.set_status(0, 0x0180);
  bus.add(node).state = 0x05;
  node.hold = true;  // answers leave the node one step at a time
  bus.send(node.heartbeat(0x05));
  // Step until the snapshot's status read (the second read of 0x2001; the first was the
  // axis probe) has been answered by the node but the answer is still on its way.
  int status_reads = 0;
  for (int step = 0; step < 200 && status_reads < 2; ++step) {
    const od::CanFrame& last = bus.observer_sent.back();
    if (last.data[0] == 0x40 && od::get_u16(&last.data[1]) == 0x2001) ++status_reads;
    if (status_reads < 2) bus.release(node, true);
  }
  ASSERT_EQ(status_reads, 2);
  ASSERT_EQ(node.held.size(), 1u) << "the snapshot's answer, with status 0x0180";
  EXPECT_TRUE(bus.sink.statuses.empty());
  node.set_status(0, 0x8180);  // a move starts; its TPDO overtakes the SDO answer
  bus.send(node.tpdo(0));
  ASSERT_EQ(bus.sink.statuses.size(), 1u) << "TPDOs are decoded during the snapshot";
  bus.release(node);
  EXPECT_TRUE(bus.observer.node_health(5, bus.now_us).discovered);
  ASSERT_EQ(bus.sink.statuses.size(), 1u) << "the older snapshot value is not published";
  EXPECT_EQ(bus.sink.statuses[0].status_bits, 0x8180);
}

TEST(Snapshot, NotReadAgainAfterARemap) {
  TestBus bus;
  FakeNode node({.id = 5, .axes = 1});
  bus.add(node).state = 0x05;
  bus.boot(node);
  bus.run_ms(50);
  bus.master_start(5);
  bus.master_download(0x1801, 1, od::encode<uint32_t>(0xC0000285));
  bus.master_download(0x1801, 1, od::encode<uint32_t>(0x40000285));
  const size_t before = bus.observer_sent.size();
  bus.sink.clear();
  bus.run_ms(400);
  ASSERT_GT(bus.observer_sent.size(), before) << "the TPDO parameters were read again";
  for (size_t i = before; i < bus.observer_sent.size(); ++i) {
    const uint16_t index = od::get_u16(&bus.observer_sent[i].data[1]);
    EXPECT_TRUE(index >= 0x1800 && index <= 0x1BFF) << std::hex << index;
  }
  EXPECT_TRUE(bus.sink.statuses.empty());
  EXPECT_TRUE(bus.sink.positions.empty());
}

}  // namespace
}  // namespace stepnode::bridge::test
