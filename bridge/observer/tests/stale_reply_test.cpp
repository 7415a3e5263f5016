// Issue 13's 0x06040043: a late answer naming another object must not end the transfer in
// progress. CiA 301 7.2.4.3.3: an expedited upload response repeats the request's index
// and sub-index, so an answer naming another object is not this transfer's answer.
#include <gtest/gtest.h>

#include "bridge/observer/sdo_channel.hpp"
#include "bridge/observer/transfer_pacer.hpp"

namespace stepnode::bridge {
namespace {

TEST(StaleReply, AnAnswerNamingAnotherObjectIsIgnoredAndTheTransferGoesOn) {
  SdoChannel ch(5, 500'000, 300'000);
  std::vector<od::CanFrame> out;
  ch.start_upload(0x1000, 0, 1000, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], od::CanFrame(0x605, {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0}));
  out.clear();
  // The answer to an earlier read of 0x1017 (timed out), arriving now: 0x4B = expedited,
  // 2 bytes, 100 ms.
  auto ev = ch.on_frame(od::CanFrame(0x585, {0x4B, 0x17, 0x10, 0x00, 100, 0, 0, 0}), 2000, out);
  EXPECT_FALSE(ev.completed);
  EXPECT_FALSE(ev.collision);
  EXPECT_TRUE(out.empty()) << "no abort 0x06040043 sent";
  // Our own answer: 0x43 = expedited, 4 bytes, device type 0x00020192.
  ev =
      ch.on_frame(od::CanFrame(0x585, {0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00}), 3000, out);
  ASSERT_TRUE(ev.completed);
  EXPECT_TRUE(ch.result().ok());
  EXPECT_EQ(ch.result().data, (od::Bytes{0x92, 0x01, 0x02, 0x00}));
  EXPECT_EQ(ch.result().foreign_replies, 1u);
}

TEST(TransferPacer, BoundsTransfersInFlightAndTheirRate) {
  TransferPacer p(2, 1000);  // 2 in flight; one start per ms on average, bursts of 2
  EXPECT_TRUE(p.may_start(0));
  p.started(0);
  EXPECT_TRUE(p.may_start(0));
  p.started(0);
  EXPECT_FALSE(p.may_start(0)) << "two in flight";
  p.ended();
  p.ended();
  EXPECT_FALSE(p.may_start(0)) << "none in flight, but two starts at t = 0 are the burst";
  EXPECT_FALSE(p.may_start(999));
  EXPECT_TRUE(p.may_start(1000)) << "one per ms after the burst";
  p.started(1000);
  p.ended();
  EXPECT_FALSE(p.may_start(1999));
  EXPECT_TRUE(p.may_start(2000));
  EXPECT_EQ(p.starts(), 3u);
  TransferPacer unlimited(1, 0);
  unlimited.started(0);
  EXPECT_FALSE(unlimited.may_start(0)) << "one in flight";
  unlimited.ended();
  EXPECT_TRUE(unlimited.may_start(0)) << "rate 0: only the in-flight bound";
}

}  // namespace
}  // namespace stepnode::bridge
