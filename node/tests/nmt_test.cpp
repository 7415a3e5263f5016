// NMT slave (CiA 301 7.2.8.2.1, 7.3.2): boot-up, every state transition by each command
// from each state, addressing (own id, broadcast 0, other ids), malformed commands, the
// services each state allows (table 85), and what reset communication / reset node
// restore (7.3.2.2.1).
#include <filesystem>

#include "node/tests/node_harness.hpp"
#include "node/tests/recording_application.hpp"

namespace stepnode::node::test {
namespace {

class NmtTest : public NodeHarness {
 protected:
  static constexpr uint8_t kStart = 0x01, kStop = 0x02, kPreOp = 0x80, kResetNode = 0x81,
                           kResetComm = 0x82;

  void go_to(NmtState s) {
    if (s == NmtState::Operational) nmt(kStart);
    if (s == NmtState::Stopped) nmt(kStop);
    ASSERT_EQ(node->state(), s);
  }
  static NmtState expected_after(uint8_t cs) {
    switch (cs) {
      case kStart: return NmtState::Operational;
      case kStop: return NmtState::Stopped;
      default: return NmtState::PreOperational;  // enter pre-op, and both resets
    }
  }
  std::vector<uint8_t> heartbeat_bytes(size_t from = 0) const {
    std::vector<uint8_t> out;
    for (const auto& f : with_id(kHeartbeatId, from)) {
      EXPECT_EQ(f.dlc, 1);
      out.push_back(f.data[0]);
    }
    return out;
  }
};

const NmtState kStates[] = {NmtState::PreOperational, NmtState::Operational, NmtState::Stopped};
const uint8_t kCommands[] = {0x01, 0x02, 0x80, 0x81, 0x82};

TEST_F(NmtTest, BootUpOnStartThenPreOperational) {
  // CiA 301 7.2.8.3.2.1: boot-up = the error control COB-ID with one byte 0x00; the
  // node then enters pre-operational by itself.
  ASSERT_FALSE(sent.empty());
  EXPECT_EQ(sent.front(), CanFrame(0x705, {0x00}));
  EXPECT_EQ(node->state(), NmtState::PreOperational);
  // The heartbeat confirms pre-operational at once (and only after the boot-up).
  EXPECT_EQ(heartbeat_bytes(), (std::vector<uint8_t>{0x00, 0x7F}));
  // Nothing else: no EMCY, no PDO, no SDO.
  EXPECT_EQ(sent.size(), 2u);
}

TEST_F(NmtTest, FirstStartWithoutStoredFileHasNoErrorAndStartWorks) {
  EXPECT_FALSE(std::filesystem::exists(node->parameter_file()));
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0);
  EXPECT_EQ(sdo_read(0x1001, 0), 0u);
  EXPECT_EQ(sdo_read(0x1003, 0), 0u);  // no error in the history either
  EXPECT_TRUE(emcys().empty());
  clear_sent();
  nmt(kStart);
  EXPECT_EQ(node->state(), NmtState::Operational);
  EXPECT_EQ(heartbeat_bytes(), (std::vector<uint8_t>{0x05}));
  advance_ms(3000);
  EXPECT_TRUE(emcys().empty());
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0);
}

// Every command from every state (CiA 301 figure 48), each new state confirmed at once by
// a heartbeat carrying the new state byte; a command that leaves the state unchanged sends
// nothing; the resets go through initialisation: boot-up, then pre-operational.
TEST_F(NmtTest, EveryCommandFromEveryState) {
  for (NmtState from : kStates) {
    for (uint8_t cs : kCommands) {
      SCOPED_TRACE(testing::Message()
                   << "from " << state_name(from) << ", command 0x" << std::hex << int(cs));
      make();
      go_to(from);
      advance_ms(10);
      RecordingApplication app;
      node->set_application(&app);
      std::vector<NmtState>& hooked = app.states;
      clear_sent();
      nmt(cs);
      NmtState expect = expected_after(cs);
      EXPECT_EQ(node->state(), expect);
      std::vector<uint8_t> hb = heartbeat_bytes();
      if (cs == kResetNode || cs == kResetComm) {
        EXPECT_EQ(hb, (std::vector<uint8_t>{0x00, 0x7F}));
        ASSERT_FALSE(sent.empty());
        EXPECT_EQ(sent.front(), CanFrame(0x705, {0x00}));  // boot-up comes first
        EXPECT_EQ(hooked, (std::vector<NmtState>{NmtState::PreOperational}));
      } else if (expect != from) {
        EXPECT_EQ(hb, (std::vector<uint8_t>{static_cast<uint8_t>(expect)}));
        EXPECT_EQ(hooked, (std::vector<NmtState>{expect}));
      } else {
        EXPECT_TRUE(hb.empty());
        EXPECT_TRUE(hooked.empty());
      }
      node->set_application(nullptr);
    }
  }
}

TEST_F(NmtTest, BroadcastNodeZeroAppliesEveryCommand) {
  for (NmtState from : kStates) {
    for (uint8_t cs : kCommands) {
      SCOPED_TRACE(testing::Message()
                   << "from " << state_name(from) << ", broadcast 0x" << std::hex << int(cs));
      make();
      go_to(from);
      clear_sent();
      nmt(cs, 0);
      EXPECT_EQ(node->state(), expected_after(cs));
      if (cs == kResetNode || cs == kResetComm) {
        EXPECT_EQ(heartbeat_bytes(), (std::vector<uint8_t>{0x00, 0x7F}));
      }
    }
  }
}

TEST_F(NmtTest, CommandsForOtherNodesAreIgnored) {
  for (NmtState from : kStates) {
    for (uint8_t cs : kCommands) {
      for (uint8_t other :
           {uint8_t{1}, uint8_t{4}, uint8_t{6}, uint8_t{127}, uint8_t{128}, uint8_t{255}}) {
        SCOPED_TRACE(testing::Message() << "from " << state_name(from) << ", command 0x" << std::hex
                                        << int(cs) << " for node " << std::dec << int(other));
        make();
        ASSERT_EQ(sdo_write(0x2F00, 1, 0x1234), 0u);
        go_to(from);
        clear_sent();
        nmt(cs, other);
        EXPECT_EQ(node->state(), from);
        EXPECT_TRUE(sent.empty());
        EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 0x1234u);  // no reset happened
      }
    }
  }
}

TEST_F(NmtTest, MalformedCommandsAreIgnored) {
  for (NmtState from : kStates) {
    SCOPED_TRACE(state_name(from));
    make();
    go_to(from);
    clear_sent();
    // CiA 301 7.2.8.3.1: an NMT command is COB-ID 0 with exactly 2 bytes (cs, node id).
    frame(CanFrame(0, {}));
    frame(CanFrame(0, {kResetNode}));
    frame(CanFrame(0, {kStart}));
    frame(CanFrame(0, {kStop}));
    frame(CanFrame(0, {kResetComm, kId, 0}));
    frame(CanFrame(0, {kStart, kId, 0, 0, 0, 0, 0, 0}));
    frame(CanFrame(0, {kStop, 0, 0}));
    // Unknown command specifiers.
    for (uint8_t cs : {0x00, 0x03, 0x04, 0x05, 0x7F, 0x83, 0xFF}) frame(CanFrame(0, {cs, kId}));
    // A remote frame is not a command.
    CanFrame rtr(0, {kStop, kId});
    rtr.rtr = true;
    frame(rtr);
    EXPECT_EQ(node->state(), from);
    EXPECT_TRUE(sent.empty());
  }
}

TEST_F(NmtTest, StoppedAnswersOnlyNmtAndErrorControl) {
  map_rpdo(0, {0x2F000120}, 255);
  map_tpdo(0, {0x2F000220}, 1);    // on SYNC
  map_tpdo(1, {0x2F000320}, 254);  // on change
  nmt(kStop);
  clear_sent();
  // SDO: no answer at all, in either direction (CiA 301 table 85).
  EXPECT_EQ(sdo_write(0x2F00, 4, 7), kNoAnswer);
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 4), 0u);
  uint32_t abort = 0;
  EXPECT_FALSE(sdo_read(0x1017, 0, &abort));
  EXPECT_EQ(abort, kNoAnswer);
  // PDOs: a SYNC sends nothing, a change sends nothing, an RPDO is not applied.
  sync();
  od().put<uint32_t>(0x2F00, 3, 99);
  frame(CanFrame(0x205, {1, 2, 3, 4}));
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 0u);
  // EMCY is not sent in stopped either.
  node->emcy().report(0x5000, 0x01, {}, t);
  advance_ms(2500);
  // Only heartbeats, with the stopped state byte, at the period.
  for (const auto& f : sent) EXPECT_EQ(f.id, kHeartbeatId) << std::hex << f.id;
  EXPECT_EQ(heartbeat_bytes(), (std::vector<uint8_t>{0x04, 0x04}));
}

TEST_F(NmtTest, PreOperationalAnswersSdoButHasNoPdos) {
  map_rpdo(0, {0x2F000120}, 255);
  map_tpdo(0, {0x2F000220}, 1);
  map_tpdo(1, {0x2F000320}, 254, 0, 100);  // on change and every 100 ms
  nmt(kStart);
  nmt(kPreOp);
  clear_sent();
  sync();
  od().put<uint32_t>(0x2F00, 3, 99);
  frame(CanFrame(0x205, {1, 2, 3, 4}));
  advance_ms(500);
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 0u);
  for (const auto& f : sent) EXPECT_EQ(f.id, kHeartbeatId) << std::hex << f.id;
  EXPECT_EQ(sdo_write(0x2F00, 4, 7), 0u);
  EXPECT_EQ(sdo_read(0x2F00, 4), 7u);
  // Back in operational the same PDOs work.
  nmt(kStart);
  frame(CanFrame(0x205, {1, 2, 3, 4}));
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 0x04030201u);
}

TEST_F(NmtTest, ResetCommunicationRestoresCommunicationAreaOnly) {
  for (NmtState from : kStates) {
    SCOPED_TRACE(state_name(from));
    make();
    ASSERT_EQ(sdo_write(0x1017, 0, 250, 2), 0u);
    ASSERT_EQ(sdo_write(0x1015, 0, 7, 2), 0u);
    map_tpdo(0, {0x2F000120}, 3);
    ASSERT_EQ(sdo_write(0x2F00, 1, 0xCAFE), 0u);
    go_to(from);
    nmt(kResetComm);
    // 0x1000-0x1FFF: power-on values (defaults: nothing was stored).
    EXPECT_EQ(od().get<uint16_t>(0x1017, 0), 1000);
    EXPECT_EQ(od().get<uint16_t>(0x1015, 0), 0);
    EXPECT_EQ(od().get<uint8_t>(0x1800, 2), 254);
    EXPECT_NE(od().get<uint32_t>(0x1A00, 1), 0x2F000120u);
    // Application values are kept.
    EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 0xCAFEu);
    // The restored heartbeat period is the one in force.
    clear_sent();
    advance_ms(1000);
    EXPECT_EQ(heartbeat_bytes(), (std::vector<uint8_t>{0x7F}));
  }
}

TEST_F(NmtTest, ResetCommunicationRestoresStoredCommunicationValues) {
  ASSERT_EQ(sdo_write(0x1017, 0, 250, 2), 0u);
  ASSERT_EQ(sdo_write(0x1010, 2, od::kSaveSignature), 0u);  // communication parameters
  ASSERT_EQ(sdo_write(0x1017, 0, 400, 2), 0u);
  nmt(kResetComm);
  EXPECT_EQ(od().get<uint16_t>(0x1017, 0), 250);
}

TEST_F(NmtTest, ResetNodeRestoresEverythingAndBootsAgain) {
  for (NmtState from : kStates) {
    SCOPED_TRACE(state_name(from));
    make();
    RecordingApplication app;
    node->set_application(&app);
    int& resets = app.resets;
    ASSERT_EQ(sdo_write(0x1017, 0, 250, 2), 0u);
    ASSERT_EQ(sdo_write(0x2F00, 1, 0xCAFE), 0u);
    go_to(from);
    clear_sent();
    nmt(kResetNode);
    EXPECT_EQ(resets, 1);
    EXPECT_EQ(od().get<uint16_t>(0x1017, 0), 1000);
    EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 0u);
    ASSERT_GE(sent.size(), 2u);
    EXPECT_EQ(sent[0], CanFrame(0x705, {0x00}));
    EXPECT_EQ(sent[1], CanFrame(0x705, {0x7F}));
    EXPECT_EQ(node->state(), NmtState::PreOperational);
  }
}

TEST_F(NmtTest, ResetCommunicationDoesNotResetTheApplication) {
  RecordingApplication app;
  node->set_application(&app);
  int& resets = app.resets;
  nmt(kResetComm);
  EXPECT_EQ(resets, 0);
  nmt(kResetNode);
  EXPECT_EQ(resets, 1);
}

TEST_F(NmtTest, ResetAbortsAnSdoTransferInProgress) {
  // A segmented upload of the device name is in progress...
  frame(CanFrame(kSdoRx, {0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0}));
  ASSERT_FALSE(with_id(kSdoTx).empty());
  nmt(kResetComm);
  clear_sent();
  // ...and the reset dropped it: an upload segment request is now out of sequence.
  frame(CanFrame(kSdoRx, {0x60, 0, 0, 0, 0, 0, 0, 0}));
  auto answer = with_id(kSdoTx);
  ASSERT_EQ(answer.size(), 1u);
  EXPECT_EQ(answer[0].data[0], 0x80);
}

}  // namespace
}  // namespace stepnode::node::test
