// Issue 13: the HP 44714A channel's own timed work as deadlines, in a node woken only at its
// own deadlines: a triggered MOVE starts after its DELAY (manual 3-5: "the delay between
// the trigger and the start of the action") at exactly that instant, and STANDBY AUTO
// removes motor power one second after the last move (3-6), with no wake-up in between.
#include <gtest/gtest.h>

#include "node/profiles/hp44714a/objects.hpp"
#include "node/tests/event_driven.hpp"

namespace stepnode::node::test {
namespace {

using namespace hp44714a::obj;

class HpDeadlineTest : public EventDrivenHarness {
 protected:
  void SetUp() override {
    EventDrivenHarness::SetUp();
    ASSERT_EQ(sdo_write(0x1017, 0, 0, 2), 0u);  // no heartbeat: only the channel's work
    nmt(0x01);
    device->on_tick(t);
  }
  uint32_t move(double d, bool nowait) {
    EXPECT_EQ(put_int<uint8_t>(index(0, kMove), hp44714a::move_sub::kNowait, nowait ? 1 : 0), 0u);
    return put(index(0, kMove), hp44714a::move_sub::kRelative, d);
  }
  uint32_t trig(uint8_t mode) { return sdo_write(index(0, kTrig), 0, mode, 1); }
  int done() { return static_cast<int8_t>(*sdo_read(index(0, kDone), 0)); }
  const sim::AxisMachine& machine() { return device->machine().axes[0]; }
};

TEST_F(HpDeadlineTest, ATriggeredMoveStartsExactlyAfterItsDelay) {
  ASSERT_EQ(sdo_write(index(0, kDelay), 0, 5000, 2), 0u);  // DELAY 5 (s; the object is ms)
  ASSERT_EQ(trig(0), 0u);                                  // TRIG HOLD
  ASSERT_EQ(move(20, true), 0u);                           // MOVE 20 NOWAIT: waits
  EXPECT_EQ(deadline(), kNoDeadline) << "a job waiting for its trigger waits for a frame";
  ASSERT_EQ(trig(2), 0u);  // TRIG: the delay starts
  const uint64_t triggered = t;
  EXPECT_EQ(done(), -2) << "the delay runs";
  EXPECT_EQ(deadline(), triggered + 5'000'000) << "the DELAY's end, not a poll";
  EXPECT_EQ(run_event_driven(triggered + 5'000'000), 1u) << "one wake-up in the whole delay";
  EXPECT_EQ(machine().position(), 0) << "the first step comes one step period after";
  const std::optional<motion::Tick> first = device->axes().core(0).next_step_time();
  ASSERT_TRUE(first);
  EXPECT_EQ(device->axes().micros_at_or_after(*first), deadline()) << "then its first step";
}

TEST_F(HpDeadlineTest, StandbyAutoPowersOffOneSecondAfterTheLastMove) {
  const uint16_t out = index(0, kOutput);
  ASSERT_EQ(sdo_write(out, hp44714a::output_sub::kStandbyMode, 2, 1), 0u);  // STANDBY AUTO
  ASSERT_EQ(move(10, true), 0u);
  EXPECT_EQ(*sdo_read(out, hp44714a::output_sub::kMotorPowered), 1u);
  // Woken at its deadlines, one at a time, until the wake-up that ends the move.
  for (int guard = 0; guard < 100'000 && device->axes().core(0).busy(); ++guard) {
    t = deadline();
    ASSERT_NE(t, kNoDeadline);
    device->on_tick(t);
  }
  ASSERT_FALSE(device->axes().core(0).busy());
  ASSERT_NE(machine().position(), 0);
  const uint64_t ended = t;
  EXPECT_EQ(deadline(), ended + 1'000'000) << "the power-off, one second after the move";
  EXPECT_EQ(run_event_driven(ended + 999'999), 0u) << "nothing in between";
  EXPECT_EQ(*sdo_read(out, hp44714a::output_sub::kMotorPowered), 1u);
  EXPECT_EQ(run_event_driven(ended + 1'000'000), 1u);
  EXPECT_EQ(*sdo_read(out, hp44714a::output_sub::kMotorPowered), 0u);
  EXPECT_EQ(deadline(), kNoDeadline);
}

}  // namespace
}  // namespace stepnode::node::test
