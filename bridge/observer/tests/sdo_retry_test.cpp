// SDO failures during discovery are never fatal: each is counted in NodeHealth and the same
// read is tried again after a backoff that doubles from retry_initial_ms to retry_max_ms.
#include <gtest/gtest.h>

#include "bridge/observer/discovery_plan.hpp"
#include "bridge/observer/retry_backoff.hpp"
#include "test_bus.hpp"

namespace stepnode::bridge::test {
namespace {

// Start times (us) of the upload requests the observer sent.
std::vector<uint64_t> upload_starts(const TestBus& bus) {
  std::vector<uint64_t> t;
  for (size_t i = 0; i < bus.observer_sent.size(); ++i)
    if (bus.observer_sent[i].data[0] == 0x40) t.push_back(bus.observer_sent_at[i]);
  return t;
}

TEST(SdoRetry, SilentNodeIsRetriedWithDoublingBackoff) {
  ObserverConfig cfg;
  cfg.sdo_timeout_ms = 500;
  cfg.retry_initial_ms = 200;
  cfg.retry_max_ms = 1000;
  TestBus bus(cfg);
  FakeNode node({.id = 5, .axes = 1});
  node.silent = true;
  bus.add(node);
  bus.boot(node);
  bus.run_ms(6000);
  const auto starts = upload_starts(bus);
  ASSERT_GE(starts.size(), 5u);
  // timeout 500 ms + backoff 200, 400, 800, then capped at 1000.
  EXPECT_EQ(starts[1] - starts[0], 700'000u);
  EXPECT_EQ(starts[2] - starts[1], 900'000u);
  EXPECT_EQ(starts[3] - starts[2], 1'300'000u);
  EXPECT_EQ(starts[4] - starts[3], 1'500'000u);
  // The same read each time (0x1017, the first of the plan), aborted on timeout.
  for (const od::CanFrame& f : bus.observer_sent) {
    EXPECT_EQ(od::get_u16(&f.data[1]), 0x1017);
    if (f.data[0] == 0x80) {
      EXPECT_EQ(od::get_u32(&f.data[4]), 0x05040000u);
    }
  }
  // Every transfer whose timeout has passed is one failure.
  size_t timed_out = 0;
  for (uint64_t t : starts) timed_out += t + 500'000 <= bus.now_us ? 1 : 0;
  const NodeHealthSample h = bus.observer.node_health(5, bus.now_us);
  EXPECT_EQ(h.sdo_failures, timed_out);
  EXPECT_FALSE(h.discovered);
  ASSERT_NE(bus.sink.last_health(5), nullptr);
  EXPECT_GE(bus.sink.last_health(5)->sdo_failures, 4u) << "failures are published";

  // The node recovers: discovery completes, the count stays as history.
  node.silent = false;
  bus.run_ms(1600);
  const NodeHealthSample after = bus.observer.node_health(5, bus.now_us);
  EXPECT_TRUE(after.discovered);
  // The request in flight when it recovered had been dropped: one more timeout, then success.
  EXPECT_EQ(after.sdo_failures, h.sdo_failures + 1);
}

TEST(SdoRetry, AbortedReadsAreRetriedAndDiscoveryGoesOn) {
  TestBus bus;
  FakeNode node({.id = 5, .axes = 2});
  node.abort_next = 3;  // general error: transient, not "absent"
  bus.add(node);
  bus.boot(node);
  bus.run_ms(3000);
  const NodeHealthSample h = bus.observer.node_health(5, bus.now_us);
  EXPECT_TRUE(h.discovered);
  EXPECT_EQ(h.sdo_failures, 3u);
  EXPECT_EQ(h.axes, 2);
  EXPECT_EQ(h.device_name, "stepnode");
}

TEST(SdoRetry, AnotherMasterStartingMidTransferIsACollisionRetriedLater) {
  TestBus bus;
  FakeNode node({.id = 5, .axes = 1});
  node.hold = true;  // our first request stays unanswered for now
  bus.add(node);
  bus.boot(node);
  ASSERT_EQ(upload_starts(bus).size(), 1u);
  bus.master_start(5);
  bus.master_upload(0x1000, 0);  // another master talks to the node
  EXPECT_EQ(bus.observer.node_health(5, bus.now_us).sdo_failures, 1u);
  bus.release(node);  // the node answers both; neither confuses the bridge
  bus.run_ms(1000);
  const NodeHealthSample h = bus.observer.node_health(5, bus.now_us);
  EXPECT_TRUE(h.discovered);
  EXPECT_EQ(h.axes, 1);
  // No abort frame from the bridge: it would have ended the other master's transfer.
  for (const od::CanFrame& f : bus.observer_sent) EXPECT_NE(f.data[0], 0x80);
}

TEST(RetryBackoff, DoublesToTheMaximumAndResets) {
  RetryBackoff b(200, 1000);
  EXPECT_TRUE(b.ready(0));
  b.failed(0);
  EXPECT_EQ(b.delay_us(), 200'000u);
  EXPECT_FALSE(b.ready(199'999));
  EXPECT_TRUE(b.ready(200'000));
  b.failed(0);
  b.failed(0);
  EXPECT_EQ(b.delay_us(), 800'000u);
  b.failed(0);
  EXPECT_EQ(b.delay_us(), 1'000'000u);
  b.reset();
  EXPECT_TRUE(b.ready(0));
  b.failed(0);
  EXPECT_EQ(b.delay_us(), 200'000u);
}

TEST(DiscoveryPlan, AbsentVersusFailed) {
  od::SdoResult r;
  EXPECT_EQ(classify(r), ReadOutcome::Value);
  r.abort = od::SdoAbort::NoObject;
  r.aborted_by_server = true;
  EXPECT_EQ(classify(r), ReadOutcome::Absent);
  r.abort = od::SdoAbort::NoSubindex;
  EXPECT_EQ(classify(r), ReadOutcome::Absent);
  r.abort = od::SdoAbort::WriteOnly;
  EXPECT_EQ(classify(r), ReadOutcome::Absent);
  r.abort = od::SdoAbort::DeviceState;
  EXPECT_EQ(classify(r), ReadOutcome::Failed);
  r.abort = od::SdoAbort::Timeout;
  r.aborted_by_server = false;
  EXPECT_EQ(classify(r), ReadOutcome::Failed);
}

TEST(DiscoveryPlan, FailedReadIsRepeatedAbsentMovesOn) {
  DiscoveryPlan p;
  EXPECT_EQ(p.next(), (SdoRead{0x1017, 0}));
  od::SdoResult timeout;
  timeout.abort = od::SdoAbort::Timeout;
  EXPECT_EQ(p.on_result(timeout), ReadOutcome::Failed);
  EXPECT_EQ(p.next(), (SdoRead{0x1017, 0}));
  od::SdoResult none;
  none.abort = od::SdoAbort::NoObject;
  none.aborted_by_server = true;
  p.on_result(none);
  EXPECT_EQ(p.next(), (SdoRead{0x1000, 0}));
  p.on_result(none);  // no device type: nothing says CiA 402
  EXPECT_EQ(p.next(), (SdoRead{0x1018, 1}));
  p.on_result(none);  // no identity at all: straight to the name
  EXPECT_EQ(p.next(), (SdoRead{0x1008, 0}));
  p.on_result(none);
  EXPECT_TRUE(p.finished()) << "not a stepnode: no axis blocks, no TPDOs";
  EXPECT_FALSE(p.info().is_stepnode());
}

}  // namespace
}  // namespace stepnode::bridge::test
