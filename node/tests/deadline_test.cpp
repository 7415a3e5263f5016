// Event-driven timing (issue 13): the deadline each service reports against its CiA 301
// rule, in virtual time, and a node run only at its own deadlines doing what the rule says.
#include <gtest/gtest.h>

#include "node/profiles/horner/objects.hpp"
#include "node/profiles/sim/objects.hpp"
#include "node/tests/event_driven.hpp"

namespace stepnode::node::test {
namespace {

class DeadlineTest : public EventDrivenHarness {};

TEST_F(DeadlineTest, AnIdleNodeWithoutHeartbeatHasNoDeadline) {
  ASSERT_EQ(sdo_write(0x1017, 0, 0, 2), 0u);
  device->on_tick(t);
  EXPECT_EQ(device->next_deadline_us(t), kNoDeadline);
  nmt(0x01);  // operational: default TPDOs sent once, nothing timed after
  device->on_tick(t);
  EXPECT_EQ(device->next_deadline_us(t), kNoDeadline);
}

TEST_F(DeadlineTest, HeartbeatProducerIsLastSentPlusProducerTime) {
  ASSERT_EQ(sdo_write(0x1017, 0, 100, 2), 0u);
  const uint64_t start = t;
  clear_sent();
  // Ten heartbeats in one second, each 0x1017 = 100 ms after the last, and nothing else.
  EXPECT_EQ(run_event_driven(start + 1'000'000), 10u);
  std::vector<uint64_t> at = times_of(kHeartbeatId);
  ASSERT_EQ(at.size(), 10u);
  for (size_t i = 1; i < at.size(); ++i) EXPECT_EQ(at[i] - at[i - 1], 100'000u);
}

TEST_F(DeadlineTest, HeartbeatConsumerTimesOutJustAfterTheConsumerTime) {
  ASSERT_EQ(sdo_write(0x1017, 0, 0, 2), 0u);
  ASSERT_EQ(sdo_write(0x1016, 1, (9u << 16) | 150u), 0u);  // node 9, 150 ms
  EXPECT_EQ(device->next_deadline_us(t), kNoDeadline)
      << "monitoring starts with the first heartbeat";
  frame(CanFrame(0x709, {0x05}));
  const uint64_t heard = t;
  // Late is "more than" the consumer time: the first moment is 150 ms + 1 us later.
  EXPECT_EQ(device->next_deadline_us(t), heard + 150'001);
  clear_sent();
  run_event_driven(heard + 200'000);
  // The heartbeat EMCY first (the lost master's axis reaction may follow at once).
  std::vector<uint64_t> at = times_of(kEmcyId);
  ASSERT_GE(at.size(), 1u);
  EXPECT_EQ(emcy_code(with_id(kEmcyId)[0]), 0x8130);
  EXPECT_EQ(at[0], heard + 150'001);
}

TEST_F(DeadlineTest, LifeGuardingDeadlineIsTheNodeLifeTimeAfterTheLastRequest) {
  ASSERT_EQ(sdo_write(0x1017, 0, 0, 2), 0u);
  ASSERT_EQ(sdo_write(0x100C, 0, 100, 2), 0u);  // guard time 100 ms
  ASSERT_EQ(sdo_write(0x100D, 0, 3, 1), 0u);    // life time factor 3: 300 ms
  EXPECT_EQ(device->next_deadline_us(t), kNoDeadline)
      << "life guarding starts with the first request";
  CanFrame rtr(kHeartbeatId, {});
  rtr.rtr = true;
  frame(rtr);
  EXPECT_EQ(device->next_deadline_us(t), t + 300'001);
}

TEST_F(DeadlineTest, TpdoEventTimerAndInhibitTime) {
  nmt(0x01);
  // TPDO 1 on change (254) of the error register, inhibit 10 ms (100 x 100 us), event 50 ms.
  map_tpdo(0, {0x10010008}, 254, 100, 50);
  device->on_tick(t);
  const uint64_t sent = times_of(0x180 + kId).back();
  EXPECT_EQ(device->next_deadline_us(t), sent + 50'000);
  clear_sent();
  run_event_driven(sent + 50'000 + 1);
  EXPECT_EQ(times_of(0x180 + kId), std::vector<uint64_t>{sent + 50'000});
}

TEST_F(DeadlineTest, TpdoChangeHeldByTheInhibitTimeGoesOutAtItsEnd) {
  ASSERT_EQ(sdo_write(0x1017, 0, 0, 2), 0u);
  nmt(0x01);
  map_tpdo(0, {0x10010008}, 254, 1000, 0);  // 0x1001 on change, inhibit 100 ms, no event timer
  device->on_tick(t);
  const uint64_t first = times_of(0x180 + kId).back();
  t = first + 10'000;
  node->emcy().raise(0xFF01, 0x80, {}, t);
  device->on_tick(t);
  EXPECT_EQ(deadline(), first + 100'000) << "the change waits for the inhibit time";
  clear_sent();
  run_event_driven(first + 200'000);
  EXPECT_EQ(times_of(0x180 + kId), std::vector<uint64_t>{first + 100'000});
  EXPECT_EQ(deadline(), kNoDeadline);
}

TEST_F(DeadlineTest, TpdoChangeUndoneWithinTheInhibitTimeLeavesNothingTimed) {
  // Found in review: the change stayed held, its deadline max(now, inhibit end) = now for
  // ever after the inhibit time, and the loop woke at once on every turn.
  ASSERT_EQ(sdo_write(0x1017, 0, 0, 2), 0u);
  nmt(0x01);
  map_tpdo(0, {0x10010008}, 254, 1000, 0);
  device->on_tick(t);
  const uint64_t first = times_of(0x180 + kId).back();
  t = first + 10'000;
  node->emcy().raise(0xFF01, 0x80, {}, t);  // 0x1001 changes: held
  device->on_tick(t);
  t = first + 20'000;
  node->emcy().clear(0xFF01, t);  // and back to what was sent
  device->on_tick(t);
  EXPECT_EQ(deadline(), kNoDeadline) << "nothing is held any more";
  clear_sent();
  run_event_driven(first + 300'000);  // fails its own check if a deadline stays at now
  EXPECT_TRUE(times_of(0x180 + kId).empty()) << "the value last sent is still the value";
}

TEST_F(DeadlineTest, RpdoDeadlineIsLastFramePlusEventTime) {
  nmt(0x01);
  map_rpdo(0, {0x20000010}, 255, 20);  // RPDO 1: the Horner command word of axis 1, 20 ms
  frame(CanFrame(0x200 + kId, {0x00, 0x00}));
  const uint64_t rx = t;
  EXPECT_LE(device->next_deadline_us(t), rx + 20'001);
  clear_sent();
  run_event_driven(rx + 25'000);
  std::vector<uint64_t> at = times_of(kEmcyId);
  ASSERT_EQ(at.size(), 1u);
  EXPECT_EQ(emcy_code(with_id(kEmcyId)[0]), 0x8250);
  EXPECT_EQ(at[0], rx + 20'001);
}

TEST_F(DeadlineTest, SyncProducerWakesEveryCommunicationCyclePeriod) {
  ASSERT_EQ(sdo_write(0x1006, 0, 10'000), 0u);  // 10 ms
  ASSERT_EQ(sdo_write(0x1005, 0, 0x40000080), 0u);
  device->on_tick(t);  // the producer starts its period
  const uint64_t begun = t;
  clear_sent();
  EXPECT_EQ(run_event_driven(begun + 100'000), 10u);
  std::vector<uint64_t> at = times_of(0x80);
  ASSERT_EQ(at.size(), 10u);
  for (size_t i = 0; i < at.size(); ++i) EXPECT_EQ(at[i], begun + 10'000 * (i + 1));
}

TEST_F(DeadlineTest, EmcyWaitsForTheInhibitTime) {
  ASSERT_EQ(sdo_write(0x1015, 0, 50, 2), 0u);  // 5 ms
  node->emcy().raise(0xFF01, 0x80, {}, t);
  node->emcy().raise(0xFF02, 0x80, {}, t);
  const uint64_t first = times_of(kEmcyId).back();
  EXPECT_EQ(device->next_deadline_us(t), first + 5'000);
  run_event_driven(first + 6'000);
  EXPECT_EQ(times_of(kEmcyId).back(), first + 5'000);
}

TEST_F(DeadlineTest, AMovingAxisWakesTheNodeUntilItsMoveEnds) {
  const uint16_t switches = sim::obj::index(0, sim::obj::kSwitches);
  const uint16_t command = horner::obj::index(0, horner::obj::kCommandBits);
  ASSERT_EQ(sdo_write(0x1017, 0, 1000, 2), 0u);
  ASSERT_EQ(sdo_write(switches, sim::switches_sub::kLowerLimitEnabled, 0, 1), 0u);  // no limits
  ASSERT_EQ(sdo_write(switches, sim::switches_sub::kUpperLimitEnabled, 0, 1), 0u);
  ASSERT_EQ(sdo_write(command, 0, 1u << 13, 2), 0u);  // clear errors
  ASSERT_EQ(sdo_write(command, 0, 0, 2), 0u);
  ASSERT_EQ(sdo_write(command, 0, 1u << 5, 2), 0u);  // jog up
  const uint64_t d = device->next_deadline_us(t);
  EXPECT_GE(d, t + kPollUs) << "no more often than the poll period";
  EXPECT_LT(d, t + 1'000'000) << "before the next heartbeat: the axis needs it";
  ASSERT_EQ(sdo_write(command, 0, 0, 2), 0u);  // released: the jog ramps down and ends
  run_event_driven(t + 2'000'000);
  EXPECT_FALSE(device->axes().core(0).busy());
  const uint64_t hb = times_of(kHeartbeatId).back();
  EXPECT_EQ(device->next_deadline_us(t), hb + 1'000'000) << "idle again: only the heartbeat";
}

}  // namespace
}  // namespace stepnode::node::test
