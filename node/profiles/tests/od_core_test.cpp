// The dictionary's CiA 301 rules (access, length, range), the device dictionary's
// consistency rules (PDO procedure, COB-IDs, SYNC, heartbeat consumer, store/restore),
// PDO packing, and the EDS writer/reader.
#include <gtest/gtest.h>

#include "node/profiles/tests/stepnode_device.hpp"
#include "node/profiles/user/objects.hpp"
#include "od/eds.hpp"
#include "od/pdo_mapping.hpp"

namespace stepnode::od {
namespace {

class DeviceDictionaryTest : public ::testing::Test {
 protected:
  void SetUp() override { build_stepnode_device(od, info); }
  SdoAbort w32(uint16_t i, uint8_t s, uint32_t v) { return od.write(i, s, encode<uint32_t>(v)); }
  SdoAbort w8(uint16_t i, uint8_t s, uint8_t v) { return od.write(i, s, Bytes{v}); }
  DeviceInfo info{.node_id = 5};
  Dictionary od;
};

// CiA 301 7.2.4.3.17: each abort code the dictionary gives, with its cause.
TEST_F(DeviceDictionaryTest, AbortCodesOfTheDictionary) {
  EXPECT_EQ(od.read(0x1F00, 0).abort, SdoAbort::NoObject);                       // 0x06020000
  EXPECT_EQ(od.read(0x1018, 9).abort, SdoAbort::NoSubindex);                     // 0x06090011
  EXPECT_EQ(w32(0x1000, 0, 1), SdoAbort::ReadOnly);                              // 0x06010002
  EXPECT_EQ(w32(0x1008, 0, 1), SdoAbort::ReadOnly);                              // const
  EXPECT_EQ(od.write(0x1017, 0, encode<uint32_t>(5)), SdoAbort::LengthTooHigh);  // 0x06070012
  EXPECT_EQ(od.write(0x1017, 0, Bytes{5}), SdoAbort::LengthTooLow);              // 0x06070013
  EXPECT_EQ(w8(0x1A00, 0, 1), SdoAbort::DeviceState);  // PDO valid: 0x08000022
  EXPECT_EQ(w32(0x1800, 1, 0x80000185), SdoAbort::None);
  EXPECT_EQ(w8(0x1A00, 0, 9), SdoAbort::ValueTooHigh);                                 // 0x06090031
  EXPECT_EQ(od.write(0x2002, 0, encode<int32_t>(-8'388'609)), SdoAbort::ValueTooLow);  // 0x06090032
  EXPECT_EQ(od.write(0x2009, 5, Bytes{2}), SdoAbort::InvalidValue);  // BOOLEAN 2: 0x06090030
  EXPECT_EQ(w32(0x1010, 1, 0x12345678), SdoAbort::DataTransfer);     // 0x08000020
  EXPECT_EQ(w32(0x1011, 1, 0x65766173), SdoAbort::DataTransfer);     // "save" is not "load"
  // A write-only object cannot be read (0x06010001): the simulated displacement.
  EXPECT_EQ(od.read(0x5002, 6).abort, SdoAbort::WriteOnly);
  EXPECT_EQ(od.write(0x2F01, 0, Bytes(user::kDataMaxLength + 1, 0)), SdoAbort::LengthTooHigh);
}

TEST_F(DeviceDictionaryTest, PredefinedConnectionSetDefaults) {
  EXPECT_EQ(od.get<uint32_t>(0x1014, 0), 0x85u);
  EXPECT_EQ(od.get<uint32_t>(0x1200, 1), 0x605u);
  EXPECT_EQ(od.get<uint32_t>(0x1200, 2), 0x585u);
  for (unsigned n = 0; n < 4; ++n) {
    EXPECT_EQ(od.get<uint32_t>(static_cast<uint16_t>(0x1400 + n), 1), 0x205u + 0x100 * n);
    EXPECT_EQ(od.get<uint32_t>(static_cast<uint16_t>(0x1800 + n), 1), 0x40000185u + 0x100 * n);
  }
  EXPECT_TRUE(od.get<uint32_t>(0x1804, 1) & 0x80000000u);  // PDO 5+: no ID until given one
  EXPECT_NE(od.object(0x180B), nullptr);                   // 4 per axis, 3 axes
  EXPECT_EQ(od.object(0x180C), nullptr);
}

// CiA 301 7.5.2.36: the dynamic mapping procedure and its refusals at each wrong step.
TEST_F(DeviceDictionaryTest, PdoMappingProcedure) {
  EXPECT_EQ(w32(0x1A00, 1, 0x2F000120), SdoAbort::DeviceState);            // PDO still valid
  EXPECT_EQ(w32(0x1800, 1, 0xC0000185), SdoAbort::None);                   // 1. destroy
  EXPECT_EQ(w32(0x1A00, 1, 0x2F000120), SdoAbort::DeviceState);            // count not yet 0
  EXPECT_EQ(w8(0x1A00, 0, 0), SdoAbort::None);                             // 2. disable mapping
  EXPECT_EQ(w32(0x1A00, 1, 0x10080008), SdoAbort::NotMappable);            // string: 0x06040041
  EXPECT_EQ(w32(0x1A00, 1, 0x2F000110), SdoAbort::ParameterIncompatible);  // wrong length
  EXPECT_EQ(w32(0x1A00, 1, 0x30000020), SdoAbort::NoObject);
  EXPECT_EQ(w32(0x1A00, 1, 0x2F000120), SdoAbort::None);  // 3. entries
  EXPECT_EQ(w32(0x1A00, 2, 0x2F000220), SdoAbort::None);
  EXPECT_EQ(w32(0x1A00, 3, 0x10010008), SdoAbort::None);
  EXPECT_EQ(w8(0x1A00, 0, 3), SdoAbort::PdoTooLong);      // 72 bits: 0x06040042
  EXPECT_EQ(w8(0x1A00, 0, 2), SdoAbort::None);            // 4. enable
  EXPECT_EQ(w32(0x1800, 1, 0x40000185), SdoAbort::None);  // 5. create
  // RPDOs map only writable entries, and may use dummies (not BOOLEAN).
  EXPECT_EQ(w32(0x1400, 1, 0x80000205), SdoAbort::None);
  EXPECT_EQ(w8(0x1600, 0, 0), SdoAbort::None);
  EXPECT_EQ(w32(0x1600, 1, 0x10010008), SdoAbort::NotMappable);  // read-only
  EXPECT_EQ(w32(0x1600, 1, 0x00050008), SdoAbort::None);         // dummy UNSIGNED8
  EXPECT_EQ(w32(0x1600, 2, 0x00010001), SdoAbort::NotMappable);  // dummy BOOLEAN
}

TEST_F(DeviceDictionaryTest, CobIdRules) {
  EXPECT_EQ(w32(0x1800, 1, 0x40000186), SdoAbort::InvalidValue);  // CAN-ID change while valid
  EXPECT_EQ(w32(0x1800, 1, 0x60000185), SdoAbort::InvalidValue);  // 29-bit
  EXPECT_EQ(w32(0x1800, 1, 0xC0000185), SdoAbort::None);
  EXPECT_EQ(w32(0x1800, 1, 0x40000701), SdoAbort::InvalidValue);         // restricted (heartbeat)
  EXPECT_EQ(w32(0x1800, 1, 0xC0000701), SdoAbort::None);                 // allowed while invalid
  EXPECT_EQ(w8(0x1800, 2, 241), SdoAbort::InvalidValue);                 // reserved
  EXPECT_EQ(w8(0x1800, 2, 252), SdoAbort::InvalidValue);                 // RTR only
  EXPECT_EQ(od.write(0x1800, 3, encode<uint16_t>(10)), SdoAbort::None);  // invalid: may change
  EXPECT_EQ(w32(0x1800, 1, 0x40000190), SdoAbort::None);
  EXPECT_EQ(od.write(0x1800, 3, encode<uint16_t>(20)), SdoAbort::InvalidValue);  // valid: not
  EXPECT_EQ(w32(0x1014, 1 - 1, 0x00000086), SdoAbort::InvalidValue);  // EMCY ID while valid
  EXPECT_EQ(w32(0x1005, 0, 0x20000080), SdoAbort::InvalidValue);      // 29-bit SYNC
}

TEST_F(DeviceDictionaryTest, SyncCounterAndHeartbeatConsumerAndErrorHistory) {
  EXPECT_EQ(w8(0x1019, 0, 1), SdoAbort::InvalidValue);
  EXPECT_EQ(w8(0x1019, 0, 5), SdoAbort::None);
  EXPECT_EQ(w32(0x1006, 0, 10000), SdoAbort::None);
  EXPECT_EQ(w8(0x1019, 0, 6), SdoAbort::DeviceState);  // period != 0 (CiA 301 7.5.2.22)
  EXPECT_EQ(w32(0x1016, 1, 0x000101F4), SdoAbort::None);
  EXPECT_EQ(w32(0x1016, 2, 0x00010064), SdoAbort::ParameterIncompatible);  // same node twice
  EXPECT_EQ(w32(0x1016, 2, 0x00020064), SdoAbort::None);
  od.put<uint8_t>(0x1003, 0, 2);
  od.put<uint32_t>(0x1003, 1, 0x8130);
  EXPECT_EQ(w8(0x1003, 0, 1), SdoAbort::InvalidValue);
  EXPECT_EQ(w8(0x1003, 0, 0), SdoAbort::None);
  EXPECT_EQ(od.get<uint32_t>(0x1003, 1), 0u);
}

TEST(PdoPacking, BitExactLittleEndian) {
  Dictionary od;
  od.var(0x2000, "a", DataType::Unsigned8, Access::ReadWrite, {0xAB}, true);
  od.var(0x2001, "b", DataType::Integer16, Access::ReadWrite, encode<int16_t>(-2), true);
  od.var(0x2002, "c", DataType::Unsigned32, Access::ReadWrite, encode<uint32_t>(0x11223344), true);
  PdoMapping map{{0x2000, 0, 8}, {0x2001, 0, 16}, {0x2002, 0, 32}};
  EXPECT_EQ(pack_pdo(od, map), (std::vector<uint8_t>{0xAB, 0xFE, 0xFF, 0x44, 0x33, 0x22, 0x11}));
  std::vector<uint8_t> in{0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07};
  EXPECT_EQ(unpack_pdo(od, map, in), SdoAbort::None);
  EXPECT_EQ(od.get<uint8_t>(0x2000, 0), 0x01);
  EXPECT_EQ(od.get<int16_t>(0x2001, 0), 0x0302);
  EXPECT_EQ(od.get<uint32_t>(0x2002, 0), 0x07060504u);
  // A dummy skips its bits.
  PdoMapping with_dummy{{0x0005, 0, 8}, {0x2000, 0, 8}};
  EXPECT_EQ(unpack_pdo(od, with_dummy, std::vector<uint8_t>{0xEE, 0x42}), SdoAbort::None);
  EXPECT_EQ(od.get<uint8_t>(0x2000, 0), 0x42);
}

// A PDO's on_written reactions run after all its values are stored: a command bit mapped
// before its destination must see the new destination.
TEST(PdoPacking, ReactionsRunAfterTheWholePdo) {
  Dictionary od;
  od.var(0x2000, "command", DataType::Unsigned8, Access::ReadWrite, {0}, true);
  od.var(0x2001, "destination", DataType::Unsigned8, Access::ReadWrite, {0}, true);
  uint8_t seen = 0;
  listen(od.at(0x2000, 0), [&] { seen = od.get<uint8_t>(0x2001, 0); });
  PdoMapping map{{0x2000, 0, 8}, {0x2001, 0, 8}};
  EXPECT_EQ(unpack_pdo(od, map, std::vector<uint8_t>{1, 42}), SdoAbort::None);
  EXPECT_EQ(seen, 42);
}

TEST(Eds, RoundTripAndStructure) {
  Dictionary od;
  DeviceInfo info;
  build_stepnode_device(od, info);
  std::string text = write_eds(od, info);
  EdsFile eds = parse_eds(text);
  for (const char* section : {"fileinfo", "deviceinfo", "dummyusage", "mandatoryobjects",
                              "optionalobjects", "manufacturerobjects"})
    EXPECT_TRUE(eds.sections.count(section)) << section;
  EXPECT_EQ(eds.sections["deviceinfo"]["nroftxpdo"], "12");
  EXPECT_EQ(eds.sections["mandatoryobjects"]["supportedobjects"], "3");
  EXPECT_EQ(eds.sections["1018"]["subnumber"], "5");
  EXPECT_EQ(eds.sections["1018"]["objecttype"], "0x9");
  EXPECT_EQ(eds.sections["1003"]["objecttype"], "0x8");
  EXPECT_EQ(eds.sections["1800sub1"]["defaultvalue"], "$NODEID+0x40000180");
  EXPECT_EQ(eds.sections["1014"]["defaultvalue"], "$NODEID+0x80");
  size_t entries = 0;
  for (const auto& [index, obj] : od.objects())
    for (const auto& [sub, e] : obj.entries) {
      const EdsEntry* got = eds.find(index, sub);
      ASSERT_NE(got, nullptr) << std::hex << index << ":" << int(sub);
      EXPECT_EQ(got->type, e.type);
      EXPECT_EQ(got->access, e.access);
      EXPECT_EQ(got->pdo_mappable, e.pdo_mappable);
      ++entries;
    }
  EXPECT_EQ(eds.entries.size(), entries);
  EXPECT_THROW(parse_eds("[1000]\nDataType=0x0007\nAccessType=xx\nParameterName=x\n"),
               std::runtime_error);
  try {
    parse_eds("[FileInfo]\nnot a key value\n");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos);
  }
}

}  // namespace
}  // namespace stepnode::od
