// The SDO server channels 0x1200..0x1203 (CiA 301 7.2.4.1, 7.5.2.33) on a whole node: the
// parameter records, a disabled channel, COB-ID rules, two transfers at once on two
// channels, store/restore. Request and response frames are written from CiA 301 7.2.4.3.
#include <string>

#include "node/tests/node_harness.hpp"
#include "od/sdo_client.hpp"

namespace stepnode::node::test {
namespace {

constexpr uint32_t kInvalid = 0x80000000;
// Channel 0x1201 as the demo configures it for node 5: free identifiers (CiA 301 7.3.5).
constexpr uint32_t kRx2 = 0x685, kTx2 = 0x6C5;
constexpr uint32_t kRx3 = 0x695, kTx3 = 0x6D5;
constexpr uint32_t kInvalidValue = 0x06090030;

CanFrame upload_request(uint32_t cob_id, uint16_t index, uint8_t sub) {
  return CanFrame(cob_id, {0x40, static_cast<uint8_t>(index), static_cast<uint8_t>(index >> 8), sub,
                           0, 0, 0, 0});
}
// Upload segment request, 7.2.4.3.7: ccs 3, toggle in bit 4.
CanFrame segment_request(uint32_t cob_id, bool toggle) {
  return CanFrame(cob_id, {static_cast<uint8_t>(0x60 | (toggle ? 0x10 : 0)), 0, 0, 0, 0, 0, 0, 0});
}

class SdoServerChannelsTest : public NodeHarness {
 protected:
  void enable(uint16_t index, uint32_t rx, uint32_t tx) {
    ASSERT_EQ(sdo_write(index, 1, rx), 0u);
    ASSERT_EQ(sdo_write(index, 2, tx), 0u);
  }
  // The frames the node sent on `id` for this one request.
  std::vector<CanFrame> answer(const CanFrame& request, uint32_t id) {
    size_t before = sent.size();
    frame(request);
    return with_id(id, before);
  }
};

TEST_F(SdoServerChannelsTest, ParameterRecordsAsCia301Lays) {
  EXPECT_EQ(sdo_read(0x1200, 0), 2u);
  EXPECT_EQ(sdo_read(0x1200, 1), kSdoRx);
  EXPECT_EQ(sdo_read(0x1200, 2), kSdoTx);
  for (uint16_t index : {0x1201, 0x1202, 0x1203}) {
    EXPECT_EQ(sdo_read(index, 0), 3u) << std::hex << index;
    EXPECT_EQ(sdo_read(index, 1), kInvalid);  // disabled until an integrator configures it
    EXPECT_EQ(sdo_read(index, 2), kInvalid);
    EXPECT_EQ(sdo_read(index, 3), 0u);
  }
  uint32_t abort = 0;
  EXPECT_FALSE(sdo_read(0x1204, 0, &abort).has_value());
  EXPECT_EQ(abort, 0x06020000u);                        // no such object
  EXPECT_EQ(sdo_write(0x1200, 1, 0x606), 0x06010002u);  // the default channel is read-only
}

TEST_F(SdoServerChannelsTest, DisabledChannelIgnoresFrames) {
  ASSERT_EQ(sdo_write(0x1201, 1, kRx2), 0u);  // rx valid, tx still invalid: not usable
  EXPECT_TRUE(answer(upload_request(kRx2, 0x1017, 0), kTx2).empty());
  clear_sent();
  frame(upload_request(kRx2, 0x1017, 0));
  EXPECT_TRUE(sent.empty());
}

TEST_F(SdoServerChannelsTest, ExpeditedUploadOnTheSecondChannelIsAnsweredOnItsTxCobId) {
  enable(0x1201, kRx2, kTx2);
  ASSERT_EQ(sdo_write(0x1017, 0, 500, 2), 0u);
  // 7.2.4.3.6: scs 2, n = 2 unused bytes, e = 1, s = 1: 0x4B; 0x1017:00 = 500 (0x01F4).
  const size_t before = sent.size();
  auto r = answer(upload_request(kRx2, 0x1017, 0), kTx2);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0], CanFrame(kTx2, {0x4B, 0x17, 0x10, 0x00, 0xF4, 0x01, 0x00, 0x00}));
  EXPECT_TRUE(with_id(kSdoTx, before).empty()) << "the default channel stays silent";
}

TEST_F(SdoServerChannelsTest, TwoSegmentedUploadsAtOnceOnTwoChannels) {
  enable(0x1201, kRx2, kTx2);
  // "stepnode" (8 bytes) on both channels, the requests interleaved segment by segment.
  auto a = answer(upload_request(kSdoRx, 0x1008, 0), kSdoTx);
  auto b = answer(upload_request(kRx2, 0x1008, 0), kTx2);
  const CanFrame init(0, {0x41, 0x08, 0x10, 0x00, 0x08, 0x00, 0x00, 0x00});  // s = 1, size 8
  ASSERT_EQ(a.size(), 1u);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(a[0].data, init.data);
  EXPECT_EQ(b[0].data, init.data);
  a = answer(segment_request(kSdoRx, false), kSdoTx);
  b = answer(segment_request(kRx2, false), kTx2);
  ASSERT_EQ(a.size(), 1u);
  ASSERT_EQ(b.size(), 1u);
  // 7 bytes, toggle 0, not last: 0x00 "stepnod".
  EXPECT_EQ(a[0], CanFrame(kSdoTx, {0x00, 's', 't', 'e', 'p', 'n', 'o', 'd'}));
  EXPECT_EQ(b[0], CanFrame(kTx2, {0x00, 's', 't', 'e', 'p', 'n', 'o', 'd'}));
  b = answer(segment_request(kRx2, true), kTx2);
  a = answer(segment_request(kSdoRx, true), kSdoTx);
  // 1 byte, toggle 1, n = 6, c = 1: 0x1D "e".
  ASSERT_EQ(b.size(), 1u);
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(b[0], CanFrame(kTx2, {0x1D, 'e', 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(a[0], CanFrame(kSdoTx, {0x1D, 'e', 0, 0, 0, 0, 0, 0}));
}

// Three od::SdoClient transfers on three channels at once, frame by frame.
TEST_F(SdoServerChannelsTest, BlockAndSegmentedTransfersOnThreeChannelsAtOnce) {
  enable(0x1201, kRx2, kTx2);
  enable(0x1202, kRx3, kTx3);
  od::SdoClient eds(kSdoRx, kSdoTx), data(kRx2, kTx2), name(kRx3, kTx3);
  std::vector<CanFrame> out;
  const od::Bytes blob(3000, 0x5A);
  eds.start_upload(0x1021, 0, od::SdoClient::Mode::Block, t, out);
  data.start_download(0x2F01, 0, blob, od::SdoClient::Mode::Block, t, out);
  name.start_upload(0x1008, 0, od::SdoClient::Mode::Segmented, t, out);
  for (int round = 0; round < 10000 && !(eds.done() && data.done() && name.done()); ++round) {
    size_t before = sent.size();
    for (const auto& f : out) frame(f);
    out.clear();
    t += 100;
    for (size_t i = before; i < sent.size(); ++i)
      for (od::SdoClient* c : {&eds, &data, &name}) c->on_frame(sent[i], t, out);
  }
  ASSERT_TRUE(eds.result().ok()) << std::hex << static_cast<uint32_t>(eds.result().abort);
  ASSERT_TRUE(data.result().ok()) << std::hex << static_cast<uint32_t>(data.result().abort);
  ASSERT_TRUE(name.result().ok());
  EXPECT_EQ(std::string(name.result().data.begin(), name.result().data.end()), "stepnode");
  const auto& text = eds.result().data;
  EXPECT_NE(std::string(text.begin(), text.end()).find("[1201]"), std::string::npos);
  EXPECT_EQ(od().value(0x2F01, 0), blob);
}

TEST_F(SdoServerChannelsTest, CobIdOfAValidChannelChangesOnlyAfterBit31) {
  enable(0x1201, kRx2, kTx2);
  EXPECT_EQ(sdo_write(0x1201, 1, 0x686), kInvalidValue);
  EXPECT_EQ(sdo_read(0x1201, 1), kRx2);
  EXPECT_EQ(sdo_write(0x1201, 1, kInvalid | kRx2), 0u);  // disable ...
  EXPECT_TRUE(answer(upload_request(kRx2, 0x1017, 0), kTx2).empty());
  EXPECT_EQ(sdo_write(0x1201, 1, 0x686), 0u);  // ... then the new identifier
  EXPECT_EQ(answer(upload_request(0x686, 0x1017, 0), kTx2).size(), 1u);
}

TEST_F(SdoServerChannelsTest, RestrictedOrExtendedIdentifiersAreRefused) {
  EXPECT_EQ(sdo_write(0x1201, 1, 0x605), kInvalidValue);       // 0x601..0x67F: default SDO
  EXPECT_EQ(sdo_write(0x1201, 2, 0x705), kInvalidValue);       // 0x701..0x77F: heartbeat
  EXPECT_EQ(sdo_write(0x1201, 1, 0x20000685), kInvalidValue);  // 29-bit frame
  EXPECT_EQ(sdo_write(0x1201, 3, 128, 1), 0x06090031u);        // client node-ID above 127
  EXPECT_EQ(sdo_write(0x1201, 3, 7, 1), 0u);
  EXPECT_EQ(sdo_write(0x1201, 1, 0x40000685), 0u);  // bit 30 dynamic: allowed
}

TEST_F(SdoServerChannelsTest, ChannelThatDisablesItselfConfirmsOnItsOldCobId) {
  enable(0x1201, kRx2, kTx2);
  auto r = answer(CanFrame(kRx2, {0x23, 0x01, 0x12, 0x02, 0xC5, 0x06, 0x00, 0x80}), kTx2);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0], CanFrame(kTx2, {0x60, 0x01, 0x12, 0x02, 0, 0, 0, 0}));
  EXPECT_TRUE(answer(upload_request(kRx2, 0x1017, 0), kTx2).empty());
}

TEST_F(SdoServerChannelsTest, StoredByCommunicationParametersAndRestoredToDisabled) {
  enable(0x1201, kRx2, kTx2);
  ASSERT_EQ(sdo_write(0x1201, 3, 9, 1), 0u);
  ASSERT_EQ(sdo_write(0x1010, 2, 0x65766173), 0u);  // "save" communication parameters
  make();                                           // a new process
  EXPECT_EQ(sdo_read(0x1201, 1), kRx2);
  EXPECT_EQ(sdo_read(0x1201, 3), 9u);
  EXPECT_EQ(answer(upload_request(kRx2, 0x1201, 3), kTx2).size(), 1u);
  ASSERT_EQ(sdo_write(0x1011, 2, 0x64616F6C), 0u);  // "load": defaults after the next reset
  nmt(0x82);                                        // reset communication
  EXPECT_EQ(sdo_read(0x1201, 1), kInvalid);
  EXPECT_TRUE(answer(upload_request(kRx2, 0x1017, 0), kTx2).empty());
}

TEST_F(SdoServerChannelsTest, StoppedNodeAnswersOnNoChannel) {
  enable(0x1201, kRx2, kTx2);
  nmt(0x02);  // stop
  EXPECT_TRUE(answer(upload_request(kRx2, 0x1017, 0), kTx2).empty());
  nmt(0x80);  // pre-operational
  EXPECT_EQ(answer(upload_request(kRx2, 0x1017, 0), kTx2).size(), 1u);
}

}  // namespace
}  // namespace stepnode::node::test
