// The LSS slave inside the node (CiA 305 with CiA 301): a node started without a node-ID
// is silent (no boot-up, no heartbeat, no SDO) until a master configures one and switches
// it to waiting; then it boots with it. Store configuration survives a restart, with the
// precedence command line > LSS-stored > configuration file; a configured node takes a new
// node-ID at its next reset communication, COB-IDs and all; back-to-back requests are each
// answered at once.
#include <filesystem>

#include "node/profiles/horner/bits.hpp"
#include "node/profiles/horner/objects.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

constexpr uint32_t kLssTx = 0x7E4;

CanFrame lss(std::initializer_list<uint8_t> bytes) {
  CanFrame f(0x7E5, {0, 0, 0, 0, 0, 0, 0, 0});
  size_t i = 0;
  for (uint8_t b : bytes) f.data[i++] = b;
  return f;
}
CanFrame lss_answer(std::initializer_list<uint8_t> bytes) {
  CanFrame f = lss(bytes);
  f.id = kLssTx;
  return f;
}

class LssNodeTest : public NodeHarness {
 protected:
  static constexpr uint32_t kSerial = 0x0000B001;
  void SetUp() override { make_node(lss::kUnconfigured, NodeIdOrigin::None); }

  void make_node(uint8_t node_id, NodeIdOrigin origin) {
    NodeOptions o;
    o.device.node_id = node_id;
    o.device.serial_number = kSerial;
    o.node_id_origin = origin;
    o.state_dir = dir.path;
    make(o);
  }
};

TEST_F(LssNodeTest, WithoutNodeIdTheNodeIsSilentButForLss) {
  EXPECT_FALSE(node->configured());
  EXPECT_EQ(node->state(), NmtState::Initialising);
  advance_ms(3000);
  frame(CanFrame(0x600 + 0x7F, {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0}));  // SDO to any id
  frame(CanFrame(0, {0x01, 0x00}));                                     // NMT start, broadcast
  EXPECT_TRUE(sent.empty()) << "no boot-up, heartbeat, SDO answer or EMCY without a node-ID";
  EXPECT_EQ(node->state(), NmtState::Initialising);
  frame(lss({0x4C}));  // identify non-configured remote slave
  EXPECT_EQ(sent, std::vector<CanFrame>{lss_answer({0x50})});
}

TEST_F(LssNodeTest, ConfigureNodeIdThenSwitchToWaitingBootsWithIt) {
  frame(lss({0x04, 0x01}));
  frame(lss({0x5E}));
  frame(lss({0x11, kId}));
  EXPECT_EQ(sent, (std::vector<CanFrame>{lss_answer({0x5E, 0xFF}), lss_answer({0x11, 0x00})}));
  EXPECT_EQ(node->state(), NmtState::Initialising);  // pending only, until the switch
  frame(lss({0x04, 0x00}));
  EXPECT_EQ(node->node_id(), kId);
  EXPECT_EQ(node->state(), NmtState::PreOperational);
  ASSERT_GE(sent.size(), 3u);
  EXPECT_EQ(sent[2], CanFrame(0x705, {0x00}));  // boot-up, CiA 301 7.2.8.3.2.1
  // Every COB-ID that follows the node-ID follows the new one; SDO answers on 0x585.
  EXPECT_EQ(sdo_read(0x1014, 0), 0x85u);
  EXPECT_EQ(sdo_read(0x1200, 1), 0x605u);
  EXPECT_EQ(sdo_read(0x1200, 2), 0x585u);
  EXPECT_EQ(sdo_read(0x1800, 1).value_or(0) & 0x7FF, 0x185u);
  EXPECT_EQ(sdo_read(0x1400, 1).value_or(0) & 0x7FF, 0x205u);
  EXPECT_EQ(sdo_read(0x1018, 4), kSerial);
  clear_sent();
  advance_ms(1000);
  EXPECT_EQ(with_id(0x705), std::vector<CanFrame>{CanFrame(0x705, {0x7F})});  // heartbeat
}

TEST_F(LssNodeTest, NmtResetCommunicationAlsoAppliesTheConfiguredNodeId) {
  frame(lss({0x04, 0x01}));
  frame(lss({0x11, 0x21}));
  clear_sent();
  nmt(0x82, 0);  // reset communication, broadcast
  EXPECT_EQ(node->node_id(), 0x21);
  ASSERT_FALSE(sent.empty());
  EXPECT_EQ(sent.front(), CanFrame(0x721, {0x00}));
}

TEST_F(LssNodeTest, NmtResetCommunicationReturnsTheLssSlaveToWaiting) {
  // CiA 305: after initialisation the LSS slave is in waiting. Found in review: it stayed in
  // configuration state and took the node-ID the master meant for the next device.
  frame(lss({0x04, 0x01}));
  frame(lss({0x11, 0x21}));
  nmt(0x82, 0);
  ASSERT_EQ(node->node_id(), 0x21);
  clear_sent();
  frame(lss({0x5E}));        // inquire node-ID: configuration state only
  frame(lss({0x11, 0x22}));  // configure node-ID: configuration state only
  EXPECT_TRUE(with_id(kLssTx).empty());
  EXPECT_EQ(node->lss().state(), lss::State::Waiting);
  EXPECT_EQ(node->lss().pending_node_id(), 0x21);
}

TEST_F(LssNodeTest, StoredNodeIdIsUsedAtTheNextStart) {
  frame(lss({0x04, 0x01}));
  frame(lss({0x11, 0x2A}));
  frame(lss({0x13, 0x00, 0x03}));  // 250 kbit/s
  size_t before = sent.size();
  frame(lss({0x17}));
  EXPECT_EQ(with_id(kLssTx, before), std::vector<CanFrame>{lss_answer({0x17, 0x00})});
  EXPECT_TRUE(std::filesystem::exists(node->lss_file()));
  // Power off before the id was ever used: the stored one is what the next start uses.
  make_node(lss::kUnconfigured, NodeIdOrigin::None);
  EXPECT_EQ(node->node_id(), 0x2A);
  ASSERT_FALSE(sent.empty());
  EXPECT_EQ(sent.front(), CanFrame(0x72A, {0x00}));
  EXPECT_EQ(node->lss().active_bit_timing(), 3);
  // The LSS-stored id wins over the configuration file's...
  make_node(9, NodeIdOrigin::ConfigFile);
  EXPECT_EQ(node->node_id(), 0x2A);
  // ... and the command line's wins over it.
  make_node(9, NodeIdOrigin::CommandLine);
  EXPECT_EQ(node->node_id(), 9);
  EXPECT_EQ(sent.front(), CanFrame(0x709, {0x00}));
}

TEST_F(LssNodeTest, AConfiguredNodeTakesANewNodeIdAtResetCommunication) {
  make_node(kId, NodeIdOrigin::CommandLine);
  // Switch state selective by the identity of 0x1018, as a master that knows it does.
  const auto u32 = [](uint8_t cs, uint32_t v) {
    return lss({cs, static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8),
                static_cast<uint8_t>(v >> 16), static_cast<uint8_t>(v >> 24)});
  };
  const od::DeviceInfo& d = node->device_info();
  clear_sent();
  frame(u32(0x40, d.vendor_id));
  frame(u32(0x41, d.product_code));
  frame(u32(0x42, d.revision));
  frame(u32(0x43, kSerial));
  EXPECT_EQ(sent, std::vector<CanFrame>{lss_answer({0x44})});
  frame(lss({0x11, 0x06}));
  frame(lss({0x04, 0x00}));
  EXPECT_EQ(node->node_id(), kId);  // a configured node keeps its id until reset communication
  EXPECT_EQ(sdo_read(0x1017, 0), 1000u);
  clear_sent();
  nmt(0x82);  // to node 5
  EXPECT_EQ(node->node_id(), 6);
  ASSERT_FALSE(sent.empty());
  EXPECT_EQ(sent.front(), CanFrame(0x706, {0x00}));
  frame(CanFrame(0x606, {0x40, 0x18, 0x10, 0x04, 0, 0, 0, 0}));
  EXPECT_EQ(with_id(0x586).size(), 1u);
  EXPECT_TRUE(with_id(0x585).empty());
  // Selected before the reset, waiting after it: a second configure is not this node's.
  EXPECT_EQ(node->lss().state(), lss::State::Waiting);
  clear_sent();
  frame(lss({0x11, 0x07}));
  EXPECT_TRUE(with_id(kLssTx).empty());
  EXPECT_EQ(node->lss().pending_node_id(), 6);
}

TEST_F(LssNodeTest, ARunningNodeConfiguredToNoNodeIdFallsSilentAndItsAxesRampDown) {
  make_node(kId, NodeIdOrigin::CommandLine);
  namespace axis_obj = horner::obj;
  const uint16_t commands = axis_obj::index(0, axis_obj::kCommandBits);
  const uint16_t status = axis_obj::index(0, axis_obj::kStatusBits);
  ASSERT_EQ(sdo_write(commands, 0, horner::command::kClearErrors, 2), 0u);
  ASSERT_EQ(sdo_write(commands, 0, 0, 2), 0u);
  nmt(0x01);
  ASSERT_EQ(sdo_write(commands, 0, horner::command::kJogUp, 2), 0u);
  advance_ms(500);
  ASSERT_EQ(od().get<uint16_t>(status, 0) & horner::status::kDecelerating, 0);
  frame(lss({0x04, 0x01}));
  frame(lss({0x11, 0xFF}));
  frame(lss({0x04, 0x00}));
  EXPECT_TRUE(node->configured()) << "until reset communication";
  nmt(0x82);
  EXPECT_FALSE(node->configured());
  EXPECT_EQ(node->state(), NmtState::Initialising);
  EXPECT_NE(od().get<uint16_t>(status, 0) & horner::status::kDecelerating, 0);
  EXPECT_NE(od().get<uint16_t>(status, 0) & horner::status::kPowerUp, 0) << "%I8 latches";
  clear_sent();
  advance_ms(2000);
  EXPECT_TRUE(with_id(kHeartbeatId).empty());
  frame(lss({0x4C}));
  EXPECT_EQ(with_id(kLssTx), std::vector<CanFrame>{lss_answer({0x50})});
}

TEST_F(LssNodeTest, BackToBackRequestsAreEachAnswered) {
  make_node(kId, NodeIdOrigin::CommandLine);
  frame(lss({0x04, 0x01}));
  clear_sent();
  // Seven requests in the same microsecond, no tick between them.
  for (uint8_t cs : {0x5A, 0x5B, 0x5C, 0x5D, 0x5E, 0x11, 0x5E}) frame(lss({cs, 0x07}));
  const od::DeviceInfo& d = node->device_info();
  auto u32 = [](uint8_t cs, uint32_t v) {
    return lss_answer({cs, static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8),
                       static_cast<uint8_t>(v >> 16), static_cast<uint8_t>(v >> 24)});
  };
  EXPECT_EQ(with_id(kLssTx), (std::vector<CanFrame>{
                                 u32(0x5A, d.vendor_id), u32(0x5B, d.product_code),
                                 u32(0x5C, d.revision), u32(0x5D, kSerial), lss_answer({0x5E, kId}),
                                 lss_answer({0x11, 0x00}), lss_answer({0x5E, kId})}));
}

TEST_F(LssNodeTest, LssWorksInNmtStopped) {
  make_node(kId, NodeIdOrigin::CommandLine);
  nmt(0x02);
  ASSERT_EQ(node->state(), NmtState::Stopped);
  frame(lss({0x04, 0x01}));
  clear_sent();
  frame(lss({0x5E}));
  EXPECT_EQ(sent, std::vector<CanFrame>{lss_answer({0x5E, kId})});
}

}  // namespace
}  // namespace stepnode::node::test
