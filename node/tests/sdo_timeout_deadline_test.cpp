// Issue 13: the SDO server's timeouts as deadlines. A transfer the client leaves open is
// aborted with 0x05040000 (CiA 301 7.2.4.3.17, SDO protocol timed out) exactly the SDO
// timeout after the client's last frame, in a node woken only at its own deadlines.
#include <gtest/gtest.h>

#include "node/tests/event_driven.hpp"
#include "od/value_codec.hpp"

namespace stepnode::node::test {
namespace {

constexpr uint64_t kTimeoutUs = 1'000'000;  // NodeOptions::sdo_timeout_us, the default

class SdoTimeoutDeadlineTest : public EventDrivenHarness {
 protected:
  void SetUp() override {
    EventDrivenHarness::SetUp();
    ASSERT_EQ(sdo_write(0x1017, 0, 0, 2), 0u);  // no heartbeat: only the SDO timer is due
    device->on_tick(t);
    ASSERT_EQ(deadline(), kNoDeadline);
    clear_sent();
  }
  // The abort frames of the server (scs 4) and when each went out.
  std::vector<std::pair<uint64_t, CanFrame>> aborts() const {
    std::vector<std::pair<uint64_t, CanFrame>> out;
    for (size_t i = 0; i < sent.size(); ++i)
      if (sent[i].id == kSdoTx && sent[i].data[0] == 0x80) out.push_back({sent_at[i], sent[i]});
    return out;
  }
};

TEST_F(SdoTimeoutDeadlineTest, SegmentedDownloadLeftOpenTimesOutAtTheTimeout) {
  // Initiate a segmented download of 0x1017 (ccs 1, s = 1, e = 0: 0x21, size 2), 7.2.4.3.3.
  frame(CanFrame(kSdoRx, {0x21, 0x17, 0x10, 0x00, 0x02, 0x00, 0x00, 0x00}));
  ASSERT_EQ(with_id(kSdoTx).size(), 1u);
  EXPECT_EQ(with_id(kSdoTx)[0].data[0], 0x60) << "initiate download response";
  const uint64_t last = t;
  EXPECT_EQ(deadline(), last + kTimeoutUs) << "the timeout instant, not a poll";
  run_event_driven(last + 2 * kTimeoutUs);
  const auto a = aborts();
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].first, last + kTimeoutUs);
  EXPECT_EQ(od::get_u16(&a[0].second.data[1]), 0x1017);
  EXPECT_EQ(a[0].second.data[3], 0);
  EXPECT_EQ(od::get_u32(&a[0].second.data[4]), 0x05040000u);
  EXPECT_EQ(deadline(), kNoDeadline) << "the transfer is over";
}

TEST_F(SdoTimeoutDeadlineTest, EachSegmentRestartsTheTimeout) {
  // A segmented upload of 0x1008 (the device name: longer than 4 bytes), 7.2.4.3.6.
  frame(CanFrame(kSdoRx, {0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0}));
  ASSERT_EQ(with_id(kSdoTx).size(), 1u);
  ASSERT_EQ(with_id(kSdoTx)[0].data[0] & 0xE3, 0x41) << "segmented, size indicated";
  run_event_driven(t + 600'000);
  EXPECT_TRUE(aborts().empty());
  frame(CanFrame(kSdoRx, {0x60, 0, 0, 0, 0, 0, 0, 0}));  // upload segment, toggle 0
  const uint64_t last = t;
  if ((with_id(kSdoTx).back().data[0] & 0x01) != 0) GTEST_SKIP() << "the name fits one segment";
  EXPECT_EQ(deadline(), last + kTimeoutUs);
  run_event_driven(last + 2 * kTimeoutUs);
  const auto a = aborts();
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].first, last + kTimeoutUs);
  EXPECT_EQ(od::get_u32(&a[0].second.data[4]), 0x05040000u);
}

TEST_F(SdoTimeoutDeadlineTest, StalledSubBlockIsAcknowledgedAtHalfTheTimeout) {
  // Block download of 0x1017 with CRC and size 2 (ccs 6, cc = 1, s = 1: 0xC6), 7.2.4.3.9.
  frame(CanFrame(kSdoRx, {0xC6, 0x17, 0x10, 0x00, 0x02, 0x00, 0x00, 0x00}));
  ASSERT_EQ(with_id(kSdoTx).size(), 1u);
  EXPECT_EQ(with_id(kSdoTx)[0].data[0], 0xA4) << "initiate block download response";
  const uint8_t blksize = with_id(kSdoTx)[0].data[4];
  ASSERT_GT(blksize, 1) << "segment 1 must not end the sub-block by itself";
  // Segment 1 of the sub-block, not the last: the sub-block stalls after it.
  frame(CanFrame(kSdoRx, {0x01, 0x00, 0x00, 0, 0, 0, 0, 0}));
  const uint64_t segment = t;
  ASSERT_EQ(with_id(kSdoTx).size(), 1u) << "no acknowledgement before the sub-block ends";
  EXPECT_EQ(deadline(), segment + kTimeoutUs / 2);
  run_event_driven(segment + 2 * kTimeoutUs);
  const std::vector<uint64_t> at = times_of(kSdoTx);
  ASSERT_EQ(at.size(), 3u) << "the stalled sub-block's acknowledgement, then the abort";
  EXPECT_EQ(with_id(kSdoTx)[1].data[0], 0xA2) << "block download response, ss = 2";
  EXPECT_EQ(with_id(kSdoTx)[1].data[1], 1) << "ackseq: segment 1 arrived";
  EXPECT_EQ(at[1], segment + kTimeoutUs / 2);
  EXPECT_EQ(with_id(kSdoTx)[2].data[0], 0x80);
  EXPECT_EQ(od::get_u32(&with_id(kSdoTx)[2].data[4]), 0x05040000u);
  EXPECT_EQ(at[2], segment + kTimeoutUs) << "the client's last frame + the timeout";
}

TEST_F(SdoTimeoutDeadlineTest, SecondChannelTimesOutOnItsOwnClock) {
  // Channel 0x1201 on 0x6A0/0x6B0 (client->server, server->client), 7.5.2.33.
  ASSERT_EQ(sdo_write(0x1201, 1, 0x6A0), 0u);
  ASSERT_EQ(sdo_write(0x1201, 2, 0x6B0), 0u);
  device->on_tick(t);
  frame(CanFrame(kSdoRx, {0x21, 0x17, 0x10, 0x00, 0x02, 0x00, 0x00, 0x00}));
  const uint64_t first = t;
  run_event_driven(t + 300'000);
  frame(CanFrame(0x6A0, {0x21, 0x17, 0x10, 0x00, 0x02, 0x00, 0x00, 0x00}));
  const uint64_t second = t;
  EXPECT_EQ(deadline(), first + kTimeoutUs) << "the earlier of the two";
  clear_sent();
  run_event_driven(second + 2 * kTimeoutUs);
  EXPECT_EQ(times_of(kSdoTx), std::vector<uint64_t>{first + kTimeoutUs});
  EXPECT_EQ(times_of(0x6B0), std::vector<uint64_t>{second + kTimeoutUs});
}

}  // namespace
}  // namespace stepnode::node::test
