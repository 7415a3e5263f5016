// Discovery over SDO against a real stepnode dictionary: identity, name, axes, PSCALE,
// every valid TPDO's mapping; non-stepnode devices; no SDO while stopped; the quiet wait
// for another master; echo of own requests.
#include <gtest/gtest.h>

#include "test_bus.hpp"

namespace stepnode::bridge::test {
namespace {

TEST(Discovery, BootUpStartsReadingIdentityNameAxesAndMapping) {
  TestBus bus;
  FakeNode node({.id = 5, .axes = 3, .pscale = 0.5});
  bus.add(node);
  bus.boot(node);
  ASSERT_FALSE(bus.observer_sent.empty()) << "discovery starts on the boot-up itself";
  EXPECT_EQ(bus.observer_sent.front().id, 0x605u);
  bus.run_ms(50);

  const NodeHealthSample h = bus.observer.node_health(5, bus.now_us);
  EXPECT_TRUE(h.discovered);
  EXPECT_TRUE(h.is_stepnode);
  EXPECT_EQ(h.device_name, "stepnode");
  EXPECT_EQ(h.vendor_id, 0u);
  EXPECT_EQ(h.product_code, 0x53544550u);
  EXPECT_EQ(h.revision, 0x00010000u);
  EXPECT_EQ(h.serial, 4242u);
  EXPECT_EQ(h.axes, 3);
  EXPECT_EQ(h.sdo_failures, 0u);
  EXPECT_EQ(h.state, NodeState::BootUp);  // the first heartbeat is 100 ms after boot-up
  ASSERT_NE(bus.sink.last_health(5), nullptr);
  EXPECT_TRUE(bus.sink.last_health(5)->discovered) << "discovery's end is published at once";

  // Every TPDO of 3 axes (12) is probed, plus the "no object" at 0x180C.
  std::vector<uint16_t> comm_reads;
  for (const od::CanFrame& f : bus.observer_sent)
    if (f.data[0] == 0x40 && od::get_u16(&f.data[1]) >= 0x1800 && od::get_u16(&f.data[1]) < 0x1A00)
      comm_reads.push_back(od::get_u16(&f.data[1]));
  ASSERT_EQ(comm_reads.size(), 13u);
  EXPECT_EQ(comm_reads.back(), 0x180C);
}

TEST(Discovery, TheMappingReadIsTheOneUsedForDecoding) {
  TestBus bus;
  FakeNode node({.id = 5, .axes = 2, .pscale = 0.25});
  bus.add(node);
  bus.boot(node);
  bus.run_ms(50);
  bus.sink.clear();  // (discovery's own snapshot of the axes)
  node.set_position(0, 1000, 998);
  bus.send(node.tpdo(1));  // TPDO2: motor and encoder position of axis 1
  ASSERT_EQ(bus.sink.positions.size(), 1u);
  const AxisPositionSample& p = bus.sink.positions[0];
  EXPECT_EQ(p.node, 5);
  EXPECT_EQ(p.axis, 1);
  EXPECT_EQ(p.motor_position, 1000);
  EXPECT_EQ(p.encoder_position, 998);
  EXPECT_DOUBLE_EQ(p.motor_user_units, 250.0) << "PSCALE 0x2011 read and applied";
  EXPECT_DOUBLE_EQ(p.encoder_user_units, 249.5);
}

TEST(Discovery, PscaleAbsentMeansOne) {
  TestBus bus;
  FakeNode node({.id = 7, .axes = 1});
  bus.add(node);
  bus.boot(node);
  bus.run_ms(50);
  bus.sink.clear();
  node.set_position(0, -321, 5);
  bus.send(node.tpdo(1));
  ASSERT_EQ(bus.sink.positions.size(), 1u);
  EXPECT_DOUBLE_EQ(bus.sink.positions[0].motor_user_units, -321.0);
}

TEST(Discovery, AHeartbeatAloneMakesANodeKnown) {
  TestBus bus;
  FakeNode node({.id = 9, .axes = 1});
  bus.add(node);
  bus.send(node.heartbeat(0x05));
  bus.run_ms(50);
  const NodeHealthSample h = bus.observer.node_health(9, bus.now_us);
  EXPECT_TRUE(h.discovered);
  EXPECT_EQ(h.axes, 1);
  EXPECT_EQ(h.state, NodeState::Operational);
}

TEST(Discovery, ThirdPartyDeviceIsListedWithoutAxes) {
  TestBus bus;
  FakeNode io({.id = 0x20, .stepnode = false, .name = "io-module"});
  bus.add(io);
  bus.boot(io);
  bus.run_ms(150);
  const NodeHealthSample h = bus.observer.node_health(0x20, bus.now_us);
  EXPECT_TRUE(h.discovered);
  EXPECT_FALSE(h.is_stepnode);
  EXPECT_EQ(h.axes, 0);
  EXPECT_EQ(h.device_name, "io-module");
  EXPECT_EQ(h.vendor_id, 0xABu);
  EXPECT_EQ(h.product_code, 0x1234u);
  // Its 0x2001 is not an axis block: never probed, no TPDO parameters read.
  for (const od::CanFrame& f : bus.observer_sent) {
    const uint16_t index = od::get_u16(&f.data[1]);
    EXPECT_TRUE(index < 0x1800 || index > 0x1BFF) << std::hex << index;
    EXPECT_NE(index, 0x2001);
  }
  // Heartbeat and EMCY still reported.
  bus.send(io.emcy(0x3110, 0x04, {}));
  ASSERT_EQ(bus.sink.emergencies.size(), 1u);
  EXPECT_EQ(bus.sink.last_health(0x20)->last_emcy_code, 0x3110);
  EXPECT_EQ(bus.sink.last_health(0x20)->state, NodeState::PreOperational);
}

TEST(Discovery, StepProductCodeWithoutAxisBlocksIsNoStepnode) {
  TestBus bus;
  FakeNode odd({.id = 0x21, .stepnode = false, .product_code = 0x53544550, .has_2001 = false});
  bus.add(odd);
  bus.boot(odd);
  bus.run_ms(50);
  const NodeHealthSample h = bus.observer.node_health(0x21, bus.now_us);
  EXPECT_TRUE(h.discovered);
  EXPECT_FALSE(h.is_stepnode);
  EXPECT_EQ(h.axes, 0);
  EXPECT_EQ(h.product_code, 0x53544550u);
}

TEST(Discovery, NoSdoWhileStopped) {
  TestBus bus;
  FakeNode node({.id = 5, .axes = 1});
  bus.add(node).state = 0x04;
  bus.send(node.heartbeat(0x04));
  bus.run_ms(500);
  EXPECT_TRUE(bus.observer_sent.empty());
  EXPECT_FALSE(bus.observer.node_health(5, bus.now_us).discovered);
  EXPECT_EQ(bus.observer.node_health(5, bus.now_us).state, NodeState::Stopped);
  bus.beat_of(node).state = 0x05;  // a master starts it
  bus.run_ms(150);
  EXPECT_TRUE(bus.observer.node_health(5, bus.now_us).discovered);
}

TEST(Discovery, WaitsForAnotherMastersSdoTrafficToEnd) {
  ObserverConfig cfg;
  cfg.sdo_quiet_ms = 300;
  TestBus bus(cfg);
  FakeNode node({.id = 5, .axes = 1});
  bus.add(node);
  bus.master_start(5);
  bus.master_upload(0x1000, 0);    // another master reads the device type ...
  bus.send(node.heartbeat(0x7F));  // ... and then the bridge first hears of the node
  EXPECT_TRUE(bus.observer_sent.empty()) << "the channel was busy a moment ago";
  bus.run_ms(290);
  EXPECT_TRUE(bus.observer_sent.empty());
  bus.run_ms(20);
  EXPECT_FALSE(bus.observer_sent.empty()) << "quiet for 300 ms: the bridge starts";
  bus.run_ms(50);
  EXPECT_TRUE(bus.observer.node_health(5, bus.now_us).discovered);
}

TEST(Discovery, EchoOfOwnRequestsIsNotAnotherMaster) {
  ObserverConfig cfg;
  cfg.own_frames_echoed = true;
  TestBus bus(cfg);
  bus.echo_observer_frames = true;  // a socket that loops sent frames back
  FakeNode node({.id = 5, .axes = 2});
  bus.add(node);
  bus.boot(node);
  bus.run_ms(50);
  const NodeHealthSample h = bus.observer.node_health(5, bus.now_us);
  EXPECT_TRUE(h.discovered) << "own requests taken for another master would stall discovery";
  EXPECT_EQ(h.sdo_failures, 0u);
}

TEST(Discovery, TwoNodesAreDiscoveredIndependently) {
  TestBus bus;
  FakeNode a({.id = 5, .axes = 3}), b({.id = 6, .axes = 3});
  bus.add(a);
  bus.add(b);
  bus.boot(a);
  bus.boot(b);
  bus.run_ms(100);
  EXPECT_TRUE(bus.observer.node_health(5, bus.now_us).discovered);
  EXPECT_TRUE(bus.observer.node_health(6, bus.now_us).discovered);
  bus.sink.clear();
  a.set_status(0, 0x0100);
  b.set_status(0, 0x0180);
  bus.send(a.tpdo(0));
  bus.send(b.tpdo(0));
  ASSERT_EQ(bus.sink.statuses.size(), 2u);
  EXPECT_EQ(bus.sink.statuses[0].node, 5);
  EXPECT_EQ(bus.sink.statuses[0].status_bits, 0x0100);
  EXPECT_EQ(bus.sink.statuses[1].node, 6);
  EXPECT_EQ(bus.sink.statuses[1].status_bits, 0x0180);
}

}  // namespace
}  // namespace stepnode::bridge::test
