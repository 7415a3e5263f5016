// HP 44714A rules for commands that set a value, over the bus (found in review): POS in
// the manual's range, and the setting commands refused with error 89 while a MOVE without
// NOWAIT runs, accepted (0x2n19 = 0) otherwise.
#include <gtest/gtest.h>

#include "node/profiles/hp44714a/objects.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

using namespace hp44714a::obj;
constexpr uint32_t kRange = 0x06090030;

class HpCommandRules : public NodeHarness {
 protected:
  void SetUp() override { make(1); }
};

// POS takes "any number from -2,147,483,648 to +2,147,483,647 specified in the units of the
// PSCALE command" (3-18); outside it a range abort, as a MOVE of more pulses than the
// module has (POS 3E9 was loaded).
TEST_F(HpCommandRules, PosTakesTheManualsRangeAndNoMore) {
  const uint16_t pos = index(0, kPosition);
  EXPECT_EQ(put(pos, 0, 2147483647.0), 0u);
  EXPECT_EQ(get(pos), 2147483647.0);
  EXPECT_EQ(put(pos, 0, -2147483648.0), 0u);
  EXPECT_EQ(get(pos), -2147483648.0);
  EXPECT_EQ(put(pos, 0, 2147483648.0), kRange);
  EXPECT_EQ(put(pos, 0, 3e9), kRange);
  EXPECT_EQ(put(pos, 0, -2147483649.0), kRange);
  EXPECT_EQ(get(pos), -2147483648.0);  // unchanged
  // In PSCALE units: 0.5 units a step do not widen it.
  ASSERT_EQ(put(index(0, kPscale), 0, 0.5), 0u);
  EXPECT_EQ(put(pos, 0, 2147483648.0), kRange);
  EXPECT_EQ(put(pos, 0, 1e3), 0u);
}

// 3-13 note 1: without NOWAIT "the HP 44714A must complete the MOVE or SUSTAIN command
// before the next command is recognized": DELAY, PULSE, HARDLIM, QSCALE, QINDEX and
// ENABLE INTR were taken while it ran. Each is error 89 then (its value not taken), and
// once the MOVE is done each is accepted with 0x2n19 back at 0.
TEST_F(HpCommandRules, SettingCommandsWaitForAMoveWithoutNowait) {
  constexpr uint32_t kDeviceState = 0x08000022;
  struct Setting {
    uint16_t offset;
    uint8_t sub;
    uint8_t value;
  };
  const Setting settings[] = {
      {kDelay, 0, 5},
      {kOutput, hp44714a::output_sub::kPulseMode, 0},
      {kLimits, hp44714a::limits_sub::kPlimSense, 1},
      {kQuadrature, hp44714a::quad_sub::kQindex, 1},
      {kInterrupt, hp44714a::intr_sub::kEnable, 1},
  };
  ASSERT_EQ(put_int<uint8_t>(index(0, kMove), hp44714a::move_sub::kNowait, 0), 0u);
  ASSERT_EQ(put(index(0, kMove), hp44714a::move_sub::kRelative, 2000.0), 0u);  // 8 s at 250 Hz
  advance_us(100'000);
  for (const Setting& s : settings) {
    const uint8_t before = static_cast<uint8_t>(*sdo_read(index(0, s.offset), s.sub));
    const int width = s.offset == kDelay ? 2 : 1;
    EXPECT_EQ(sdo_write(index(0, s.offset), s.sub, s.value, width), kDeviceState)
        << std::hex << index(0, s.offset) << ":" << int{s.sub};
    EXPECT_EQ(*sdo_read(index(0, kError), 0), 89u);
    EXPECT_EQ(*sdo_read(index(0, s.offset), s.sub), before);
  }
  EXPECT_EQ(put(index(0, kQuadrature), hp44714a::quad_sub::kQscale, 2.0), kDeviceState);
  advance_us(9'000'000);  // the MOVE is done
  for (const Setting& s : settings) {
    const int width = s.offset == kDelay ? 2 : 1;
    EXPECT_EQ(sdo_write(index(0, s.offset), s.sub, s.value, width), 0u);
    EXPECT_EQ(*sdo_read(index(0, kError), 0), 0u);
  }
  EXPECT_EQ(put(index(0, kQuadrature), hp44714a::quad_sub::kQscale, 2.0), 0u);
}

}  // namespace
}  // namespace stepnode::node::test
