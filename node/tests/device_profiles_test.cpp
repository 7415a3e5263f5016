// A device is configured with any subset of profiles: one with only the HP 44714A channels
// and one with only the Horner registers each have only their own objects (in the
// dictionary, in the EDS they serve over 0x1021 and in --print-eds), PDOs that no profile
// maps start invalid, and each is driven over the bus as a master would (SDO frames built
// by hand, CiA 301 abort 0x06020000 for an object the device does not have).
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "node/profiles/horner/bits.hpp"
#include "node/profiles/horner/objects.hpp"
#include "node/profiles/hp44714a/objects.hpp"
#include "node/tests/node_harness.hpp"
#include "od/eds.hpp"

namespace stepnode::node::test {
namespace {

constexpr uint32_t kNoObject = 0x06020000;

class DeviceProfiles : public NodeHarness {
 protected:
  void SetUp() override {}
  void build(const DeviceLayout& layout) { make(layout); }
  // The manufacturer objects (0x2000-0x5FFF) of the EDS the node serves (0x1021).
  std::set<uint16_t> eds_manufacturer_objects() {
    od::SdoResult r = transfer(false, 0x1021, 0);
    EXPECT_TRUE(r.ok());
    od::EdsFile eds = od::parse_eds(std::string(r.data.begin(), r.data.end()));
    std::set<uint16_t> out;
    for (const auto& [key, entry] : eds.entries)
      if (key.first >= 0x2000 && key.first <= 0x5FFF) out.insert(key.first);
    return out;
  }
  uint32_t cob_id(uint16_t comm) { return *sdo_read(comm, 1); }
};

TEST_F(DeviceProfiles, AnHpOnlyDeviceHasOnlyTheChannelsObjects) {
  build(DeviceLayout{.axes = 2, .horner = false, .user = false});
  for (uint16_t i : eds_manufacturer_objects()) {
    SCOPED_TRACE(testing::Message() << std::hex << i);
    const unsigned offset = i & 0xFF;
    const bool hp = i < 0x2800 && offset >= 0x10 && offset <= 0x1F;
    const bool sim = i >= 0x5000 && (offset <= 0x05 || i == 0x5F00);
    EXPECT_TRUE(hp || sim || i == 0x2F10 || i == 0x2F11 || i == 0x2F12);
  }
  EXPECT_TRUE(eds_manufacturer_objects().count(hp44714a::obj::index(1, hp44714a::obj::kDone)));
  // The Horner registers and the user objects are not there.
  uint32_t abort = 0;
  EXPECT_FALSE(sdo_read(horner::obj::index(0, horner::obj::kStatusBits), 0, &abort));
  EXPECT_EQ(abort, kNoObject);
  EXPECT_EQ(sdo_write(horner::obj::index(0, horner::obj::kCommandBits), 0, 1, 2), kNoObject);
  EXPECT_EQ(sdo_write(0x2F00, 1, 7), kNoObject);
  // TPDO 4 (DONE?, error, events) is mapped; RPDO/TPDO 1-3 map nothing and are invalid.
  EXPECT_EQ(cob_id(0x1803) & 0x80000000u, 0u);
  for (uint16_t comm : {0x1400, 0x1401, 0x1402, 0x1403, 0x1800, 0x1801, 0x1802})
    EXPECT_NE(cob_id(comm) & 0x80000000u, 0u) << std::hex << comm;
}

TEST_F(DeviceProfiles, AnHpOnlyDeviceRunsFigure3_3OverTheBus) {
  build(DeviceLayout{.axes = 1, .horner = false, .user = false});
  nmt(0x01);
  uint16_t p = hp44714a::obj::index(0, hp44714a::obj::kProfile);
  ASSERT_EQ(put(p, hp44714a::profile_sub::kMin, 100), 0u);
  ASSERT_EQ(put(p, hp44714a::profile_sub::kMax, 800), 0u);
  ASSERT_EQ(put(p, hp44714a::profile_sub::kSlope, 200), 0u);
  ASSERT_EQ(put(p, hp44714a::profile_sub::kLast, 25e-6), 0u);
  ASSERT_EQ(put_int<uint8_t>(p, hp44714a::profile_sub::kApply, 1), 0u);
  ASSERT_EQ(put(hp44714a::obj::index(0, hp44714a::obj::kPscale), 0, 0.1), 0u);
  ASSERT_EQ(put(hp44714a::obj::index(0, hp44714a::obj::kMove), hp44714a::move_sub::kRelative, 20),
            0u);
  advance_ms(3000);
  EXPECT_EQ(static_cast<int8_t>(*sdo_read(hp44714a::obj::index(0, hp44714a::obj::kDone), 0)), 0);
  EXPECT_EQ(static_cast<int32_t>(*sdo_read(0x5003, 0)),
            200);  // the simulated motor moved 200 steps
  EXPECT_NEAR(get(hp44714a::obj::index(0, hp44714a::obj::kPosition)), 20.0, 1e-9);
}

TEST_F(DeviceProfiles, AHornerOnlyDeviceHasOnlyTheRegisters) {
  build(DeviceLayout{.axes = 1, .hp = false, .user = false});
  for (uint16_t i : eds_manufacturer_objects()) {
    SCOPED_TRACE(testing::Message() << std::hex << i);
    const unsigned offset = i & 0xFF;
    const bool horner = i < 0x2800 && offset <= 0x0A;
    const bool sim = i >= 0x5000 && (offset <= 0x04 || i == 0x5F00);
    EXPECT_TRUE(horner || sim || i == 0x2F10 || i == 0x2F11 || i == 0x2F12);
  }
  EXPECT_EQ(sdo_write(hp44714a::obj::index(0, hp44714a::obj::kTrig), 0, 1, 1), kNoObject);
  EXPECT_NE(cob_id(0x1803) & 0x80000000u, 0u);  // TPDO 4 (the HP channel's) maps nothing
  EXPECT_EQ(cob_id(0x1800) & 0x80000000u, 0u);
  // A move over SDO: Clear Errors, Set Position, Move Relative 500 (SPM30 chapter 3).
  const uint16_t bits = horner::obj::index(0, horner::obj::kCommandBits);
  for (uint16_t c : {horner::command::kClearErrors, horner::command::kSetPosition,
                     horner::command::kMoveRelative}) {
    if (c == horner::command::kMoveRelative) {
      ASSERT_EQ(sdo_write(horner::obj::index(0, horner::obj::kDestination), 0, 500), 0u);
    }
    ASSERT_EQ(sdo_write(bits, 0, c, 2), 0u);
    ASSERT_EQ(sdo_write(bits, 0, 0, 2), 0u);
  }
  advance_ms(3000);
  EXPECT_EQ(static_cast<int32_t>(*sdo_read(horner::obj::index(0, horner::obj::kMotorPosition), 0)),
            500);
  EXPECT_EQ(static_cast<int32_t>(*sdo_read(0x5003, 0)), 500);
}

TEST_F(DeviceProfiles, TheEdsCommentNamesTheProfiles) {
  build(DeviceLayout{.axes = 2, .horner = false});
  od::SdoResult r = transfer(false, 0x1021, 0);
  ASSERT_TRUE(r.ok());
  std::string text(r.data.begin(), r.data.end());
  EXPECT_NE(text.find("Line2=HP 44714A, user objects; 2 axes on the simulated machine"),
            std::string::npos);
}

}  // namespace
}  // namespace stepnode::node::test
