// A stored HP PROFILE comes back in the units it was given in: FREQ values are units/s of
// the PSCALE in effect when PROFILE is given (3-9), so a restart gives the stored PROFILE
// at that PSCALE and then the stored PSCALE (found in review: "PSCALE 0.5; PROFILE FREQ 100
// 100 0" ran at 200 pulses/s, and at 100 after a restart: every move took twice as long).
#include <gtest/gtest.h>

#include "node/profiles/hp44714a/objects.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

using namespace hp44714a::obj;
constexpr uint32_t kSave = 0x65766173;  // "save"

class HpStoredProfile : public NodeHarness {
 protected:
  uint32_t profile(double min, double max, double slope) {
    const uint16_t p = index(0, kProfile);
    EXPECT_EQ(put_int<uint8_t>(p, hp44714a::profile_sub::kMode, 0), 0u);  // FREQ
    EXPECT_EQ(put(p, hp44714a::profile_sub::kMin, min), 0u);
    EXPECT_EQ(put(p, hp44714a::profile_sub::kMax, max), 0u);
    EXPECT_EQ(put(p, hp44714a::profile_sub::kSlope, slope), 0u);
    EXPECT_EQ(put(p, hp44714a::profile_sub::kLast, 25e-6), 0u);
    return put_int<uint8_t>(p, hp44714a::profile_sub::kApply, 1);
  }
  int32_t mechanical() { return static_cast<int32_t>(*sdo_read(0x5003, 0)); }
  // Steps made in the first 60 ms of MOVE `units` NOWAIT (then it is let finish).
  int32_t steps_in_60_ms(double units) {
    const int32_t from = mechanical();
    EXPECT_EQ(put_int<uint8_t>(index(0, kMove), hp44714a::move_sub::kNowait, 1), 0u);
    EXPECT_EQ(put(index(0, kMove), hp44714a::move_sub::kRelative, units), 0u);
    advance_us(60'000);
    const int32_t made = mechanical() - from;
    advance_us(2'000'000);
    return made;
  }
};

TEST_F(HpStoredProfile, AProfileGivenAfterPscaleRunsAtItsRateAfterARestart) {
  make(1);
  nmt(0x01);
  ASSERT_EQ(put(index(0, kPscale), 0, 0.5), 0u);
  ASSERT_EQ(profile(100, 100, 0), 0u);  // 100 units/s at 0.5 units per step: 200 pulses/s
  EXPECT_EQ(get(index(0, kProfile), hp44714a::profile_sub::kGivenAtPscale), 0.5);
  const int32_t before = steps_in_60_ms(10);
  EXPECT_EQ(before, 12);  // the first pulse one period (5 ms) after the start
  ASSERT_EQ(sdo_write(0x1010, 1, kSave), 0u);
  make(1);  // a new process on the same state directory
  nmt(0x01);
  EXPECT_EQ(get(index(0, kPscale)), 0.5);
  EXPECT_EQ(get(index(0, kProfile), hp44714a::profile_sub::kMax), 100.0);
  EXPECT_EQ(steps_in_60_ms(10), before);
}

// The order of Figure 3-3 (PROFILE, then PSCALE) is kept too: that profile was given at
// PSCALE 1, in pulses/s.
TEST_F(HpStoredProfile, AProfileGivenBeforePscaleStaysInPulsesPerSecond) {
  make(1);
  nmt(0x01);
  ASSERT_EQ(profile(100, 100, 0), 0u);  // 100 pulses/s
  ASSERT_EQ(put(index(0, kPscale), 0, 0.5), 0u);
  const int32_t before = steps_in_60_ms(10);
  EXPECT_EQ(before, 6);
  ASSERT_EQ(sdo_write(0x1010, 1, kSave), 0u);
  make(1);
  nmt(0x01);
  EXPECT_EQ(steps_in_60_ms(10), before);
}

}  // namespace
}  // namespace stepnode::node::test
