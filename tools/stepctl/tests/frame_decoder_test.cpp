// `stepctl watch`'s words for frames whose layout depends on more than their COB-ID (found
// in review): a node guarding answer (the toggle in bit 7) and the segments of an SDO block
// transfer (no command specifier: the transfer's state says what they are).
#include <gtest/gtest.h>

#include <string>

#include "tools/stepctl/frame_decoder.hpp"

namespace stepnode::tools {
namespace {

const ObjectCatalog& catalog() {
  static const ObjectCatalog c("");
  return c;
}

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// CiA 301 7.2.8.3.2: the answer's bits 6..0 are the state, bit 7 the toggle.
TEST(WatchWords, ANodeGuardingAnswerIsItsStateWhateverTheToggle) {
  FrameDecoder d(catalog());
  EXPECT_TRUE(has(d.describe(od::CanFrame(0x705, {0x85})), ": operational"));
  EXPECT_TRUE(has(d.describe(od::CanFrame(0x705, {0xFF})), ": pre-operational"));
  EXPECT_TRUE(has(d.describe(od::CanFrame(0x705, {0x84})), ": stopped"));
  EXPECT_TRUE(has(d.describe(od::CanFrame(0x705, {0x04})), ": stopped"));
}

// 7.2.4.3.10-13: initiate, the client's segments (c | seqno, 7 bytes), the server's ack,
// the end. A segment whose bytes look like an expedited download is a segment.
TEST(WatchWords, ABlockDownloadsSegmentsAreSegments) {
  FrameDecoder d(catalog());
  EXPECT_TRUE(has(d.describe(od::CanFrame(0x605, {0xC6, 0x00, 0x20, 0x00, 0x0E, 0, 0, 0})),
                  "block download"));
  d.describe(od::CanFrame(0x585, {0xA4, 0x00, 0x20, 0x00, 0x7F, 0, 0, 0}));  // blksize 127
  const std::string seg =
      d.describe(od::CanFrame(0x605, {0x01, 0x23, 0x18, 0x10, 0x01, 0x11, 0x22, 0x33}));
  EXPECT_TRUE(has(seg, "block segment 1: 23 18 10 01 11 22 33")) << seg;
  const std::string last = d.describe(od::CanFrame(0x605, {0x82, 0x44, 0x55, 0x66, 0x77, 0, 0, 0}));
  EXPECT_TRUE(has(last, "block segment 2, last")) << last;
  EXPECT_TRUE(has(d.describe(od::CanFrame(0x585, {0xA2, 0x02, 0x7F, 0, 0, 0, 0, 0})),
                  "block ack: ackseq 2"));
  EXPECT_TRUE(has(d.describe(od::CanFrame(0x605, {0xC9, 0x12, 0x34, 0, 0, 0, 0, 0})),
                  "block download end"));
  d.describe(od::CanFrame(0x585, {0xA1, 0, 0, 0, 0, 0, 0, 0}));
  // The transfer is over: the same bytes are an expedited download again.
  EXPECT_TRUE(has(d.describe(od::CanFrame(0x605, {0x23, 0x18, 0x10, 0x01, 0x11, 0x22, 0x33, 0x44})),
                  "download 0x1018:01"));
}

// 7.2.4.3.14-17: the server's segments after the client's start, until the client's ack
// of the last; an abort ends the transfer.
TEST(WatchWords, ABlockUploadsSegmentsAreSegmentsUntilItEnds) {
  FrameDecoder d(catalog());
  d.describe(od::CanFrame(0x605, {0xA4, 0x08, 0x10, 0x00, 0x7F, 0x04, 0, 0}));  // initiate
  d.describe(od::CanFrame(0x585, {0xC6, 0x08, 0x10, 0x00, 0x08, 0, 0, 0}));     // 8 bytes
  d.describe(od::CanFrame(0x605, {0xA3, 0, 0, 0, 0, 0, 0, 0}));                 // start
  EXPECT_TRUE(has(d.describe(od::CanFrame(0x585, {0x01, 's', 't', 'e', 'p', 'n', 'o', 'd'})),
                  "block segment 1"));
  EXPECT_TRUE(
      has(d.describe(od::CanFrame(0x585, {0x82, 'e', 0, 0, 0, 0, 0, 0})), "block segment 2, last"));
  d.describe(od::CanFrame(0x605, {0xA2, 0x02, 0x7F, 0, 0, 0, 0, 0}));  // ack
  // The server's end request, the client's end response: then a response is a command.
  d.describe(od::CanFrame(0x585, {0xD9, 0x12, 0x34, 0, 0, 0, 0, 0}));
  d.describe(od::CanFrame(0x605, {0xA1, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_TRUE(has(d.describe(od::CanFrame(0x585, {0x4B, 0x17, 0x10, 0x00, 0xE8, 0x03, 0, 0})),
                  "upload 0x1017"));
  // An abort in the middle ends it too.
  d.describe(od::CanFrame(0x605, {0xA3, 0, 0, 0, 0, 0, 0, 0}));
  d.describe(od::CanFrame(0x605, {0x80, 0x08, 0x10, 0x00, 0, 0, 0x04, 0x05}));
  EXPECT_TRUE(has(d.describe(od::CanFrame(0x585, {0x4B, 0x17, 0x10, 0x00, 0xE8, 0x03, 0, 0})),
                  "upload 0x1017"));
}

}  // namespace
}  // namespace stepnode::tools
