// Issue 13: a CiA 402 drive in operation enabled is no longer polled. Its timed work is a
// deadline: target reached (6041h bit 10) once the position has been inside the position
// window (6067h) for the position window time (6068h, CiA 402-2 6.2.3), exactly then, in a
// node woken only at its own deadlines; and an enabled drive standing still wakes nothing.
#include <gtest/gtest.h>

#include "node/tests/event_driven.hpp"

namespace stepnode::node::test {
namespace {

constexpr uint32_t kTpdo1 = 0x180 + 5;  // 6041h, 6061h (CiA 402 default TPDO1)

class Cia402DeadlineTest : public EventDrivenHarness {
 protected:
  void SetUp() override {
    make(DeviceLayout{.axes = 1, .horner = false, .hp = false, .user = false, .cia402 = true});
    ASSERT_EQ(sdo_write(0x1017, 0, 0, 2), 0u);  // no heartbeat: only the drive's own work
    nmt(0x01);
    ASSERT_EQ(sdo_write(0x6060, 0, 1, 1), 0u);  // modes of operation: profile position
    for (uint16_t cw : {0x0006, 0x0007, 0x000F}) ASSERT_EQ(sdo_write(0x6040, 0, cw, 2), 0u);
    ASSERT_EQ(*sdo_read(0x6041, 0) & 0x6F, 0x27u) << "operation enabled";
    device->on_tick(t);
  }
  uint16_t statusword_of(const CanFrame& f) const {
    return static_cast<uint16_t>(f.data[0] | f.data[1] << 8);
  }
};

TEST_F(Cia402DeadlineTest, AnEnabledDriveStandingStillWakesNothing) {
  EXPECT_EQ(deadline(), kNoDeadline);
  EXPECT_EQ(run_event_driven(t + 5'000'000), 0u) << "before issue 13: 5,000 polls";
}

TEST_F(Cia402DeadlineTest, TargetReachedComesThePositionWindowTimeAfterTheLastStep) {
  ASSERT_EQ(sdo_write(0x6068, 0, 50, 2), 0u);  // position window time 50 ms
  ASSERT_EQ(sdo_write(0x6081, 0, 2000), 0u);   // profile velocity, steps/s
  ASSERT_EQ(sdo_write(0x6083, 0, 20000), 0u);
  ASSERT_EQ(sdo_write(0x6084, 0, 20000), 0u);
  ASSERT_EQ(sdo_write(0x607A, 0, 300), 0u);
  ASSERT_EQ(sdo_write(0x6040, 0, 0x001F, 2), 0u);  // new set-point (bit 4)
  ASSERT_EQ(sdo_write(0x6040, 0, 0x000F, 2), 0u);
  clear_sent();
  run_event_driven(t + 2'000'000);
  ASSERT_EQ(*sdo_read(0x6064, 0), 300u);
  const sim::AxisMachine& m = device->machine().axes[0];
  // 6068h in ticks of 4.9152 MHz (50 ms = 245,760 ticks), after the step that ended it.
  const uint64_t reached = device->axes().micros_at_or_after(m.last_step_time() + 245'760);
  std::optional<uint64_t> first_reached;
  for (size_t i = 0; i < sent.size(); ++i)
    if (sent[i].id == kTpdo1 && (statusword_of(sent[i]) & 0x0400) && !first_reached)
      first_reached = sent_at[i];
  ASSERT_TRUE(first_reached);
  EXPECT_EQ(*first_reached, reached);
  EXPECT_EQ(deadline(), kNoDeadline) << "standing at its target: nothing timed";
}

}  // namespace
}  // namespace stepnode::node::test
