// Command words that arrive in an RPDO outside the module's ranges (SPM30 3.4, B1.2).
// Over SDO the master gets a range abort; a PDO has no answer, so the register holds the
// illegal word and the next move command is an Illegal Move (%I4, EMCY 0xFF01) with no
// motion, until a legal value is written.
#include <gtest/gtest.h>

#include "node/motion/axis_registers.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

using namespace motion;

class RpdoIllegalWords : public NodeHarness {
 protected:
  static constexpr uint32_t kRpdo1 = 0x200 + kId, kRpdo2 = 0x300 + kId;

  void SetUp() override {
    NodeHarness::SetUp();
    nmt(0x01);
    advance_ms(5);
    rpdo1(command::kClearErrors, 0);
    rpdo1(0, 0);
    rpdo1(command::kSetPosition, 0);
    rpdo1(0, 0);
    ASSERT_EQ(status() & (status::kErrors | status::kPositionValid), status::kPositionValid);
  }
  // RPDO1: command bits (U16) + destination (I32).
  void rpdo1(uint16_t bits, int32_t dest) {
    auto d = static_cast<uint32_t>(dest);
    frame(CanFrame(kRpdo1, {static_cast<uint8_t>(bits), static_cast<uint8_t>(bits >> 8),
                            static_cast<uint8_t>(d), static_cast<uint8_t>(d >> 8),
                            static_cast<uint8_t>(d >> 16), static_cast<uint8_t>(d >> 24)}));
    advance_ms(2);
  }
  // RPDO2: velocity divisor, base, running, acceleration (U16 each).
  void rpdo2(uint16_t aq3, uint16_t aq4, uint16_t aq5, uint16_t aq6) {
    frame(CanFrame(kRpdo2, {static_cast<uint8_t>(aq3), static_cast<uint8_t>(aq3 >> 8),
                            static_cast<uint8_t>(aq4), static_cast<uint8_t>(aq4 >> 8),
                            static_cast<uint8_t>(aq5), static_cast<uint8_t>(aq5 >> 8),
                            static_cast<uint8_t>(aq6), static_cast<uint8_t>(aq6 >> 8)}));
    advance_ms(2);
  }
  uint16_t status() { return static_cast<uint16_t>(*sdo_read(0x2001, 0)); }
  int32_t motor() { return static_cast<int32_t>(*sdo_read(0x2005, 0)); }
  bool emcy_ff01_since(size_t from) {
    for (const auto& f : emcys(from))
      if (emcy_code(f) == 0xFF01) return true;
    return false;
  }
};

TEST_F(RpdoIllegalWords, DestinationOutsideTheModuleRangeSentWithTheCommandIsAnIllegalMove) {
  for (int32_t dest : {8'388'608, -8'388'609}) {
    size_t from = sent.size();
    rpdo1(command::kMoveRelative, dest);
    advance_ms(200);
    EXPECT_TRUE(status() & status::kIllegalMove) << dest;
    EXPECT_EQ(motor(), 0) << "no motion on an illegal destination " << dest;
    EXPECT_TRUE(emcy_ff01_since(from)) << dest;
    // The dictionary kept the last legal value (SDO reads never show an illegal word).
    EXPECT_EQ(*sdo_read(0x2002, 0), 0u);
    rpdo1(0, dest);
    rpdo1(command::kClearErrors, 0);
    rpdo1(0, 0);
  }
}

TEST_F(RpdoIllegalWords, AnIllegalProfileWordStaysUntilALegalOneIsWritten) {
  rpdo2(10, 20, 400, 100);  // %AQ3 = 10 is below 20
  rpdo1(command::kMoveRelative, 100);
  advance_ms(100);
  EXPECT_TRUE(status() & status::kIllegalMove);
  EXPECT_EQ(motor(), 0);
  rpdo1(command::kClearErrors, 100);
  rpdo1(0, 100);
  rpdo1(command::kMoveRelative, 100);  // the register still holds 10
  advance_ms(100);
  EXPECT_TRUE(status() & status::kIllegalMove);
  rpdo1(command::kClearErrors, 100);
  rpdo1(0, 100);
  rpdo2(60, 20, 400, 100);  // legal again
  rpdo1(command::kMoveRelative, 100);
  advance_ms(2000);
  EXPECT_FALSE(status() & status::kErrors);
  EXPECT_EQ(motor(), 100);
}

TEST_F(RpdoIllegalWords, ZeroAccelerationIsIllegalAndSdoStillGetsTheRangeAbort) {
  EXPECT_EQ(sdo_write(0x2003, 4, 0, 2), 0x06090032u);  // value too low
  rpdo2(60, 20, 400, 0);
  rpdo1(command::kMoveRelative, 100);
  advance_ms(100);
  EXPECT_TRUE(status() & status::kIllegalMove);
  EXPECT_EQ(motor(), 0);
}

TEST_F(RpdoIllegalWords, PowerUpForgetsTheIllegalWord) {
  rpdo2(10, 20, 400, 100);
  nmt(0x81);  // reset node: registers back to their stored values
  advance_ms(50);
  nmt(0x01);
  advance_ms(5);
  rpdo1(command::kClearErrors, 0);
  rpdo1(0, 0);
  rpdo1(command::kMoveRelative, 50);
  advance_ms(2000);
  EXPECT_FALSE(status() & status::kErrors);
  EXPECT_EQ(motor(), 50);
}

}  // namespace
}  // namespace stepnode::node::test
