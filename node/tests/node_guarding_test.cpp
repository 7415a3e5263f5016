// Node guarding and life guarding (CiA 301 7.2.8.3.1, objects 0x100C/0x100D), the frames
// as CiA 301 gives them: the master's remote frame on 0x700 + node-ID, the node's one-byte
// answer on the same COB-ID, bit 7 a toggle (0 first, alternating, back to 0 only at reset
// communication), bits 0..6 the NMT state (0x04 stopped, 0x05 operational, 0x7F
// pre-operational). Life guarding's loss is a communication error: EMCY 0x8130, 0x1029's
// change of state, and the device's policy for a lost master.
#include <gtest/gtest.h>

#include "node/profiles/horner/bits.hpp"
#include "node/profiles/horner/objects.hpp"
#include "node/tests/node_harness.hpp"
#include "node/tests/recording_application.hpp"

namespace stepnode::node::test {
namespace {

class NodeGuardingTest : public NodeHarness {
 protected:
  // Heartbeat off (0x1017 = 0): a device runs one error control protocol, and with a
  // producer time the heartbeat is the one.
  void SetUp() override { make(1, {{"1017", "0"}}); }

  // One guarding request; the answer's byte, or -1 for none.
  int guard() {
    size_t before = sent.size();
    CanFrame rtr(kHeartbeatId, {});
    rtr.rtr = true;
    rtr.dlc = 1;  // masters send the length of the answer; any length is a request
    frame(rtr);
    auto answers = with_id(kHeartbeatId, before);
    if (answers.empty()) return -1;
    EXPECT_EQ(answers.size(), 1u);
    EXPECT_EQ(answers[0].dlc, 1);
    EXPECT_FALSE(answers[0].rtr);
    return answers[0].data[0];
  }
  RecordingApplication app;  // for the tests of the slave's own rules (set_application)
};

TEST_F(NodeGuardingTest, AnswersStateWithAToggleThatStartsAtZero) {
  EXPECT_EQ(guard(), 0x7F);  // pre-operational, toggle 0
  EXPECT_EQ(guard(), 0xFF);  // toggle 1
  EXPECT_EQ(guard(), 0x7F);
  nmt(0x01);
  EXPECT_EQ(guard(), 0x85);  // operational, toggle 1
  EXPECT_EQ(guard(), 0x05);
  nmt(0x02);
  EXPECT_EQ(guard(), 0x84);  // stopped: error control still runs
  nmt(0x80);
  EXPECT_EQ(guard(), 0x7F);  // enter pre-operational does not reset the toggle
  nmt(0x82);                 // reset communication does
  EXPECT_EQ(guard(), 0x7F);
  EXPECT_EQ(guard(), 0xFF);
}

TEST_F(NodeGuardingTest, OtherNodesRequestsAndDataFramesAreNotAnswered) {
  clear_sent();
  CanFrame other(0x700 + kId + 1, {});
  other.rtr = true;
  frame(other);
  // A data frame is somebody's heartbeat: another device with this node-ID, reported (EMCY
  // 0x8100, node_id_conflict_test.cpp), never answered as a guarding request.
  advance_ms(2500);
  frame(CanFrame(kHeartbeatId, {0x7F}));
  EXPECT_TRUE(with_id(kHeartbeatId).empty());
  EXPECT_TRUE(with_id(0x700 + kId + 1).empty());
}

TEST_F(NodeGuardingTest, NotAnsweredWhileHeartbeatIsProduced) {
  ASSERT_EQ(sdo_write(0x1017, 0, 100, 2), 0u);
  EXPECT_EQ(guard(), -1);
  ASSERT_EQ(sdo_write(0x1017, 0, 0, 2), 0u);
  EXPECT_EQ(guard(), 0x7F);
}

TEST_F(NodeGuardingTest, ObjectsAreReadWriteDefaultZeroAndStored) {
  EXPECT_EQ(sdo_read(0x100C, 0), 0u);
  EXPECT_EQ(sdo_read(0x100D, 0), 0u);
  ASSERT_EQ(sdo_write(0x100C, 0, 250, 2), 0u);
  ASSERT_EQ(sdo_write(0x100D, 0, 3, 1), 0u);
  ASSERT_EQ(sdo_write(0x1010, 2, 0x65766173), 0u);  // store the communication parameters
  make(1, {{"1017", "0"}});
  EXPECT_EQ(sdo_read(0x100C, 0), 250u);
  EXPECT_EQ(sdo_read(0x100D, 0), 3u);
}

TEST_F(NodeGuardingTest, LifeGuardingLossIsACommunicationErrorAndTheNextRequestEndsIt) {
  ASSERT_EQ(sdo_write(0x100C, 0, 100, 2), 0u);  // guard time 100 ms
  ASSERT_EQ(sdo_write(0x100D, 0, 3, 1), 0u);    // x 3: node life time 300 ms
  nmt(0x01);
  // Life guarding starts with the first request, not before.
  advance_ms(1000);
  EXPECT_TRUE(emcys().empty());
  node->set_application(&app);
  EXPECT_EQ(guard(), 0x05);
  for (int i = 0; i < 5; ++i) {
    advance_ms(290);
    EXPECT_EQ(guard() & 0x7F, 0x05);
  }
  EXPECT_TRUE(emcys().empty());
  size_t before = sent.size();
  advance_ms(300);
  EXPECT_TRUE(emcys(before).empty()) << "within the node life time";
  advance_ms(2);
  auto e = emcys(before);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(emcy_code(e[0]), 0x8130);    // life guard error or heartbeat error
  EXPECT_EQ(e[0].data[2] & 0x10, 0x10);  // error register: communication
  EXPECT_EQ(app.guarding_lost, 1);
  EXPECT_EQ(node->state(), NmtState::PreOperational);  // 0x1029 sub 1 = 0
  advance_ms(1000);
  EXPECT_EQ(app.guarding_lost, 1) << "one event per loss";
  before = sent.size();
  EXPECT_EQ(guard() & 0x7F, 0x7F);
  e = emcys(before);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(emcy_code(e[0]), 0x0000);  // error reset
  EXPECT_EQ(app.guarding_recovered, 1);
}

TEST_F(NodeGuardingTest, LifeGuardingLostRampsTheAxesDownAsALostMasterDoes) {
  // The device's policy (Device::communication_error): the guarding master is the master.
  namespace axis_obj = horner::obj;
  const uint16_t commands = axis_obj::index(0, axis_obj::kCommandBits);
  const uint16_t status = axis_obj::index(0, axis_obj::kStatusBits);
  ASSERT_EQ(sdo_write(commands, 0, horner::command::kClearErrors, 2), 0u);
  ASSERT_EQ(sdo_write(commands, 0, 0, 2), 0u);
  ASSERT_EQ(sdo_write(0x100C, 0, 50, 2), 0u);
  ASSERT_EQ(sdo_write(0x100D, 0, 4, 1), 0u);  // 200 ms
  ASSERT_EQ(sdo_write(0x1029, 1, 1, 1), 0u);  // no change of NMT state: only the policy acts
  nmt(0x01);
  ASSERT_EQ(sdo_write(commands, 0, horner::command::kJogUp, 2), 0u);
  for (int i = 0; i < 10; ++i) {
    advance_ms(100);
    ASSERT_EQ(guard(), i % 2 ? 0x85 : 0x05);  // toggle 0 first, then alternating
  }
  ASSERT_EQ(od().get<uint16_t>(status, 0) & horner::status::kDecelerating, 0);
  size_t before = sent.size();
  advance_ms(201);
  EXPECT_EQ(node->state(), NmtState::Operational);
  ASSERT_FALSE(emcys(before).empty());
  EXPECT_EQ(emcy_code(emcys(before)[0]), 0x8130);  // then the axis's own (master lost)
  EXPECT_NE(od().get<uint16_t>(status, 0) & horner::status::kDecelerating, 0);
  EXPECT_NE(od().get<uint16_t>(status, 0) & horner::status::kPowerUp, 0) << "%I8 latches";
}

TEST_F(NodeGuardingTest, SwitchingGuardingOffEndsALoss) {
  node->set_application(&app);  // the slave's rule alone
  ASSERT_EQ(sdo_write(0x100C, 0, 50, 2), 0u);
  ASSERT_EQ(sdo_write(0x100D, 0, 2, 1), 0u);
  EXPECT_EQ(guard(), 0x7F);
  advance_ms(150);
  ASSERT_EQ(emcys().size(), 1u);
  EXPECT_EQ(app.guarding_lost, 1);
  ASSERT_EQ(sdo_write(0x100D, 0, 0, 1), 0u);
  advance_ms(2);
  ASSERT_EQ(emcys().size(), 2u);
  EXPECT_EQ(emcy_code(emcys()[1]), 0x0000);
  EXPECT_EQ(app.guarding_recovered, 1);
}

}  // namespace
}  // namespace stepnode::node::test
