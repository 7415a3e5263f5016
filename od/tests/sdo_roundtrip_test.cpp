// SdoClient <-> SdoServer over a simulated bus: every transfer mode and size, block sizes,
// lost and reordered segments, corrupted CRCs and timeouts. Also the CRC itself.
#include <gtest/gtest.h>

#include <string>

#include "od/crc16.hpp"
#include "sdo_test_support.hpp"

namespace stepnode::od {
namespace {

using namespace sdotest;
using Mode = SdoClient::Mode;

const Mode kModes[] = {Mode::Auto, Mode::Segmented, Mode::Block};
const size_t kSizes[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 5000};

std::string name(Mode mode) {
  return mode == Mode::Auto ? "auto" : mode == Mode::Segmented ? "segmented" : "block";
}

TEST(SdoCrc16, MatchesTheXmodemCheckValue) {
  const std::string check = "123456789";
  Bytes data(check.begin(), check.end());
  EXPECT_EQ(crc16_ccitt(data), 0x31C3);
  EXPECT_EQ(crc16_ccitt({}), 0x0000);
  // Incremental: the CRC of a prefix seeds the rest.
  uint16_t first = crc16_ccitt(std::span(data).first(4));
  EXPECT_EQ(crc16_ccitt(std::span(data).subspan(4), first), 0x31C3);
}

TEST(SdoRoundTrip, UploadEveryModeAndSize) {
  for (Mode mode : kModes) {
    for (size_t size : kSizes) {
      SCOPED_TRACE(name(mode) + " " + std::to_string(size));
      Link link;
      link.dict.set(kDomain, 0, pattern(size, 3));
      const SdoResult& r = link.upload(kDomain, 0, mode);
      EXPECT_TRUE(r.ok()) << abort_text(r.abort);
      EXPECT_EQ(r.data, pattern(size, 3));
      EXPECT_FALSE(link.server.busy());
      // Which protocol ran: expedited for 1..4 bytes, block above the client's pst (4).
      const bool expedited = size >= 1 && size <= 4;
      const uint8_t answer = link.first(kTx).data[0];
      EXPECT_EQ((answer & 0xF3) == 0x43, expedited);
      EXPECT_EQ(answer == 0xC6, mode == Mode::Block && size > 4);
    }
  }
}

TEST(SdoRoundTrip, DownloadEveryModeAndSize) {
  for (Mode mode : kModes) {
    for (size_t size : kSizes) {
      SCOPED_TRACE(name(mode) + " " + std::to_string(size));
      Link link;
      const SdoResult& r = link.download(kDomain, 0, pattern(size, 9), mode);
      EXPECT_TRUE(r.ok()) << abort_text(r.abort);
      EXPECT_TRUE(r.data.empty());
      EXPECT_EQ(link.dict.value(kDomain, 0), pattern(size, 9));
      EXPECT_FALSE(link.server.busy());
      const bool expedited = mode == Mode::Auto && size >= 1 && size <= 4;
      const uint8_t initiate = link.first(kRx).data[0];
      EXPECT_EQ((initiate & 0xF3) == 0x23, expedited);
      EXPECT_EQ(initiate == 0xC6, mode == Mode::Block);
    }
  }
}

TEST(SdoRoundTrip, TypedEntriesInEveryMode) {
  for (Mode mode : kModes) {
    SCOPED_TRACE(name(mode));
    Link link;
    EXPECT_TRUE(link.download(kU8, 0, encode<uint8_t>(42), mode).ok());
    EXPECT_TRUE(link.download(kU16, 0, encode<uint16_t>(0xABCD), mode).ok());
    EXPECT_TRUE(link.download(kU32, 0, encode<uint32_t>(0xDEADBEEF), mode).ok());
    EXPECT_TRUE(link.download(kI32, 0, encode<int32_t>(-999), mode).ok());
    EXPECT_TRUE(link.download(kU64, 0, encode<uint64_t>(0x0102030405060708), mode).ok());
    EXPECT_TRUE(
        link.download(kString, 0, encode_string("thirty characters, not one mor"), mode).ok());
    EXPECT_EQ(link.upload(kU8, 0, mode).data, encode<uint8_t>(42));
    EXPECT_EQ(link.upload(kU16, 0, mode).data, encode<uint16_t>(0xABCD));
    EXPECT_EQ(link.upload(kU32, 0, mode).data, encode<uint32_t>(0xDEADBEEF));
    EXPECT_EQ(link.upload(kI32, 0, mode).data, encode<int32_t>(-999));
    EXPECT_EQ(link.upload(kU64, 0, mode).data, encode<uint64_t>(0x0102030405060708));
    EXPECT_EQ(link.upload(kString, 0, mode).data, encode_string("thirty characters, not one mor"));
  }
}

TEST(SdoRoundTrip, ServerRefusalsReachTheClient) {
  for (Mode mode : kModes) {
    SCOPED_TRACE(name(mode));
    Link link;
    const SdoResult& r1 = link.download(kU8, 0, encode<uint8_t>(101), mode);
    EXPECT_EQ(r1.abort, SdoAbort::ValueTooHigh);
    EXPECT_TRUE(r1.aborted_by_server);
    EXPECT_EQ(link.download(kString, 0, Bytes(31, 'x'), mode).abort, SdoAbort::LengthTooHigh);
    EXPECT_EQ(link.download(kU32, 0, Bytes(2, 1), mode).abort, SdoAbort::LengthTooLow);
    EXPECT_EQ(link.download(kRo, 0, Bytes(4, 1), mode).abort, SdoAbort::ReadOnly);
    EXPECT_EQ(link.upload(kWo, 0, mode).abort, SdoAbort::WriteOnly);
    EXPECT_EQ(link.upload(kMissing, 0, mode).abort, SdoAbort::NoObject);
    EXPECT_EQ(link.upload(kRecord, 9, mode).abort, SdoAbort::NoSubindex);
    EXPECT_FALSE(link.server.busy());
  }
}

TEST(SdoRoundTrip, BlockSizes) {
  for (uint8_t blksize : {1, 7, 127}) {
    for (size_t size : {size_t{0}, size_t{5}, size_t{7}, size_t{8}, size_t{49}, size_t{50},
                        size_t{889}, size_t{890}, size_t{5000}}) {
      SCOPED_TRACE(std::to_string(blksize) + " " + std::to_string(size));
      Link link;
      link.server.set_block_size(blksize);
      link.client.set_block_size(blksize);
      EXPECT_TRUE(link.download(kDomain, 0, pattern(size, 1), Mode::Block).ok());
      EXPECT_EQ(link.dict.value(kDomain, 0), pattern(size, 1));
      const size_t segments = std::max<size_t>(1, (size + 6) / 7);
      const size_t sub_blocks = (segments + blksize - 1) / blksize;
      EXPECT_EQ(link.count(kTx, 0xA2), sub_blocks);  // one ack per sub-block, no repeats
      link.dict.set(kDomain, 0, pattern(size, 2));
      link.log.clear();
      const SdoResult& r = link.upload(kDomain, 0, Mode::Block);
      EXPECT_TRUE(r.ok());
      EXPECT_EQ(r.data, pattern(size, 2));
      if (size > 4) {
        EXPECT_EQ(link.count(kRx, 0xA2), sub_blocks);
      }
    }
  }
}

// The first sub-block of a block transfer, as the sending side emits it.
bool first_sub_block(const std::vector<CanFrame>& out, int& seen) {
  return out.size() > 5 && (out[0].data[0] & 0x7F) == 1 && seen++ == 0;
}

TEST(SdoRoundTrip, BlockDownloadRepeatsAfterAReorderedSegment) {
  Link link;
  int seen = 0;
  link.client_filter = [&](std::vector<CanFrame>& out) {
    if (first_sub_block(out, seen)) std::swap(out[2], out[3]);  // seqno 1, 2, 4, 3, 5, ...
  };
  EXPECT_TRUE(link.download(kDomain, 0, pattern(5000, 4), Mode::Block).ok());
  EXPECT_EQ(link.dict.value(kDomain, 0), pattern(5000, 4));
  // 715 segments: the gap ack confirms 2, then the other 713 go in sub-blocks of 127.
  EXPECT_EQ(link.count(kTx, 0xA2), 1u + (715 - 2 + 126) / 127);
  CanFrame first_ack;
  for (const auto& f : link.log)
    if (f.id == kTx && f.data[0] == 0xA2) {
      first_ack = f;
      break;
    }
  EXPECT_EQ(first_ack, rsp({0xA2, 2, 127, 0, 0, 0, 0, 0}));
}

TEST(SdoRoundTrip, BlockDownloadRepeatsAfterADroppedSegment) {
  Link link;
  link.server.set_block_size(20);
  int seen = 0;
  link.client_filter = [&](std::vector<CanFrame>& out) {
    if (first_sub_block(out, seen)) out.erase(out.begin() + 9);  // seqno 10 lost
  };
  EXPECT_TRUE(link.download(kDomain, 0, pattern(5000, 5), Mode::Block).ok());
  EXPECT_EQ(link.dict.value(kDomain, 0), pattern(5000, 5));
  EXPECT_GE(link.count(kTx, 0xA2), 1u);
  bool acked_nine = false;
  for (const auto& f : link.log) acked_nine |= f == rsp({0xA2, 9, 20, 0, 0, 0, 0, 0});
  EXPECT_TRUE(acked_nine);
}

TEST(SdoRoundTrip, BlockTransfersSurviveALostFirstOrLastSegment) {
  for (bool first : {true, false}) {
    SCOPED_TRACE(first ? "first" : "last");
    Link link;
    int seen = 0;
    link.client_filter = [&](std::vector<CanFrame>& out) {
      if (first_sub_block(out, seen)) out.erase(first ? out.begin() : out.end() - 1);
    };
    EXPECT_TRUE(link.download(kDomain, 0, pattern(300, 6), Mode::Block).ok());
    EXPECT_EQ(link.dict.value(kDomain, 0), pattern(300, 6));
    // The stalled sub-block was acknowledged by the server's sub-block timer.
    EXPECT_EQ(link.count(kTx, 0xA2), 2u);
  }
}

TEST(SdoRoundTrip, BlockUploadRepeatsAfterReorderedAndDroppedSegments) {
  Link link;
  link.client.set_block_size(30);
  int seen = 0;
  link.server_filter = [&](std::vector<CanFrame>& out) {
    if (!first_sub_block(out, seen)) return;
    std::swap(out[5], out[6]);
    out.erase(out.begin() + 20);
  };
  link.dict.set(kDomain, 0, pattern(5000, 7));
  const SdoResult& r = link.upload(kDomain, 0, Mode::Block);
  EXPECT_TRUE(r.ok()) << abort_text(r.abort);
  EXPECT_EQ(r.data, pattern(5000, 7));
  bool acked_five = false;
  for (const auto& f : link.log) acked_five |= f == req({0xA2, 5, 30, 0, 0, 0, 0, 0});
  EXPECT_TRUE(acked_five);
}

// The end frame is alone in its batch and has ss/cs = 1 under command specifier 6.
void corrupt_end_crc(std::vector<CanFrame>& out) {
  if (out.size() == 1 && (out[0].data[0] & 0xE3) == 0xC1) out[0].data[1] ^= 0x40;
}

TEST(SdoRoundTrip, CorruptedCrcInBlockDownload) {
  Link link;
  link.client_filter = corrupt_end_crc;
  const SdoResult& r = link.download(kDomain, 0, pattern(1000, 8), Mode::Block);
  EXPECT_EQ(r.abort, SdoAbort::CrcError);
  EXPECT_TRUE(r.aborted_by_server);
  EXPECT_EQ(link.dict.value(kDomain, 0), pattern(100));
  EXPECT_FALSE(link.server.busy());
}

TEST(SdoRoundTrip, CorruptedCrcInBlockUpload) {
  Link link;
  link.server_filter = corrupt_end_crc;
  const SdoResult& r = link.upload(kDomain, 0, Mode::Block);
  EXPECT_EQ(r.abort, SdoAbort::CrcError);
  EXPECT_FALSE(r.aborted_by_server);
  EXPECT_TRUE(r.data.empty());
  EXPECT_EQ(link.count(kRx, 0x80), 1u);
  EXPECT_FALSE(link.server.busy());  // the client's abort ended it
}

TEST(SdoRoundTrip, ClientTimesOutWhenTheServerGoesQuiet) {
  Link link;
  link.server_filter = [](std::vector<CanFrame>& out) { out.clear(); };
  const SdoResult& r = link.download(kDomain, 0, pattern(100), Mode::Segmented);
  EXPECT_EQ(r.abort, SdoAbort::Timeout);
  EXPECT_FALSE(r.aborted_by_server);
  EXPECT_EQ(link.log.back(), abort_of(kRx, kDomain, 0, 0x05040000));
  EXPECT_FALSE(link.server.busy());  // the server got the client's abort
  EXPECT_GE(link.now, kTimeout);
}

TEST(SdoRoundTrip, ServerTimesOutWhenTheClientGoesQuiet) {
  Link link;
  link.server.set_timeout_us(kTimeout / 2);
  int batches = 0;
  link.client_filter = [&](std::vector<CanFrame>& out) {
    if (batches++ > 0) out.clear();  // only the initiate gets through
  };
  const SdoResult& r = link.upload(kDomain, 0, Mode::Segmented);
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(link.count(kTx, 0x80), 1u);
  EXPECT_EQ(r.abort, SdoAbort::Timeout);
  EXPECT_TRUE(r.aborted_by_server);
}

}  // namespace
}  // namespace stepnode::od
