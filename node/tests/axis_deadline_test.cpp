// Issue 13: a moving axis in a node woken only at its own deadlines reacts to an input at
// the step that made the edge. A jog at about 200 steps/s (one step every 5 ms, sparser than the
// 1 ms wake period) runs into the upper limit switch (SPM30 3.3.1: an end limit stops
// motion in its direction): the status TPDO with %I3 goes out at that step's own instant,
// and the node, idle again, wakes once more for STANDBY AUTO's power-off, then not at all.
#include <gtest/gtest.h>

#include "node/profiles/horner/bits.hpp"
#include "node/profiles/horner/objects.hpp"
#include "node/profiles/sim/objects.hpp"
#include "node/tests/event_driven.hpp"

namespace stepnode::node::test {
namespace {

constexpr uint32_t kTpdo1 = 0x180 + 5;  // status bits (U16), motor position (I32)

class AxisDeadlineTest : public EventDrivenHarness {
 protected:
  void SetUp() override {
    EventDrivenHarness::SetUp();
    ASSERT_EQ(sdo_write(0x1017, 0, 0, 2), 0u);
    nmt(0x01);
  }
};

TEST_F(AxisDeadlineTest, TheLimitSwitchReactionGoesOutAtTheStepThatReachedIt) {
  using namespace horner::obj;
  const uint16_t switches = sim::obj::index(0, sim::obj::kSwitches);
  const uint16_t p = index(0, kProfile), command = index(0, kCommandBits);
  ASSERT_EQ(sdo_write(switches, sim::switches_sub::kUpperLimit, 10), 0u);  // 10 steps up
  // Base 20 and running 21 units of 10 steps/s (divisor 60): about 200 steps/s, the ramp
  // between them 1 ms long.
  ASSERT_EQ(sdo_write(p, horner::profile_sub::kVelocityDivisor, 60, 2), 0u);
  ASSERT_EQ(sdo_write(p, horner::profile_sub::kBaseVelocity, 20, 2), 0u);
  ASSERT_EQ(sdo_write(p, horner::profile_sub::kRunningVelocity, 21, 2), 0u);
  ASSERT_EQ(sdo_write(p, horner::profile_sub::kAcceleration, 1, 2), 0u);
  ASSERT_EQ(sdo_write(command, 0, 1u << 13, 2), 0u);  // clear errors
  ASSERT_EQ(sdo_write(command, 0, 0, 2), 0u);
  ASSERT_EQ(sdo_write(command, 0, 1u << 5, 2), 0u);  // jog up
  clear_sent();
  run_event_driven(t + 1'000'000);
  const sim::AxisMachine& m = device->machine().axes[0];
  ASSERT_EQ(m.position(), 10) << "stopped on the limit";
  const uint64_t edge = device->axes().micros_at_or_after(m.last_step_time());
  std::optional<uint64_t> reported;
  for (size_t i = 0; i < sent.size() && !reported; ++i)
    if (sent[i].id == kTpdo1 && (od::get_u16(sent[i].data.data()) & horner::status::kUpperLimit))
      reported = sent_at[i];
  ASSERT_TRUE(reported) << "%I3 in the status TPDO";
  EXPECT_EQ(*reported, edge);
  EXPECT_FALSE(device->axes().core(0).busy());
  // Idle again, no heartbeat: only the HP channel's STANDBY AUTO (the default) is left,
  // powering the motor off one second after the move that ended at the edge (HP 3-6).
  EXPECT_EQ(deadline(), edge + 1'000'000);
  run_event_driven(edge + 1'000'000);
  EXPECT_EQ(deadline(), kNoDeadline) << "nothing to wake for";
}

}  // namespace
}  // namespace stepnode::node::test
