// Another device with this node's node-ID (README, "Duplicate node-ID"): a frame on a
// COB-ID only this node produces (0x700+id boot-up or heartbeat, 0x580+id SDO answer, the
// EMCY COB-ID). Within 2 s of its boot-up the node yields the node-ID and waits for LSS;
// later it keeps it and reports. EMCY frames written from CiA 301 7.2.7.3.1: code 0x8100
// (communication, generic) little-endian, the error register, five manufacturer bytes
// (here the COB-ID heard, little-endian, and 1 when the node yielded).
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

class NodeIdConflictTest : public NodeHarness {
 protected:
  static CanFrame lss(std::initializer_list<uint8_t> bytes) {
    CanFrame f(0x7E5, {0, 0, 0, 0, 0, 0, 0, 0});
    size_t i = 0;
    for (uint8_t b : bytes) f.data[i++] = b;
    return f;
  }
};

TEST_F(NodeIdConflictTest, AHeartbeatWithItsIdAfterTheClaimPeriodIsReportedAndTheNodeKeepsIt) {
  advance_ms(3000);
  size_t from = sent.size();
  frame(CanFrame(kHeartbeatId, {0x05}));
  // 0x8100, register 0x11 (generic, communication), 0x0705, kept.
  EXPECT_EQ(
      emcys(from),
      (std::vector<CanFrame>{CanFrame(kEmcyId, {0x00, 0x81, 0x11, 0x05, 0x07, 0x00, 0x00, 0x00})}));
  EXPECT_EQ(*sdo_read(0x1001, 0), 0x11u);
  EXPECT_EQ(*sdo_read(0x1003, 1), 0x07058100u);  // the code and the first two manufacturer bytes
  EXPECT_TRUE(node->configured());
  EXPECT_EQ(node->state(), NmtState::PreOperational);
  frame(CanFrame(kHeartbeatId, {0x05}));
  EXPECT_EQ(emcys(from).size(), 1u);  // active: reported once
  nmt(0x01);
  EXPECT_EQ(node->state(), NmtState::Operational);  // the node goes on serving
}

TEST_F(NodeIdConflictTest, ABootUpWithItsIdIsAnsweredWithTheHeartbeatAtOnce) {
  advance_ms(3000);
  size_t from = sent.size();
  frame(CanFrame(kHeartbeatId, {0x00}));  // a newcomer's boot-up
  EXPECT_EQ(with_id(kHeartbeatId, from), (std::vector<CanFrame>{CanFrame(kHeartbeatId, {0x7F})}));
  EXPECT_EQ(emcys(from).size(), 1u);
}

TEST_F(NodeIdConflictTest, WithinTheClaimPeriodTheNodeYieldsAndWaitsForLss) {
  advance_ms(500);
  size_t from = sent.size();
  frame(CanFrame(kHeartbeatId, {0x05}));  // a device that was there first
  EXPECT_EQ(
      emcys(from),
      (std::vector<CanFrame>{CanFrame(kEmcyId, {0x00, 0x81, 0x11, 0x05, 0x07, 0x01, 0x00, 0x00})}));
  EXPECT_FALSE(node->configured());
  from = sent.size();
  advance_ms(3000);
  frame(CanFrame(kSdoRx, {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0}));
  EXPECT_TRUE(std::vector<CanFrame>(sent.begin() + static_cast<long>(from), sent.end()).empty())
      << "no heartbeat, SDO answer or EMCY with a node-ID another device has";
  // An LSS master gives it another node-ID; it boots with it (CiA 305).
  frame(lss({0x4C}));  // identify non-configured remote slave
  EXPECT_EQ(sent.back(), CanFrame(0x7E4, {0x50, 0, 0, 0, 0, 0, 0, 0}));
  frame(lss({0x04, 0x01}));
  frame(lss({0x11, 6}));
  frame(lss({0x04, 0x00}));
  EXPECT_TRUE(node->configured());
  EXPECT_EQ(node->node_id(), 6);
  EXPECT_EQ(with_id(0x706, from).front(), CanFrame(0x706, {0x00}));
}

TEST_F(NodeIdConflictTest, SdoAnswersAndEmcysOfAnotherDeviceCountRemoteFramesDoNot) {
  advance_ms(3000);
  CanFrame guard(kHeartbeatId, {});
  guard.rtr = true;
  size_t from = sent.size();
  frame(guard);                                                   // a node guarding request
  frame(CanFrame(kSdoRx, {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0}));  // a request to us
  EXPECT_TRUE(emcys(from).empty());
  frame(CanFrame(kSdoTx,
                 {0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x04, 0x00}));  // somebody's answer as us
  ASSERT_EQ(emcys(from).size(), 1u);
  EXPECT_EQ(emcys(from)[0].data[3], 0x85);
  EXPECT_EQ(emcys(from)[0].data[4], 0x05);

  nmt(0x82);  // reset communication forgets the error
  advance_ms(3000);
  from = sent.size();
  frame(CanFrame(kEmcyId, {0x00, 0x10, 0x01, 0, 0, 0, 0, 0}));  // somebody's EMCY as us
  ASSERT_EQ(emcys(from).size(), 1u);
  EXPECT_EQ(emcys(from)[0].data[3], 0x85);
  EXPECT_EQ(emcys(from)[0].data[4], 0x00);
}

// With boot_listen_us the node listens before its boot-up (README, "Duplicate node-ID").
class BootListenTest : public NodeIdConflictTest {
 protected:
  void SetUp() override {
    NodeOptions o;
    o.device.node_id = kId;
    o.layout.axes = 1;
    o.state_dir = dir.path;
    o.boot_listen_us = 500'000;
    started = t;
    make(o);
  }
  uint64_t started = 0;
};

TEST_F(BootListenTest, NobodyHeardTheBootUpComesAtTheListeningsEnd) {
  advance_ms(499);
  EXPECT_TRUE(sent.empty()) << "nothing before the boot-up (CiA 301: initialisation)";
  EXPECT_EQ(node->state(), NmtState::Initialising);
  advance_ms(1);
  // The boot-up message: 0x700+id, one byte 0 (CiA 301 7.2.8.3.2.1), at 500 ms.
  ASSERT_FALSE(sent.empty());
  EXPECT_EQ(sent.front(), CanFrame(kHeartbeatId, {0x00}));
  EXPECT_EQ(sent_at.front(), started + 500'000);
  EXPECT_EQ(node->state(), NmtState::PreOperational);
  // The claim period starts at the boot-up: a device heard now makes the node yield.
  advance_ms(1000);
  frame(CanFrame(kHeartbeatId, {0x05}));
  EXPECT_FALSE(node->configured());
}

TEST_F(BootListenTest, AHeartbeatHeardWhileListeningMeansNoFrameWithTheNodeIdEver) {
  advance_ms(200);
  frame(CanFrame(kHeartbeatId, {0x05}));  // the device that has node-ID 5
  advance_ms(3000);
  frame(CanFrame(kSdoRx, {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0}));
  nmt(0x01);
  EXPECT_TRUE(sent.empty()) << "no boot-up, EMCY, heartbeat or SDO answer";
  EXPECT_FALSE(node->configured());
  // It waits for an LSS master like a node without a node-ID (CiA 305 identify
  // non-configured remote slave: 0x4C, answered with 0x50 on 0x7E4).
  frame(lss({0x4C}));
  EXPECT_EQ(sent, (std::vector<CanFrame>{CanFrame(0x7E4, {0x50, 0, 0, 0, 0, 0, 0, 0})}));
}

TEST_F(BootListenTest, AnSdoAnswerOrEmcyAsThisNodeIsARefusalARemoteFrameIsNot) {
  CanFrame guard(kHeartbeatId, {});
  guard.rtr = true;
  frame(guard);  // a master guarding node 5: says nothing of who has the id
  advance_ms(100);
  EXPECT_TRUE(node->configured());
  frame(CanFrame(kEmcyId, {0x00, 0x10, 0x01, 0, 0, 0, 0, 0}));  // node 5's EMCY
  EXPECT_FALSE(node->configured());
  advance_ms(1000);
  EXPECT_TRUE(sent.empty());

  make(NodeOptions{[&] {
    NodeOptions o;
    o.device.node_id = kId;
    o.state_dir = dir.path;
    o.boot_listen_us = 500'000;
    return o;
  }()});
  frame(CanFrame(kSdoTx, {0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x04, 0x00}));  // node 5's answer
  advance_ms(1000);
  EXPECT_FALSE(node->configured());
  EXPECT_TRUE(sent.empty());
}

TEST_F(BootListenTest, NmtAndSdoWhileListeningFindTheNodeNotBootedYet) {
  advance_ms(100);
  nmt(0x01);  // start remote node: the node is still in initialisation
  frame(CanFrame(kSdoRx, {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0}));
  EXPECT_TRUE(sent.empty());
  advance_ms(400);
  EXPECT_EQ(sent.front(), CanFrame(kHeartbeatId, {0x00}));
  EXPECT_EQ(node->state(), NmtState::PreOperational) << "the start was not remembered";
  // An LSS master can still give it another node-ID while it listens (CiA 305 works in
  // every state); covered by the LSS tests.
}

}  // namespace
}  // namespace stepnode::node::test
