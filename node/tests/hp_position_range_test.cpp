// POS takes "any number from -2,147,483,648 to +2,147,483,647 specified in the units of the
// PSCALE command" (HP 44714A 3-18); outside it a range abort, as a MOVE of more pulses
// than the module has (found in review: POS 3E9 was loaded).
#include <gtest/gtest.h>

#include "node/profiles/hp44714a/objects.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

using namespace hp44714a::obj;
constexpr uint32_t kRange = 0x06090030;

class HpPositionRange : public NodeHarness {
 protected:
  void SetUp() override { make(1); }
};

TEST_F(HpPositionRange, PosTakesTheManualsRangeAndNoMore) {
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

}  // namespace
}  // namespace stepnode::node::test
