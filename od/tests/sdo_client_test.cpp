// SdoClient against hand-written server frames (CiA 301 7.2.4.3 layouts).
#include <gtest/gtest.h>

#include "od/crc16.hpp"
#include "od/sdo_client.hpp"
#include "sdo_test_support.hpp"

namespace stepnode::od {
namespace {

using namespace sdotest;
using Mode = SdoClient::Mode;
using Frames = std::vector<CanFrame>;

class SdoClientTest : public ::testing::Test {
 protected:
  Frames upload(uint16_t index, uint8_t sub, Mode mode) {
    Frames out;
    client.start_upload(index, sub, mode, now, out);
    return out;
  }
  Frames download(uint16_t index, uint8_t sub, Bytes data, Mode mode) {
    Frames out;
    client.start_download(index, sub, std::move(data), mode, now, out);
    return out;
  }
  Frames feed(const CanFrame& f) {
    Frames out;
    client.on_frame(f, now, out);
    for (const auto& r : out) {
      EXPECT_EQ(r.dlc, 8);
      EXPECT_EQ(r.id, kRx);
    }
    return out;
  }
  static Frames one(const CanFrame& f) { return Frames{f}; }
  static CanFrame aborted(uint16_t index, uint8_t sub, uint32_t code) {
    return abort_of(kRx, index, sub, code);
  }
  void expect_failed(SdoAbort code, bool by_server = false) {
    EXPECT_TRUE(client.done());
    EXPECT_EQ(client.result().abort, code);
    EXPECT_EQ(client.result().aborted_by_server, by_server);
  }

  SdoClient client{kRx, kTx};
  uint64_t now = 0;
};

TEST_F(SdoClientTest, IdleClientIsDoneAndIgnoresFrames) {
  EXPECT_TRUE(client.done());
  EXPECT_TRUE(client.result().ok());
  EXPECT_TRUE(feed(rsp({0x43, 0x02, 0x20, 0x00, 1, 2, 3, 4})).empty());
  EXPECT_EQ(client.request_cob_id(), kRx);
  EXPECT_EQ(client.response_cob_id(), kTx);
}

// ---- uploads ----

TEST_F(SdoClientTest, ExpeditedUpload) {
  EXPECT_EQ(upload(kU32, 0, Mode::Auto), one(req({0x40, 0x02, 0x20, 0x00, 0, 0, 0, 0})));
  EXPECT_FALSE(client.done());
  EXPECT_TRUE(feed(rsp({0x43, 0x02, 0x20, 0x00, 0x78, 0x56, 0x34, 0x12})).empty());
  ASSERT_TRUE(client.done());
  EXPECT_TRUE(client.result().ok());
  EXPECT_EQ(client.result().data, (Bytes{0x78, 0x56, 0x34, 0x12}));
}

TEST_F(SdoClientTest, ExpeditedUploadSizes) {
  upload(kU8, 0, Mode::Segmented);
  feed(rsp({0x4F, 0x00, 0x20, 0x00, 0x05, 0xEE, 0xEE, 0xEE}));
  EXPECT_EQ(client.result().data, Bytes{0x05});
  upload(kU16, 0, Mode::Auto);
  feed(rsp({0x4B, 0x01, 0x20, 0x00, 0x34, 0x12, 0xEE, 0xEE}));
  EXPECT_EQ(client.result().data, (Bytes{0x34, 0x12}));
  EXPECT_FALSE(client.result().size_unspecified);
  EXPECT_EQ(client.result().value_of_size(1), (Bytes{0x34, 0x12}));  // a wrong size stays
  upload(kU32, 0, Mode::Auto);  // e = 1, s = 0: four bytes of unspecified size
  feed(rsp({0x42, 0x02, 0x20, 0x00, 1, 2, 3, 4}));
  EXPECT_EQ(client.result().data, (Bytes{1, 2, 3, 4}));
  EXPECT_TRUE(client.result().size_unspecified);
}

// 7.2.4.3.6: with e = 1 and s = 0 the data bytes hold an unspecified number of bytes;
// the client takes the object's size from its data type (another vendor's device may
// answer an UNSIGNED8 that way, the rest of the four bytes anything).
TEST_F(SdoClientTest, AnExpeditedUploadWithoutTheSizeIsCutToTheObjectsType) {
  upload(kU8, 0, Mode::Auto);
  feed(rsp({0x42, 0x00, 0x20, 0x00, 0x02, 0xEE, 0xEE, 0xEE}));
  ASSERT_TRUE(client.result().ok());
  EXPECT_EQ(client.result().value_of_size(1), Bytes{0x02});
  EXPECT_EQ(client.result().value_of_size(2), (Bytes{0x02, 0xEE}));
  EXPECT_EQ(client.result().value_of_size(4), (Bytes{0x02, 0xEE, 0xEE, 0xEE}));
}

TEST_F(SdoClientTest, SegmentedUpload) {
  upload(kString, 0, Mode::Auto);
  EXPECT_EQ(feed(rsp({0x41, 0x06, 0x20, 0x00, 8, 0, 0, 0})), one(req({0x60, 0, 0, 0, 0, 0, 0, 0})));
  EXPECT_EQ(feed(rsp({0x00, 's', 't', 'e', 'p', 'n', 'o', 'd'})),
            one(req({0x70, 0, 0, 0, 0, 0, 0, 0})));
  EXPECT_TRUE(feed(rsp({0x1D, 'e', 0, 0, 0, 0, 0, 0})).empty());
  ASSERT_TRUE(client.done());
  EXPECT_EQ(client.result().data, encode_string("stepnode"));
}

TEST_F(SdoClientTest, SegmentedUploadWithoutSize) {
  upload(kDomain, 0, Mode::Auto);
  feed(rsp({0x40, 0x07, 0x20, 0x00, 0, 0, 0, 0}));
  EXPECT_EQ(feed(rsp({0x00, 1, 2, 3, 4, 5, 6, 7})), one(req({0x70, 0, 0, 0, 0, 0, 0, 0})));
  feed(rsp({0x1B, 8, 9, 0, 0, 0, 0, 0}));  // n = 5, c
  EXPECT_EQ(client.result().data, (Bytes{1, 2, 3, 4, 5, 6, 7, 8, 9}));
}

TEST_F(SdoClientTest, UploadLongerThanIndicatedAborts) {
  upload(kString, 0, Mode::Auto);
  feed(rsp({0x41, 0x06, 0x20, 0x00, 3, 0, 0, 0}));
  EXPECT_EQ(feed(rsp({0x01, 's', 't', 'e', 'p', 'n', 'o', 'd'})),
            one(aborted(kString, 0, 0x06070010)));
  upload(kString, 0, Mode::Auto);
  feed(rsp({0x41, 0x06, 0x20, 0x00, 9, 0, 0, 0}));
  EXPECT_EQ(feed(rsp({0x01, 's', 't', 'e', 'p', 'n', 'o', 'd'})),
            one(aborted(kString, 0, 0x06070010)));
}

// ---- downloads ----

TEST_F(SdoClientTest, ExpeditedDownload) {
  EXPECT_EQ(download(kU32, 0, {0x44, 0x33, 0x22, 0x11}, Mode::Auto),
            one(req({0x23, 0x02, 0x20, 0x00, 0x44, 0x33, 0x22, 0x11})));
  EXPECT_TRUE(feed(rsp({0x60, 0x02, 0x20, 0x00, 0, 0, 0, 0})).empty());
  EXPECT_TRUE(client.done());
  EXPECT_TRUE(client.result().ok());
  EXPECT_EQ(download(kU8, 0, {0x07}, Mode::Auto), one(req({0x2F, 0x00, 0x20, 0x00, 7, 0, 0, 0})));
  feed(rsp({0x60, 0x00, 0x20, 0x00, 0, 0, 0, 0}));
  EXPECT_EQ(download(kU16, 0, {1, 2}, Mode::Auto), one(req({0x2B, 0x01, 0x20, 0x00, 1, 2, 0, 0})));
  feed(rsp({0x60, 0x01, 0x20, 0x00, 0, 0, 0, 0}));
  EXPECT_EQ(download(kU16, 0, {1, 2, 3}, Mode::Auto),
            one(req({0x27, 0x01, 0x20, 0x00, 1, 2, 3, 0})));
  feed(rsp({0x60, 0x01, 0x20, 0x00, 0, 0, 0, 0}));
  EXPECT_TRUE(client.result().ok());
}

TEST_F(SdoClientTest, SegmentedDownload) {
  EXPECT_EQ(download(kString, 0, encode_string("hello worl"), Mode::Auto),
            one(req({0x21, 0x06, 0x20, 0x00, 10, 0, 0, 0})));
  EXPECT_EQ(feed(rsp({0x60, 0x06, 0x20, 0x00, 0, 0, 0, 0})),
            one(req({0x00, 'h', 'e', 'l', 'l', 'o', ' ', 'w'})));
  EXPECT_EQ(feed(rsp({0x20, 0, 0, 0, 0, 0, 0, 0})), one(req({0x19, 'o', 'r', 'l', 0, 0, 0, 0})));
  EXPECT_FALSE(client.done());
  EXPECT_TRUE(feed(rsp({0x30, 0, 0, 0, 0, 0, 0, 0})).empty());
  EXPECT_TRUE(client.done());
  EXPECT_TRUE(client.result().ok());
}

TEST_F(SdoClientTest, SegmentedModeNeverUsesExpedited) {
  EXPECT_EQ(download(kU16, 0, {1, 2}, Mode::Segmented),
            one(req({0x21, 0x01, 0x20, 0x00, 2, 0, 0, 0})));
  EXPECT_EQ(feed(rsp({0x60, 0x01, 0x20, 0x00, 0, 0, 0, 0})), one(req({0x0B, 1, 2, 0, 0, 0, 0, 0})));
}

TEST_F(SdoClientTest, EmptyDownloadIsOneEmptySegment) {
  EXPECT_EQ(download(kDomain, 0, {}, Mode::Auto), one(req({0x21, 0x07, 0x20, 0x00, 0, 0, 0, 0})));
  EXPECT_EQ(feed(rsp({0x60, 0x07, 0x20, 0x00, 0, 0, 0, 0})), one(req({0x0F, 0, 0, 0, 0, 0, 0, 0})));
}

// ---- block download ----

TEST_F(SdoClientTest, BlockDownload) {
  Bytes data = pattern(10);
  EXPECT_EQ(download(kDomain, 0, data, Mode::Block),
            one(req({0xC6, 0x07, 0x20, 0x00, 10, 0, 0, 0})));
  EXPECT_EQ(feed(rsp({0xA4, 0x07, 0x20, 0x00, 127, 0, 0, 0})),
            (Frames{req({0x01, data[0], data[1], data[2], data[3], data[4], data[5], data[6]}),
                    req({0x82, data[7], data[8], data[9], 0, 0, 0, 0})}));
  uint16_t crc = crc16_ccitt(data);
  EXPECT_EQ(
      feed(rsp({0xA2, 2, 127, 0, 0, 0, 0, 0})),
      one(req({0xD1, static_cast<uint8_t>(crc), static_cast<uint8_t>(crc >> 8), 0, 0, 0, 0, 0})));
  EXPECT_FALSE(client.done());
  EXPECT_TRUE(feed(rsp({0xA1, 0, 0, 0, 0, 0, 0, 0})).empty());
  EXPECT_TRUE(client.done());
  EXPECT_TRUE(client.result().ok());
}

TEST_F(SdoClientTest, BlockDownloadFollowsTheServersBlockSizeAndAckseq) {
  Bytes data = pattern(30);
  download(kDomain, 0, data, Mode::Block);
  Frames first = feed(rsp({0xA4, 0x07, 0x20, 0x00, 2, 0, 0, 0}));
  ASSERT_EQ(first.size(), 2u);
  EXPECT_EQ(first[1].data[0], 0x02);
  // Only segment 1 arrived: repeat from byte 7, three segments a sub-block now.
  Frames repeat = feed(rsp({0xA2, 1, 3, 0, 0, 0, 0, 0}));
  ASSERT_EQ(repeat.size(), 3u);
  EXPECT_EQ(repeat[0],
            req({0x01, data[7], data[8], data[9], data[10], data[11], data[12], data[13]}));
  EXPECT_EQ(repeat[2].data[0], 0x03);
  Frames last = feed(rsp({0xA2, 3, 3, 0, 0, 0, 0, 0}));  // 28 bytes confirmed
  EXPECT_EQ(last, one(req({0x81, data[28], data[29], 0, 0, 0, 0, 0})));
  uint16_t crc = crc16_ccitt(data);
  EXPECT_EQ(
      feed(rsp({0xA2, 1, 3, 0, 0, 0, 0, 0})),  // n = 5
      one(req({0xD5, static_cast<uint8_t>(crc), static_cast<uint8_t>(crc >> 8), 0, 0, 0, 0, 0})));
}

TEST_F(SdoClientTest, BlockDownloadProtocolErrors) {
  download(kDomain, 0, pattern(10), Mode::Block);
  EXPECT_EQ(feed(rsp({0xA4, 0x07, 0x20, 0x00, 0, 0, 0, 0})), one(aborted(kDomain, 0, 0x05040002)));
  expect_failed(SdoAbort::InvalidBlockSize);
  download(kDomain, 0, pattern(10), Mode::Block);
  feed(rsp({0xA4, 0x07, 0x20, 0x00, 127, 0, 0, 0}));
  EXPECT_EQ(feed(rsp({0xA2, 3, 127, 0, 0, 0, 0, 0})), one(aborted(kDomain, 0, 0x05040003)));
  expect_failed(SdoAbort::InvalidSequence);
  download(kDomain, 0, pattern(10), Mode::Block);
  feed(rsp({0xA4, 0x07, 0x20, 0x00, 127, 0, 0, 0}));
  EXPECT_EQ(feed(rsp({0xA2, 2, 200, 0, 0, 0, 0, 0})), one(aborted(kDomain, 0, 0x05040002)));
}

// ---- block upload ----

TEST_F(SdoClientTest, BlockUpload) {
  client.set_block_size(7);
  EXPECT_EQ(upload(kDomain, 0, Mode::Block), one(req({0xA4, 0x07, 0x20, 0x00, 7, 4, 0, 0})));
  Bytes data = pattern(10);
  EXPECT_EQ(feed(rsp({0xC6, 0x07, 0x20, 0x00, 10, 0, 0, 0})),
            one(req({0xA3, 0, 0, 0, 0, 0, 0, 0})));
  EXPECT_TRUE(
      feed(rsp({0x01, data[0], data[1], data[2], data[3], data[4], data[5], data[6]})).empty());
  EXPECT_EQ(feed(rsp({0x82, data[7], data[8], data[9], 0, 0, 0, 0})),
            one(req({0xA2, 2, 7, 0, 0, 0, 0, 0})));
  uint16_t crc = crc16_ccitt(data);
  EXPECT_EQ(
      feed(rsp({0xD1, static_cast<uint8_t>(crc), static_cast<uint8_t>(crc >> 8), 0, 0, 0, 0, 0})),
      one(req({0xA1, 0, 0, 0, 0, 0, 0, 0})));
  ASSERT_TRUE(client.done());
  EXPECT_TRUE(client.result().ok());
  EXPECT_EQ(client.result().data, data);
}

TEST_F(SdoClientTest, BlockUploadAcksAGapWithTheLastGoodSeqno) {
  upload(kDomain, 0, Mode::Block);
  feed(rsp({0xC6, 0x07, 0x20, 0x00, 21, 0, 0, 0}));
  EXPECT_TRUE(feed(rsp({0x01, 1, 1, 1, 1, 1, 1, 1})).empty());
  EXPECT_EQ(feed(rsp({0x83, 3, 3, 3, 3, 3, 3, 3})), one(req({0xA2, 1, 127, 0, 0, 0, 0, 0})));
  EXPECT_TRUE(feed(rsp({0x02, 2, 2, 2, 2, 2, 2, 2})).empty());  // late: ignored
  EXPECT_TRUE(feed(rsp({0x01, 2, 2, 2, 2, 2, 2, 2})).empty());
  EXPECT_EQ(feed(rsp({0x82, 3, 3, 3, 3, 3, 3, 3})), one(req({0xA2, 2, 127, 0, 0, 0, 0, 0})));
  Bytes data(21);
  for (size_t i = 0; i < 21; ++i) data[i] = static_cast<uint8_t>(1 + i / 7);
  uint16_t crc = crc16_ccitt(data);
  feed(rsp({0xC1, static_cast<uint8_t>(crc), static_cast<uint8_t>(crc >> 8), 0, 0, 0, 0, 0}));
  EXPECT_EQ(client.result().data, data);
}

TEST_F(SdoClientTest, BlockUploadCrcMismatchAborts) {
  upload(kString, 0, Mode::Block);
  feed(rsp({0xC6, 0x06, 0x20, 0x00, 3, 0, 0, 0}));
  feed(rsp({0x81, 'a', 'b', 'c', 0, 0, 0, 0}));
  uint16_t crc = crc16_ccitt(encode_string("abc")) ^ 1;
  EXPECT_EQ(
      feed(rsp({0xD1, static_cast<uint8_t>(crc), static_cast<uint8_t>(crc >> 8), 0, 0, 0, 0, 0})),
      one(aborted(kString, 0, 0x05040004)));
  expect_failed(SdoAbort::CrcError);
  EXPECT_TRUE(client.result().data.empty());
}

TEST_F(SdoClientTest, BlockUploadWithoutServerCrcSkipsTheCheck) {
  upload(kString, 0, Mode::Block);
  feed(rsp({0xC2, 0x06, 0x20, 0x00, 3, 0, 0, 0}));  // sc = 0
  feed(rsp({0x81, 'a', 'b', 'c', 0, 0, 0, 0}));
  EXPECT_EQ(feed(rsp({0xD1, 0, 0, 0, 0, 0, 0, 0})), one(req({0xA1, 0, 0, 0, 0, 0, 0, 0})));
  EXPECT_EQ(client.result().data, encode_string("abc"));
}

TEST_F(SdoClientTest, BlockUploadFollowsAProtocolSwitch) {
  upload(kU32, 0, Mode::Block);
  EXPECT_TRUE(feed(rsp({0x43, 0x02, 0x20, 0x00, 1, 2, 3, 4})).empty());
  EXPECT_EQ(client.result().data, (Bytes{1, 2, 3, 4}));
  upload(kString, 0, Mode::Block);
  EXPECT_EQ(feed(rsp({0x41, 0x06, 0x20, 0x00, 3, 0, 0, 0})), one(req({0x60, 0, 0, 0, 0, 0, 0, 0})));
  feed(rsp({0x09, 'a', 'b', 'c', 0, 0, 0, 0}));
  EXPECT_EQ(client.result().data, encode_string("abc"));
}

TEST_F(SdoClientTest, BlockUploadInvalidSequenceAborts) {
  client.set_block_size(4);
  upload(kDomain, 0, Mode::Block);
  feed(rsp({0xC6, 0x07, 0x20, 0x00, 100, 0, 0, 0}));
  EXPECT_EQ(feed(rsp({0x05, 0, 0, 0, 0, 0, 0, 0})), one(aborted(kDomain, 0, 0x05040003)));
  expect_failed(SdoAbort::InvalidSequence);
}

// ---- aborts, timeouts, protocol errors ----

TEST_F(SdoClientTest, ServerAbortEndsTheTransfer) {
  upload(kWo, 0, Mode::Auto);
  EXPECT_TRUE(feed(abort_of(kTx, kWo, 0, 0x06010001)).empty());
  expect_failed(SdoAbort::WriteOnly, true);
  download(kDomain, 0, pattern(100), Mode::Block);
  feed(rsp({0xA4, 0x07, 0x20, 0x00, 127, 0, 0, 0}));
  EXPECT_TRUE(feed(abort_of(kTx, kDomain, 0, 0x05040004)).empty());
  expect_failed(SdoAbort::CrcError, true);
}

TEST_F(SdoClientTest, TimeoutSendsAnAbort) {
  client.set_timeout_us(5000);
  upload(kU32, 0, Mode::Auto);
  Frames out;
  client.on_tick(4999, out);
  EXPECT_TRUE(out.empty());
  client.on_tick(5000, out);
  EXPECT_EQ(out, one(aborted(kU32, 0, 0x05040000)));
  expect_failed(SdoAbort::Timeout);
  out.clear();
  client.on_tick(20000, out);
  EXPECT_TRUE(out.empty());
}

TEST_F(SdoClientTest, TimeoutCountsFromTheLastResponse) {
  client.set_timeout_us(5000);
  upload(kString, 0, Mode::Auto);
  now = 4000;
  feed(rsp({0x41, 0x06, 0x20, 0x00, 8, 0, 0, 0}));
  Frames out;
  client.on_tick(8999, out);
  EXPECT_TRUE(out.empty());
  client.on_tick(9000, out);
  EXPECT_EQ(out, one(aborted(kString, 0, 0x05040000)));
}

// ---- responses that are not ours (another client on the channel, CiA 301 7.2.4.1) ----

TEST_F(SdoClientTest, ExpeditedReplyNamingAnotherObjectIsIgnored) {
  upload(kU32, 0, Mode::Auto);
  // 7.2.4.3.6: 0x43 = scs 2, e, s, n = 0; multiplexer 0x2003:00 is not our 0x2002:00.
  EXPECT_TRUE(feed(rsp({0x43, 0x03, 0x20, 0x00, 1, 2, 3, 4})).empty());
  EXPECT_FALSE(client.done());
  EXPECT_TRUE(feed(rsp({0x43, 0x02, 0x20, 0x00, 0x78, 0x56, 0x34, 0x12})).empty());
  ASSERT_TRUE(client.result().ok());
  EXPECT_EQ(client.result().data, (Bytes{0x78, 0x56, 0x34, 0x12}));
  EXPECT_EQ(client.result().foreign_replies, 1u);
}

TEST_F(SdoClientTest, DownloadConfirmationNamingAnotherObjectIsIgnored) {
  download(kU32, 0, {1, 2, 3, 4}, Mode::Auto);
  EXPECT_TRUE(feed(rsp({0x60, 0x01, 0x20, 0x00, 0, 0, 0, 0})).empty());  // 0x2001:00
  EXPECT_TRUE(feed(rsp({0x60, 0x02, 0x20, 0x01, 0, 0, 0, 0})).empty());  // 0x2002:01
  EXPECT_FALSE(client.done());
  feed(rsp({0x60, 0x02, 0x20, 0x00, 0, 0, 0, 0}));
  EXPECT_TRUE(client.result().ok());
  EXPECT_EQ(client.result().foreign_replies, 2u);
}

TEST_F(SdoClientTest, WrongCommandSpecifierForThePhaseIsIgnored) {
  upload(kU32, 0, Mode::Auto);
  // A download confirmation (scs 3) and an upload segment (scs 0) answer another request.
  EXPECT_TRUE(feed(rsp({0x60, 0x02, 0x20, 0x00, 0, 0, 0, 0})).empty());
  EXPECT_TRUE(feed(rsp({0x00, 's', 't', 'e', 'p', 'n', 'o', 'd'})).empty());
  EXPECT_TRUE(feed(rsp({0xE0, 0, 0, 0, 0, 0, 0, 0})).empty());  // scs 7: none at all
  EXPECT_FALSE(client.done());
  feed(rsp({0x4B, 0x02, 0x20, 0x00, 0x34, 0x12, 0, 0}));  // n = 2: two bytes
  EXPECT_EQ(client.result().data, (Bytes{0x34, 0x12}));
  EXPECT_EQ(client.result().foreign_replies, 3u);
}

TEST_F(SdoClientTest, ShortFrameIsStillAProtocolError) {
  download(kU32, 0, {1, 2, 3, 4}, Mode::Auto);
  // 7.2.4.3.1: every SDO frame has 8 bytes.
  EXPECT_EQ(feed(CanFrame(kTx, {0x60, 0x02, 0x20, 0x00})), one(aborted(kU32, 0, 0x05040001)));
  expect_failed(SdoAbort::BadCommand);
}

TEST_F(SdoClientTest, UploadSegmentWithTheWrongToggleIsIgnored) {
  upload(kString, 0, Mode::Auto);
  EXPECT_EQ(feed(rsp({0x41, 0x06, 0x20, 0x00, 8, 0, 0, 0})), one(req({0x60, 0, 0, 0, 0, 0, 0, 0})));
  // 7.2.4.3.7: the answer to a request with t = 0 has t = 0; 0x10 (t = 1) is not it.
  EXPECT_TRUE(feed(rsp({0x10, 'x', 'x', 'x', 'x', 'x', 'x', 'x'})).empty());
  EXPECT_EQ(feed(rsp({0x00, 's', 't', 'e', 'p', 'n', 'o', 'd'})),
            one(req({0x70, 0, 0, 0, 0, 0, 0, 0})));
  EXPECT_TRUE(feed(rsp({0x0D, 'y', 0, 0, 0, 0, 0, 0})).empty());  // t = 0 again: stale
  feed(rsp({0x1D, 'e', 0, 0, 0, 0, 0, 0}));                       // t = 1, n = 6, c
  ASSERT_TRUE(client.result().ok());
  EXPECT_EQ(client.result().data, encode_string("stepnode"));
  EXPECT_EQ(client.result().foreign_replies, 2u);
}

TEST_F(SdoClientTest, DownloadSegmentConfirmationWithTheWrongToggleIsIgnored) {
  download(kString, 0, encode_string("hello worl"), Mode::Auto);
  feed(rsp({0x60, 0x06, 0x20, 0x00, 0, 0, 0, 0}));
  // 7.2.4.3.4: the confirmation of segment t = 0 is 0x20; 0x30 (t = 1) belongs elsewhere.
  EXPECT_TRUE(feed(rsp({0x30, 0, 0, 0, 0, 0, 0, 0})).empty());
  EXPECT_EQ(feed(rsp({0x20, 0, 0, 0, 0, 0, 0, 0})), one(req({0x19, 'o', 'r', 'l', 0, 0, 0, 0})));
  feed(rsp({0x30, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_TRUE(client.result().ok());
}

TEST_F(SdoClientTest, AbortNamingAnotherObjectIsIgnored) {
  upload(kU32, 0, Mode::Auto);
  EXPECT_TRUE(feed(abort_of(kTx, kU16, 0, 0x06010001)).empty());
  EXPECT_FALSE(client.done());
  EXPECT_TRUE(feed(abort_of(kTx, kU32, 0, 0x06020000)).empty());
  expect_failed(SdoAbort::NoObject, true);
  EXPECT_EQ(client.result().foreign_replies, 1u);
}

TEST_F(SdoClientTest, BlockUploadInitiateForAnotherObjectIsIgnored) {
  upload(kDomain, 0, Mode::Block);
  // 7.2.4.3.12: 0xC6 = scs 6, sc, s, ss 0; 0x2006 is not our 0x2007.
  EXPECT_TRUE(feed(rsp({0xC6, 0x06, 0x20, 0x00, 10, 0, 0, 0})).empty());
  EXPECT_EQ(feed(rsp({0xC6, 0x07, 0x20, 0x00, 10, 0, 0, 0})),
            one(req({0xA3, 0, 0, 0, 0, 0, 0, 0})));
}

TEST_F(SdoClientTest, TimeoutAfterForeignRepliesSaysTheChannelWasBusy) {
  client.set_timeout_us(5000);
  upload(kU32, 0, Mode::Auto);
  Frames out;
  for (now = 1000; now <= 4000; now += 1000) feed(rsp({0x43, 0x03, 0x20, 0x00, 1, 2, 3, 4}));
  client.on_tick(4999, out);
  EXPECT_TRUE(out.empty());  // foreign replies do not restart the timeout
  client.on_tick(5000, out);
  EXPECT_EQ(out, one(aborted(kU32, 0, 0x05040000)));
  expect_failed(SdoAbort::Timeout);
  EXPECT_EQ(client.result().foreign_replies, 4u);
  upload(kU32, 0, Mode::Auto);  // the next transfer counts anew
  feed(rsp({0x43, 0x02, 0x20, 0x00, 1, 2, 3, 4}));
  EXPECT_EQ(client.result().foreign_replies, 0u);
}

TEST_F(SdoClientTest, FramesOnOtherCobIdsAreIgnored) {
  upload(kU32, 0, Mode::Auto);
  EXPECT_TRUE(feed(CanFrame(0x586, {0x43, 0x02, 0x20, 0x00, 1, 2, 3, 4})).empty());
  EXPECT_FALSE(client.done());
}

TEST_F(SdoClientTest, StartingAnotherTransferAbortsTheOneInProgress) {
  upload(kString, 0, Mode::Auto);
  EXPECT_EQ(upload(kU32, 0, Mode::Auto),
            (Frames{aborted(kString, 0, 0x08000000), req({0x40, 0x02, 0x20, 0x00, 0, 0, 0, 0})}));
  feed(rsp({0x43, 0x02, 0x20, 0x00, 1, 2, 3, 4}));
  EXPECT_TRUE(client.result().ok());
}

}  // namespace
}  // namespace stepnode::od
