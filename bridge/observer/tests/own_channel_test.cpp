// The bridge on an SDO server channel of its own (the node's 0x1201, CiA 301 7.5.2.33):
// it reads there at once, whatever a master does on the default channel, and still
// follows the master's TPDO remapping seen on the default channel.
#include <gtest/gtest.h>

#include "test_bus.hpp"

namespace stepnode::bridge::test {
namespace {

constexpr uint32_t kRx = 0x685, kTx = 0x6C5;

ObserverConfig own_channel() {
  ObserverConfig cfg;
  cfg.sdo_quiet_ms = 300;
  cfg.sdo_channels.push_back(NodeSdoChannel{5, kRx, kTx});
  return cfg;
}

TEST(OwnSdoChannel, DiscoveryReadsOnItAndDoesNotWaitForTheMasters) {
  TestBus bus(own_channel());
  FakeNode node({.id = 5, .axes = 2, .channel_rx = kRx, .channel_tx = kTx});
  bus.add(node);
  bus.master_start(5);
  bus.master_upload(0x1008, 0);  // a master is busy on the default channel ...
  bus.send(node.heartbeat(0x7F));
  ASSERT_FALSE(bus.observer_sent.empty()) << "... which does not delay the bridge";
  bus.run_ms(50);
  const NodeHealthSample h = bus.observer.node_health(5, bus.now_us);
  EXPECT_TRUE(h.discovered);
  EXPECT_EQ(h.axes, 2);
  EXPECT_EQ(h.sdo_failures, 0u);
  for (const od::CanFrame& f : bus.observer_sent) EXPECT_EQ(f.id, kRx);
}

TEST(OwnSdoChannel, AMastersRemapOnTheDefaultChannelIsStillFollowed) {
  TestBus bus(own_channel());
  FakeNode node({.id = 5, .axes = 1, .channel_rx = kRx, .channel_tx = kTx});
  bus.add(node).state = 0x05;
  bus.boot(node);
  bus.run_ms(100);
  ASSERT_TRUE(bus.observer.node_health(5, bus.now_us).discovered);
  bus.master_start(5);
  const size_t reads_before = bus.observer_sent.size();
  // TPDO2 onto 0x1F0 by the CiA 301 procedure: invalid, new ID valid.
  for (uint32_t cob : {0xC0000285u, 0x400001F0u}) {
    bus.master_download(0x1801, 1, od::encode<uint32_t>(cob));
    ASSERT_TRUE(bus.master->result().ok());
    bus.run_ms(5);
  }
  bus.run_ms(20);  // no quiet wait: the bridge's channel is its own
  EXPECT_GT(bus.observer_sent.size(), reads_before);
  bus.sink.clear();  // (the re-read's own snapshot of the axis)
  node.set_position(0, 777, 770);
  const od::CanFrame f = node.tpdo(1);
  ASSERT_EQ(f.id, 0x1F0u);
  bus.send(f);
  ASSERT_EQ(bus.sink.positions.size(), 1u);
  EXPECT_EQ(bus.sink.positions[0].motor_position, 777);
  EXPECT_EQ(bus.observer.node_health(5, bus.now_us).sdo_failures, 0u);
}

TEST(OwnSdoChannel, OtherNodesStayOnTheirDefaultChannel) {
  TestBus bus(own_channel());
  FakeNode other({.id = 6, .axes = 1});
  bus.add(other);
  bus.boot(other);
  bus.run_ms(50);
  EXPECT_TRUE(bus.observer.node_health(6, bus.now_us).discovered);
  ASSERT_FALSE(bus.observer_sent.empty());
  EXPECT_EQ(bus.observer_sent.front().id, 0x606u);
}

}  // namespace
}  // namespace stepnode::bridge::test
