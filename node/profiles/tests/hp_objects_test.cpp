// The HP channel objects in the device dictionary: the fixed interface other parts rely on
// (0x2n18 DONE? I8, 0x2n19 error U8, both PDO-mappable; 0x2n11 PSCALE REAL64 stored),
// power-on defaults from the manual (3-2), TPDO 4n+4's default mapping, and EMCY words.
#include <gtest/gtest.h>

#include "node/profiles/hp44714a/objects.hpp"
#include "node/profiles/tests/stepnode_device.hpp"
#include "od/emcy_text.hpp"

namespace stepnode::od {
namespace {

TEST(HpObjects, FixedInterfaceTypesAndAccess) {
  Dictionary od;
  build_stepnode_device(od, DeviceInfo{}, {.axes = 3});
  for (unsigned a = 0; a < 3; ++a) {
    const Entry& done = od.at(hp44714a::obj::index(a, hp44714a::obj::kDone), 0);
    EXPECT_EQ(done.type, DataType::Integer8);
    EXPECT_EQ(done.access, Access::ReadOnly);
    EXPECT_TRUE(done.pdo_mappable);
    const Entry& err = od.at(hp44714a::obj::index(a, hp44714a::obj::kError), 0);
    EXPECT_EQ(err.type, DataType::Unsigned8);
    EXPECT_TRUE(err.pdo_mappable);
    const Entry& ps = od.at(hp44714a::obj::index(a, hp44714a::obj::kPscale), 0);
    EXPECT_EQ(ps.type, DataType::Real64);
    EXPECT_EQ(ps.access, Access::ReadWrite);
    EXPECT_TRUE(ps.persistent);
    EXPECT_EQ(decode<double>(ps.value), 1.0);  // PSCALE 1.0 at power-on
    // PROFILE FREQ 0 250 500 50E-6 at power-on.
    uint16_t p = hp44714a::obj::index(a, hp44714a::obj::kProfile);
    EXPECT_EQ(od.get<double>(p, hp44714a::profile_sub::kMax), 250);
    EXPECT_EQ(od.get<double>(p, hp44714a::profile_sub::kSlope), 500);
    EXPECT_EQ(od.get<double>(p, hp44714a::profile_sub::kLast), 50e-6);
    EXPECT_EQ(od.get<uint8_t>(hp44714a::obj::index(a, hp44714a::obj::kTrig), 0), 1);  // TRIG AUTO
    // TPDO 4a+4: DONE?, error, event word.
    uint16_t map = static_cast<uint16_t>(0x1A00 + 4 * a + 3);
    EXPECT_EQ(od.get<uint8_t>(map, 0), 3);
    EXPECT_EQ(od.get<uint32_t>(map, 1),
              (uint32_t{hp44714a::obj::index(a, hp44714a::obj::kDone)} << 16) | 8u);
    EXPECT_EQ(od.get<uint32_t>(map, 2),
              (uint32_t{hp44714a::obj::index(a, hp44714a::obj::kError)} << 16) | 8u);
    EXPECT_EQ(od.get<uint32_t>(map, 3),
              (uint32_t{hp44714a::obj::index(a, hp44714a::obj::kInterrupt)} << 16) | 0x0208u);
  }
  EXPECT_EQ(od.object(hp44714a::obj::index(3, hp44714a::obj::kDone)),
            nullptr);  // only the configured axes
}

TEST(HpObjects, EmcyCodesHaveTheManualsWords) {
  EXPECT_STREQ(hp44714a::emcy_text(hp44714a::kErrorEmcyBase + 91),
               "HP error 91 MUST STOP TO CHANGE DIRECTION");
  EXPECT_STREQ(hp44714a::emcy_text(hp44714a::kInterruptEmcyBase + 3),
               "HP interrupt: a hard limit stopped pulses");
  EXPECT_EQ(hp44714a::emcy_text(0xFF01), nullptr);  // the Horner axis codes are not the channels'
  EXPECT_EQ(emcy_code_text(0xFF5B), "device specific error");  // od knows no manufacturer codes
}

}  // namespace
}  // namespace stepnode::od
