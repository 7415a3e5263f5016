// Another master's writes that meet a read of the bridge (found in review): the answer
// to a read the write overtook is not taken for another object, a write confirmed after
// that answer is still recognised, and a new heartbeat time leaves the node's identity.
#include <gtest/gtest.h>

#include <functional>

#include "od/sdo_server.hpp"
#include "test_bus.hpp"

namespace stepnode::bridge::test {
namespace {

// With a channel of its own (0x1201), the bridge is reading 0x2005 there while a master
// disables TPDO 2 on the default channel; the node answers the bridge after confirming
// the master (as CANopenNode serves its default server first). That answer is 0x2005's,
// not 0x1800:1's, which the plan reads next after the remap.
TEST(MasterWrites, ARemapWhileAReadIsInFlightOnTheBridgesChannelKeepsTheTpdos) {
  constexpr uint32_t kRx = 0x685, kTx = 0x6C5;
  ObserverConfig cfg;
  cfg.sdo_channels.push_back(NodeSdoChannel{5, kRx, kTx});
  TestBus bus(cfg);
  FakeNode node({.id = 5, .axes = 1});
  od::SdoServer channel(node.dictionary(), kTx);  // the node's 0x1201 server, by hand
  node.set_position(0, 0x1F0, 0);                 // motor position 496 = 0x1F0
  bus.add(node).state = 0x05;
  size_t served = 0;
  std::function<bool(const od::CanFrame&)> hold = [](const od::CanFrame& f) {
    return f.data[0] == 0x40 && od::get_u16(&f.data[1]) == 0x2005;
  };
  const auto serve = [&] {
    while (served < bus.observer_sent.size()) {
      const od::CanFrame req = bus.observer_sent[served];
      if (req.id == kRx && hold(req)) return;
      ++served;
      if (req.id != kRx) continue;
      std::vector<od::CanFrame> out;
      channel.on_request(req, bus.now_us, out);
      for (const od::CanFrame& f : out) bus.send(f);
    }
  };
  bus.boot(node);
  serve();
  ASSERT_LT(served, bus.observer_sent.size());
  ASSERT_EQ(od::get_u16(&bus.observer_sent[served].data[1]), 0x2005);  // in flight
  bus.master_start(5);
  bus.master_download(0x1801, 1, od::encode<uint32_t>(0xC0000285));  // TPDO 2 off
  ASSERT_TRUE(bus.master->done());
  ASSERT_TRUE(bus.master->result().ok());
  hold = [](const od::CanFrame&) { return false; };
  serve();
  bus.run_ms(5);
  serve();
  ASSERT_TRUE(bus.observer.node_health(5, bus.now_us).discovered);
  bus.sink.clear();
  node.set_status(0, 0x0180);
  node.set_position(0, 4321, 0);
  const od::CanFrame tpdo1 = node.tpdo(0);
  ASSERT_EQ(tpdo1.id, 0x185u);
  bus.send(tpdo1);
  ASSERT_EQ(bus.sink.positions.size(), 1u);
  EXPECT_EQ(bus.sink.positions[0].motor_position, 4321);
  bus.sink.clear();
  bus.send(od::CanFrame(0x1F0, {0x80, 0x01, 0x11, 0x22, 0x33, 0x44}));
  EXPECT_TRUE(bus.sink.positions.empty()) << "0x1F0 taken for node 5's TPDO 1";
}

// A master writes 0x1017 = 2000 ms while a read of the bridge waits for its answer on
// the default channel. CiA 301 7.2.4.1: the server answers in order, so the frames are
// request (bridge), request (master), answer (bridge), confirmation (master); the
// confirmation is the master's, whatever answer came before it.
// Node 5 (one axis, a heartbeat every 100 ms) operational and discovered.
void discovered(TestBus& bus, FakeNode& node) {
  bus.add(node, 100).state = 0x05;
  bus.boot(node);
  bus.run_ms(500);
  ASSERT_TRUE(bus.observer.node_health(5, bus.now_us).discovered);
}

void follows_the_new_heartbeat_time(bool write_during_the_read) {
  TestBus bus;
  FakeNode node({.id = 5, .axes = 1});
  discovered(bus, node);
  node.hold = true;  // rebooted, it answers late: the bridge's read stays in flight
  bus.boot(node);
  bus.run_ms(300);  // heartbeats every 100 ms: the interval is measured
  ASSERT_FALSE(node.held.empty());
  const od::CanFrame write_1017(0x605, {0x2B, 0x17, 0x10, 0x00, 0xD0, 0x07, 0x00, 0x00});
  if (write_during_the_read) {
    bus.send(write_1017);
    ASSERT_EQ(node.held.size(), 2u);  // the answer to the bridge, then the confirmation
    bus.release(node);
  } else {
    bus.release(node);
    bus.send(write_1017);
  }
  bus.beat_of(node).period_us = 2'000'000;  // the node now beats every 2 s
  bus.sink.healths.clear();
  bus.run_ms(5000);
  for (const NodeHealthSample& h : bus.sink.healths)
    EXPECT_NE(h.state, NodeState::Lost) << "lost although it beats every 2 s (3 x 2 s)";
  EXPECT_TRUE(bus.sink.disposed.empty());
}

TEST(MasterWrites, ANewHeartbeatTimeWrittenDuringTheBridgesReadIsFollowed) {
  follows_the_new_heartbeat_time(true);
}

TEST(MasterWrites, ANewHeartbeatTimeWrittenAfterTheBridgesReadIsFollowed) {
  follows_the_new_heartbeat_time(false);
}

// Only 0x1017 is read again after a master writes it: the node is the same device, so
// NodeHealth keeps its identity and axes, and its EMCY keep their stepnode texts.
TEST(MasterWrites, ANewHeartbeatTimeKeepsTheNodesIdentity) {
  TestBus bus;
  FakeNode node({.id = 5, .axes = 1});
  discovered(bus, node);
  ASSERT_TRUE(bus.observer.node_health(5, bus.now_us).is_stepnode);
  const size_t requests = bus.observer_sent.size();
  bus.master_start(5);
  bus.master_download(0x1017, 0, od::encode<uint16_t>(200));
  ASSERT_TRUE(bus.master->result().ok());
  bus.run_ms(50);
  bus.sink.clear();
  bus.send(node.emcy(0xFF01, 0x81, {0x10, 0x10, 0, 0, 0}));  // axis 1: motor stalled
  ASSERT_EQ(bus.sink.emergencies.size(), 1u);
  EXPECT_EQ(bus.sink.emergencies[0].text.rfind("axis 1 error: motor stalled", 0), 0u)
      << bus.sink.emergencies[0].text;
  const NodeHealthSample* h = bus.sink.last_health(5);
  ASSERT_NE(h, nullptr);
  EXPECT_TRUE(h->is_stepnode);
  EXPECT_TRUE(h->discovered);
  EXPECT_EQ(h->axes, 1);
  EXPECT_EQ(h->device_name, "stepnode");
  EXPECT_EQ(h->serial, 4242u);
  bus.run_ms(1000);
  // One read: 0x1017 (after the quiet time), nothing else.
  ASSERT_EQ(bus.observer_sent.size(), requests + 1);
  EXPECT_EQ(od::get_u16(&bus.observer_sent.back().data[1]), 0x1017);
}

}  // namespace
}  // namespace stepnode::bridge::test
