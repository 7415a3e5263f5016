// The device's CiA 301 communication area and its consistency rules: pre-defined
// connection set defaults (7.3.3), restricted CAN-IDs (7.3.5), error history (7.5.2.3), SYNC
// COB-ID (7.5.2.5), store/restore signatures (7.5.2.13/14), EMCY COB-ID (7.5.2.17),
// heartbeat consumer (7.5.2.20), SYNC counter overflow (7.5.2.22), PDO communication and
// mapping parameters with the mapping procedure (7.5.2.35 - 7.5.2.38).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "node/profiles/horner/objects.hpp"
#include "node/profiles/tests/stepnode_device.hpp"
#include "node/profiles/user/objects.hpp"
#include "od/can_frame.hpp"
#include "od/pdo_mapping.hpp"

namespace stepnode::od {
namespace {

constexpr uint32_t kInvalid = 0x80000000;  // bit 31
constexpr uint32_t kNoRtr = 0x40000000;    // bit 30 (TPDO), gen (SYNC)
constexpr uint32_t kFrame = 0x20000000;    // bit 29

uint16_t idx(unsigned base, unsigned n) { return static_cast<uint16_t>(base + n); }

class DeviceDictionaryRules : public ::testing::Test {
 protected:
  void SetUp() override { build_stepnode_device(od, info); }
  SdoAbort w32(uint16_t i, uint8_t s, uint32_t v) { return od.write(i, s, encode<uint32_t>(v)); }
  SdoAbort w16(uint16_t i, uint8_t s, uint16_t v) { return od.write(i, s, encode<uint16_t>(v)); }
  SdoAbort w8(uint16_t i, uint8_t s, unsigned v) {
    return od.write(i, s, Bytes{static_cast<uint8_t>(v)});
  }
  uint32_t r32(uint16_t i, uint8_t s) { return decode<uint32_t>(od.read(i, s).data); }
  DeviceInfo info{.node_id = 5};
  Dictionary od;
};

// ---- defaults -----------------------------------------------------------------------------

class DefaultsForNode : public ::testing::TestWithParam<int> {};

TEST_P(DefaultsForNode, PredefinedConnectionSet) {
  const uint8_t node = static_cast<uint8_t>(GetParam());
  DeviceInfo info{.node_id = node};
  Dictionary od;
  build_stepnode_device(od, info);
  EXPECT_EQ(od.get<uint32_t>(0x1005, 0), 0x80u);         // SYNC, not produced
  EXPECT_EQ(od.get<uint32_t>(0x1014, 0), 0x80u + node);  // EMCY
  EXPECT_EQ(od.get<uint8_t>(0x1200, 0), 2);
  EXPECT_EQ(od.get<uint32_t>(0x1200, 1), 0x600u + node);  // client -> server
  EXPECT_EQ(od.get<uint32_t>(0x1200, 2), 0x580u + node);  // server -> client
  for (unsigned n = 0; n < 4; ++n) {
    SCOPED_TRACE(n);
    EXPECT_EQ(od.get<uint32_t>(idx(0x1800, n), 1), 0x40000180u + 0x100 * n + node);  // TPDO, no RTR
    EXPECT_EQ(od.get<uint32_t>(idx(0x1400, n), 1), 0x200u + 0x100 * n + node);       // RPDO
  }
  // PDO 5 and up have no CAN-ID until the integrator gives them one.
  for (unsigned n = 4; n < pdo_count(); ++n) {
    EXPECT_EQ(od.get<uint32_t>(idx(0x1800, n), 1), kInvalid | kNoRtr) << n;
    EXPECT_EQ(od.get<uint32_t>(idx(0x1400, n), 1), kInvalid) << n;
  }
  EXPECT_EQ(od.get<uint32_t>(0x1014, 0), cob::kEmcyBase + node);
  EXPECT_EQ(od.get<uint32_t>(0x1800, 1) & 0x7FF, cob::kTpdo1 + node);
  EXPECT_EQ(od.get<uint32_t>(0x1403, 1), cob::kRpdo4 + node);
}

INSTANTIATE_TEST_SUITE_P(Nodes, DefaultsForNode, ::testing::Values(1, 5, 64, 127));

TEST_F(DeviceDictionaryRules, IdentityAndOtherDefaults) {
  EXPECT_EQ(od.get<uint32_t>(0x1000, 0), 0u);
  EXPECT_EQ(od.get<uint8_t>(0x1001, 0), 0);
  EXPECT_EQ(od.value(0x1008, 0), encode_string(info.device_name));
  EXPECT_EQ(od.value(0x1009, 0), encode_string(info.hardware_version));
  EXPECT_EQ(od.value(0x100A, 0), encode_string(info.software_version));
  EXPECT_EQ(od.get<uint8_t>(0x1018, 0), 4);
  EXPECT_EQ(od.get<uint32_t>(0x1018, 1), info.vendor_id);
  EXPECT_EQ(od.get<uint32_t>(0x1018, 2), info.product_code);
  EXPECT_EQ(od.get<uint32_t>(0x1018, 3), info.revision);
  EXPECT_EQ(od.get<uint32_t>(0x1018, 4), info.serial_number);
  EXPECT_EQ(od.get<uint8_t>(0x1003, 0), 0);  // no errors yet
  EXPECT_EQ(od.get<uint32_t>(0x1006, 0), 0u);
  EXPECT_EQ(od.get<uint16_t>(0x1015, 0), 0);
  EXPECT_EQ(od.get<uint8_t>(0x1016, 0), kHeartbeatConsumers);
  EXPECT_EQ(od.get<uint16_t>(0x1017, 0), 1000);
  EXPECT_EQ(od.get<uint8_t>(0x1019, 0), 0);
  EXPECT_EQ(od.get<uint8_t>(0x1010, 0), 4);
  EXPECT_EQ(od.get<uint8_t>(0x1011, 0), 4);

  DeviceInfo custom{.node_id = 9,
                    .device_name = "x",
                    .vendor_id = 0x1234,
                    .product_code = 7,
                    .revision = 0x00020003,
                    .serial_number = 42};
  Dictionary other;
  build_stepnode_device(other, custom, {.axes = 1});
  EXPECT_EQ(other.value(0x1008, 0), encode_string("x"));
  EXPECT_EQ(other.get<uint32_t>(0x1018, 1), 0x1234u);
  EXPECT_EQ(other.get<uint32_t>(0x1018, 2), 7u);
  EXPECT_EQ(other.get<uint32_t>(0x1018, 3), 0x00020003u);
  EXPECT_EQ(other.get<uint32_t>(0x1018, 4), 42u);
}

TEST_F(DeviceDictionaryRules, PdoCommunicationParameterLayout) {
  for (unsigned n = 0; n < pdo_count(); ++n) {
    SCOPED_TRACE(n);
    const Object* rpdo = od.object(idx(0x1400, n));
    const Object* tpdo = od.object(idx(0x1800, n));
    ASSERT_NE(rpdo, nullptr);
    ASSERT_NE(tpdo, nullptr);
    EXPECT_EQ(rpdo->code, ObjectCode::Record);
    // RPDO: 1 COB-ID, 2 type, 5 event timer (deadline); TPDO also 3 inhibit, 6 SYNC start.
    EXPECT_EQ(od.get<uint8_t>(idx(0x1400, n), 0), 5);
    EXPECT_EQ(od.get<uint8_t>(idx(0x1800, n), 0), 6);
    EXPECT_EQ(rpdo->entries.size(), 4u);
    EXPECT_EQ(tpdo->entries.size(), 6u);
    EXPECT_EQ(od.locate(idx(0x1400, n), 3), SdoAbort::NoSubindex);
    EXPECT_EQ(od.locate(idx(0x1400, n), 4), SdoAbort::NoSubindex);
    EXPECT_EQ(od.locate(idx(0x1800, n), 4), SdoAbort::NoSubindex);
    EXPECT_EQ(od.get<uint8_t>(idx(0x1400, n), 2), 254);
    EXPECT_EQ(od.get<uint8_t>(idx(0x1800, n), 2), 254);
    EXPECT_EQ(od.get<uint16_t>(idx(0x1800, n), 5), 0);
    EXPECT_EQ(od.get<uint8_t>(idx(0x1800, n), 6), 0);
    // Mapping: 8 entries, sub 0 writable (the number of mapped objects).
    for (unsigned base : {0x1600u, 0x1A00u}) {
      const Object* map = od.object(idx(base, n));
      ASSERT_NE(map, nullptr);
      EXPECT_EQ(map->entries.size(), 1u + kMaxMappedEntries);
      EXPECT_EQ(map->entries.at(0).access, Access::ReadWrite);
      EXPECT_EQ(map->entries.at(1).type, DataType::Unsigned32);
    }
  }
}

TEST(DevicePdoCount, FourRpdosAndFourTpdosPerAxis) {
  EXPECT_EQ(horner::kPdosPerAxis, 4u);
  for (unsigned axes : {1u, 2u, 3u, 8u}) {
    SCOPED_TRACE(axes);
    node::DeviceLayout layout{.axes = axes};
    Dictionary od;
    build_stepnode_device(od, DeviceInfo{}, layout);
    EXPECT_EQ(pdo_count(layout), 4 * axes);
    for (unsigned base : {0x1400u, 0x1600u, 0x1800u, 0x1A00u}) {
      EXPECT_NE(od.object(idx(base, 4 * axes - 1)), nullptr) << std::hex << base;
      EXPECT_EQ(od.object(idx(base, 4 * axes)), nullptr) << std::hex << base;
    }
  }
  node::DeviceLayout spm30{.axes = 1, .spm30_multiplexed = true};
  EXPECT_EQ(pdo_count(spm30), 4u);
  EXPECT_EQ(spm30.motors(), 3u);
}

TEST_F(DeviceDictionaryRules, DefaultMappingsAreValidInTheirDirection) {
  for (unsigned n = 0; n < pdo_count(); ++n) {
    for (bool rx : {true, false}) {
      uint16_t map = idx(rx ? 0x1600 : 0x1A00, n);
      SCOPED_TRACE(testing::Message() << std::hex << map);
      uint8_t count = od.get<uint8_t>(map, 0);
      std::vector<uint32_t> words;
      for (uint8_t i = 1; i <= count; ++i) words.push_back(od.get<uint32_t>(map, i));
      EXPECT_EQ(check_mapping(od, words, rx ? PdoDirection::Receive : PdoDirection::Transmit),
                SdoAbort::None);
      for (unsigned i = count + 1u; i <= kMaxMappedEntries; ++i)
        EXPECT_EQ(od.get<uint32_t>(map, static_cast<uint8_t>(i)), 0u);
    }
  }
  // Axis 1: RPDO1 = command bits + destination, TPDO1 = status bits + motor position.
  EXPECT_EQ(od.get<uint8_t>(0x1600, 0), 2);
  EXPECT_EQ(od.get<uint32_t>(0x1600, 1), 0x20000010u);
  EXPECT_EQ(od.get<uint32_t>(0x1600, 2), 0x20020020u);
  EXPECT_EQ(od.get<uint8_t>(0x1A00, 0), 2);
  EXPECT_EQ(od.get<uint32_t>(0x1A00, 1), 0x20010010u);
  EXPECT_EQ(od.get<uint32_t>(0x1A00, 2), 0x20050020u);
}

TEST_F(DeviceDictionaryRules, EveryDefaultPassesItsOwnTypeLengthAndLimits) {
  for (const auto& [index, obj] : od.objects()) {
    EXPECT_EQ(obj.index, index);
    for (const auto& [sub, e] : obj.entries) {
      SCOPED_TRACE(testing::Message() << std::hex << index << ":" << int(sub) << " " << e.name);
      EXPECT_EQ(e.index, index);
      EXPECT_EQ(e.sub, sub);
      EXPECT_EQ(check_value(e, e.default_value), SdoAbort::None);
      EXPECT_FALSE(e.name.empty());
      if (e.pdo_mappable) {
        EXPECT_FALSE(is_variable_length(e.type));
      }
      if (obj.code != ObjectCode::Var && sub == 0 && !writable(e.access)) {
        EXPECT_EQ(e.default_value.at(0), obj.entries.rbegin()->first);
      }
    }
  }
}

// ---- abort codes ----------------------------------------------------------------------------

TEST_F(DeviceDictionaryRules, EveryAbortCodeOfTheDeviceDictionary) {
  EXPECT_EQ(od.read(0x5002, 6).abort, SdoAbort::WriteOnly);                      // 0x06010001
  EXPECT_EQ(w32(0x1000, 0, 1), SdoAbort::ReadOnly);                              // 0x06010002
  EXPECT_EQ(od.write(0x1008, 0, encode_string("y")), SdoAbort::ReadOnly);        // const
  EXPECT_EQ(od.read(0x1F00, 0).abort, SdoAbort::NoObject);                       // 0x06020000
  EXPECT_EQ(od.read(0x1018, 5).abort, SdoAbort::NoSubindex);                     // 0x06090011
  EXPECT_EQ(od.write(0x1017, 0, encode<uint32_t>(5)), SdoAbort::LengthTooHigh);  // 0x06070012
  EXPECT_EQ(od.write(0x1017, 0, Bytes{5}), SdoAbort::LengthTooLow);              // 0x06070013
  EXPECT_EQ(od.write(0x2F01, 0, Bytes(user::kDataMaxLength + 1, 0)), SdoAbort::LengthTooHigh);
  EXPECT_EQ(od.write(0x2F01, 0, Bytes(user::kDataMaxLength, 0)), SdoAbort::None);
  EXPECT_EQ(w8(0x1003, 0, 1), SdoAbort::InvalidValue);                                 // 0x06090030
  EXPECT_EQ(w8(0x1A00, 0, 9), SdoAbort::ValueTooHigh);                                 // 0x06090031
  EXPECT_EQ(od.write(0x2002, 0, encode<int32_t>(-8'388'609)), SdoAbort::ValueTooLow);  // 0x06090032
  EXPECT_EQ(w32(0x1800, 1, kInvalid | kNoRtr | 0x185), SdoAbort::None);
  EXPECT_EQ(w8(0x1A00, 0, 0), SdoAbort::None);
  EXPECT_EQ(w32(0x1A00, 1, 0x10170010), SdoAbort::NotMappable);            // 0x06040041
  EXPECT_EQ(w32(0x1A00, 1, 0x2F000110), SdoAbort::ParameterIncompatible);  // 0x06040043
  EXPECT_EQ(w32(0x1A00, 1, 0x2F000120), SdoAbort::None);
  EXPECT_EQ(w32(0x1A00, 2, 0x2F000220), SdoAbort::None);
  EXPECT_EQ(w32(0x1A00, 3, 0x10010008), SdoAbort::None);
  EXPECT_EQ(w8(0x1A00, 0, 3), SdoAbort::PdoTooLong);  // 0x06040042
  EXPECT_EQ(w32(0x1016, 1, 0x00070064), SdoAbort::None);
  EXPECT_EQ(w32(0x1016, 2, 0x000700C8), SdoAbort::ParameterIncompatible);  // 0x06040043
  EXPECT_EQ(w32(0x1010, 1, 0x12345678), SdoAbort::DataTransfer);           // 0x08000020
  EXPECT_EQ(w32(0x1011, 1, 0x12345678), SdoAbort::DataTransfer);
  EXPECT_EQ(w8(0x1A01, 0, 0), SdoAbort::DeviceState);  // 0x08000022
  EXPECT_EQ(w32(0x1006, 0, 1000), SdoAbort::None);
  EXPECT_EQ(w8(0x1019, 0, 2), SdoAbort::DeviceState);
}

TEST_F(DeviceDictionaryRules, ReadOnlyAndConstObjectsOfTheCommunicationArea) {
  struct At {
    uint16_t index;
    uint8_t sub;
  };
  for (At a : {At{0x1000, 0}, At{0x1001, 0}, At{0x1003, 1}, At{0x1003, 8}, At{0x1008, 0},
               At{0x1009, 0}, At{0x100A, 0}, At{0x1010, 0}, At{0x1011, 0}, At{0x1016, 0},
               At{0x1018, 0}, At{0x1018, 1}, At{0x1018, 4}, At{0x1021, 0}, At{0x1022, 0},
               At{0x1200, 0}, At{0x1200, 1}, At{0x1200, 2}, At{0x1400, 0}, At{0x1800, 0}}) {
    SCOPED_TRACE(testing::Message() << std::hex << a.index << ":" << int(a.sub));
    EXPECT_EQ(od.check_write_access(a.index, a.sub), SdoAbort::ReadOnly);
    EXPECT_TRUE(od.read(a.index, a.sub).ok());
  }
}

// ---- the PDO mapping procedure (CiA 301 7.5.2.36 / 7.5.2.38) ------------------------------

TEST_F(DeviceDictionaryRules, TpdoMappingProcedureAndTheRefusalAtEachWrongStep) {
  // While the PDO exists, neither the entries nor their number may change.
  EXPECT_EQ(w32(0x1A00, 1, 0x2F000120), SdoAbort::DeviceState);
  EXPECT_EQ(w8(0x1A00, 0, 0), SdoAbort::DeviceState);
  EXPECT_EQ(w8(0x1A00, 0, 2), SdoAbort::DeviceState);  // not even to the same number
  // 1. Destroy the PDO: bit 31 of 0x1800:1.
  EXPECT_EQ(w32(0x1800, 1, kInvalid | kNoRtr | 0x185), SdoAbort::None);
  // Entries still refused while the number of mapped objects is not 0.
  EXPECT_EQ(w32(0x1A00, 1, 0x2F000120), SdoAbort::DeviceState);
  // 2. Disable the mapping: 0x1A00:0 = 0.
  EXPECT_EQ(w8(0x1A00, 0, 0), SdoAbort::None);
  // 3. Write the entries; each is checked as it is written.
  EXPECT_EQ(w32(0x1A00, 1, 0x30000020), SdoAbort::NoObject);
  EXPECT_EQ(w32(0x1A00, 1, 0x2F000920), SdoAbort::NoSubindex);
  EXPECT_EQ(w32(0x1A00, 1, 0x10080008), SdoAbort::NotMappable);  // VISIBLE_STRING
  EXPECT_EQ(w32(0x1A00, 1, 0x10170010), SdoAbort::NotMappable);  // not PDO-mappable
  EXPECT_EQ(w32(0x1A00, 1, 0x00050008), SdoAbort::NotMappable);  // dummy in a TPDO
  EXPECT_EQ(w32(0x1A00, 1, 0x2F000108), SdoAbort::ParameterIncompatible);
  EXPECT_EQ(w32(0x1A00, 1, 0x2F000140), SdoAbort::ParameterIncompatible);
  EXPECT_EQ(od.get<uint32_t>(0x1A00, 1), 0x20010010u);  // refused words are not stored
  EXPECT_EQ(w32(0x1A00, 1, 0x2F000120), SdoAbort::None);
  EXPECT_EQ(w32(0x1A00, 2, 0x10010008), SdoAbort::None);  // error register (read-only)
  EXPECT_EQ(w32(0x1A00, 3, 0x20010010), SdoAbort::None);
  EXPECT_EQ(w32(0x1A00, 4, 0), SdoAbort::None);  // 0 clears an entry
  EXPECT_EQ(w32(0x1A00, 5, 0x2F000220), SdoAbort::None);
  // 4. Enable the mapping with the number of entries: each is checked again, and the total.
  EXPECT_EQ(w8(0x1A00, 0, 4), SdoAbort::NoObject);  // entry 4 is empty
  EXPECT_EQ(w8(0x1A00, 0, 5), SdoAbort::NoObject);
  EXPECT_EQ(w8(0x1A00, 0, 9), SdoAbort::ValueTooHigh);  // only 8 entries
  EXPECT_EQ(w32(0x1A00, 4, 0x2F000320), SdoAbort::None);
  EXPECT_EQ(w8(0x1A00, 0, 4), SdoAbort::PdoTooLong);  // 32+8+16+32 = 88 bits
  EXPECT_EQ(od.get<uint8_t>(0x1A00, 0), 0);
  EXPECT_EQ(w8(0x1A00, 0, 3), SdoAbort::None);  // 56 bits
  // Once enabled, the entries are fixed again.
  EXPECT_EQ(w32(0x1A00, 1, 0x2F000420), SdoAbort::DeviceState);
  // 5. Create the PDO again.
  EXPECT_EQ(w32(0x1800, 1, kNoRtr | 0x185), SdoAbort::None);
  EXPECT_EQ(w8(0x1A00, 0, 0), SdoAbort::DeviceState);

  od.put<uint32_t>(0x2F00, 1, 0x11223344);
  od.put<uint8_t>(0x1001, 0, 0x81);
  od.put<uint16_t>(0x2001, 0, 0xBEEF);
  PdoMapping mapping;
  for (uint8_t i = 1; i <= od.get<uint8_t>(0x1A00, 0); ++i)
    mapping.push_back(MappedEntry::from_word(od.get<uint32_t>(0x1A00, i)));
  EXPECT_EQ(pack_pdo(od, mapping),
            (std::vector<uint8_t>{0x44, 0x33, 0x22, 0x11, 0x81, 0xEF, 0xBE}));
}

TEST_F(DeviceDictionaryRules, RpdoMappingProcedureWithDummies) {
  EXPECT_EQ(w32(0x1600, 1, 0x2F000120), SdoAbort::DeviceState);
  EXPECT_EQ(w32(0x1400, 1, kInvalid | 0x205), SdoAbort::None);  // 1.
  EXPECT_EQ(w32(0x1600, 1, 0x2F000120), SdoAbort::DeviceState);
  EXPECT_EQ(w8(0x1600, 0, 0), SdoAbort::None);                   // 2.
  EXPECT_EQ(w32(0x1600, 1, 0x10010008), SdoAbort::NotMappable);  // read-only: not received
  EXPECT_EQ(w32(0x1600, 1, 0x20010010), SdoAbort::NotMappable);  // status bits: read-only
  EXPECT_EQ(w32(0x1600, 1, 0x00010001), SdoAbort::NotMappable);  // BOOLEAN dummy: unsupported
  EXPECT_EQ(w32(0x1600, 1, 0x00070010), SdoAbort::ParameterIncompatible);
  EXPECT_EQ(w32(0x1600, 1, 0x00050008), SdoAbort::None);  // 3. dummy U8
  EXPECT_EQ(w32(0x1600, 2, 0x2F000120), SdoAbort::None);
  EXPECT_EQ(w32(0x1600, 3, 0x00060010), SdoAbort::None);  // dummy U16
  EXPECT_EQ(w32(0x1600, 4, 0x00050008), SdoAbort::None);
  EXPECT_EQ(w8(0x1600, 0, 4), SdoAbort::None);       // 4. 64 bits
  EXPECT_EQ(w32(0x1400, 1, 0x205), SdoAbort::None);  // 5.

  PdoMapping mapping;
  for (uint8_t i = 1; i <= 4; ++i)
    mapping.push_back(MappedEntry::from_word(od.get<uint32_t>(0x1600, i)));
  EXPECT_EQ(
      unpack_pdo(od, mapping, std::vector<uint8_t>{0xEE, 0x78, 0x56, 0x34, 0x12, 0xDD, 0xDD, 0xCC}),
      SdoAbort::None);
  EXPECT_EQ(od.get<uint32_t>(0x2F00, 1), 0x12345678u);
}

// ---- COB-ID rules -------------------------------------------------------------------------

// CiA 301 7.3.5 table 43: the CAN-IDs no configurable object may use.
TEST(RestrictedCanIds, TheCiA301Table) {
  auto restricted = [](uint32_t id) {
    return id == 0 || (id >= 0x001 && id <= 0x07F) || (id >= 0x101 && id <= 0x180) ||
           (id >= 0x581 && id <= 0x5FF) || (id >= 0x601 && id <= 0x67F) ||
           (id >= 0x6E0 && id <= 0x6FF) || (id >= 0x701 && id <= 0x77F) || id >= 0x780;
  };
  for (uint32_t id = 0; id <= 0x7FF; ++id)
    EXPECT_EQ(is_restricted_can_id(id), restricted(id)) << std::hex << id;
  for (uint32_t id : {0x080u, 0x100u, 0x181u, 0x580u, 0x600u, 0x680u, 0x6DFu, 0x700u})
    EXPECT_FALSE(is_restricted_can_id(id)) << std::hex << id;
}

TEST_F(DeviceDictionaryRules, PdoCobIdCannotChangeItsCanIdWhileValid) {
  for (uint16_t comm : {uint16_t{0x1800}, uint16_t{0x1400}}) {
    SCOPED_TRACE(testing::Message() << std::hex << comm);
    uint32_t rtr = comm == 0x1800 ? kNoRtr : 0;
    uint32_t id = od.get<uint32_t>(comm, 1) & 0x7FF;
    EXPECT_EQ(w32(comm, 1, rtr | (id + 1)), SdoAbort::InvalidValue);
    EXPECT_EQ(w32(comm, 1, rtr | id), SdoAbort::None);  // the same ID again is fine
    // Invalidate (and change the ID in the same write), then make valid with the new ID.
    EXPECT_EQ(w32(comm, 1, kInvalid | rtr | 0x1E5), SdoAbort::None);
    EXPECT_EQ(w32(comm, 1, kInvalid | rtr | 0x1E6), SdoAbort::None);
    EXPECT_EQ(w32(comm, 1, rtr | 0x1E6), SdoAbort::None);
    EXPECT_EQ(od.get<uint32_t>(comm, 1), rtr | 0x1E6);
    EXPECT_EQ(w32(comm, 1, rtr | 0x1E5), SdoAbort::InvalidValue);
  }
}

TEST_F(DeviceDictionaryRules, PdoCobIdBaseFramesOnly) {
  for (uint16_t comm : {uint16_t{0x1800}, uint16_t{0x1400}, uint16_t{0x1804}, uint16_t{0x1405}}) {
    SCOPED_TRACE(testing::Message() << std::hex << comm);
    uint32_t before = od.get<uint32_t>(comm, 1);
    uint32_t id = before & 0x7FF;
    EXPECT_EQ(w32(comm, 1, (before & ~0x7FFu) | kFrame | id), SdoAbort::InvalidValue);  // bit 29
    EXPECT_EQ(w32(comm, 1, kInvalid | kFrame | 0x1234567), SdoAbort::InvalidValue);
    // Bits 11..28 are 0 with an 11-bit CAN-ID, valid or not.
    for (uint32_t bit = 11; bit <= 28; ++bit) {
      EXPECT_EQ(w32(comm, 1, before | (1u << bit)), SdoAbort::InvalidValue) << bit;
      EXPECT_EQ(w32(comm, 1, kInvalid | (1u << bit) | 0x1E5), SdoAbort::InvalidValue) << bit;
    }
    EXPECT_EQ(od.get<uint32_t>(comm, 1), before);
  }
}

TEST_F(DeviceDictionaryRules, PdoCobIdRestrictedIdsOnlyWhileInvalid) {
  for (uint16_t comm : {uint16_t{0x1801}, uint16_t{0x1401}}) {
    SCOPED_TRACE(testing::Message() << std::hex << comm);
    for (uint32_t id : {0x000u, 0x001u, 0x07Fu, 0x101u, 0x180u, 0x581u, 0x5FFu, 0x601u, 0x67Fu,
                        0x6E0u, 0x6FFu, 0x701u, 0x77Fu, 0x780u, 0x7FFu}) {
      EXPECT_EQ(w32(comm, 1, kInvalid | id), SdoAbort::None) << std::hex << id;
      EXPECT_EQ(w32(comm, 1, id), SdoAbort::InvalidValue) << std::hex << id;
    }
    for (uint32_t id : {0x080u, 0x100u, 0x181u, 0x580u, 0x600u, 0x680u, 0x6DFu, 0x700u}) {
      EXPECT_EQ(w32(comm, 1, kInvalid | id), SdoAbort::None) << std::hex << id;
      EXPECT_EQ(w32(comm, 1, id), SdoAbort::None) << std::hex << id;
    }
  }
}

TEST_F(DeviceDictionaryRules, EmcyCobId) {
  EXPECT_EQ(w32(0x1014, 0, 0x86), SdoAbort::InvalidValue);  // CAN-ID change while valid
  EXPECT_EQ(w32(0x1014, 0, 0x85), SdoAbort::None);
  EXPECT_EQ(w32(0x1014, 0, kFrame | 0x85), SdoAbort::InvalidValue);  // 29-bit
  EXPECT_EQ(w32(0x1014, 0, 0x00010085), SdoAbort::InvalidValue);     // bits 11..28
  EXPECT_EQ(w32(0x1014, 0, kNoRtr | 0x85), SdoAbort::InvalidValue);  // bit 30 is reserved (0)
  EXPECT_EQ(w32(0x1014, 0, kInvalid | 0x85), SdoAbort::None);        // EMCY off
  EXPECT_EQ(w32(0x1014, 0, kInvalid | 0x701), SdoAbort::None);
  EXPECT_EQ(w32(0x1014, 0, 0x701), SdoAbort::InvalidValue);  // restricted
  EXPECT_EQ(w32(0x1014, 0, 0x0FF), SdoAbort::None);          // on, another ID
  EXPECT_EQ(od.get<uint32_t>(0x1014, 0), 0x0FFu);
}

TEST_F(DeviceDictionaryRules, SyncCobId) {
  EXPECT_EQ(w32(0x1005, 0, 0x81), SdoAbort::None);  // consumer: the ID may change
  EXPECT_EQ(w32(0x1005, 0, 0x80), SdoAbort::None);
  EXPECT_EQ(w32(0x1005, 0, kNoRtr | 0x80), SdoAbort::None);          // become the producer
  EXPECT_EQ(w32(0x1005, 0, kNoRtr | 0x81), SdoAbort::InvalidValue);  // no change while producing
  EXPECT_EQ(w32(0x1005, 0, 0x80), SdoAbort::None);                   // stop producing
  EXPECT_EQ(w32(0x1005, 0, kFrame | 0x80), SdoAbort::InvalidValue);  // 29-bit
  EXPECT_EQ(w32(0x1005, 0, 0x00000880), SdoAbort::InvalidValue);     // bit 11
  EXPECT_EQ(w32(0x1005, 0, 0x10000080), SdoAbort::InvalidValue);     // bit 28
  for (uint32_t id : {0x000u, 0x001u, 0x07Fu, 0x101u, 0x581u, 0x601u, 0x701u, 0x7FFu})
    EXPECT_EQ(w32(0x1005, 0, id), SdoAbort::InvalidValue) << std::hex << id;  // restricted
  EXPECT_EQ(od.get<uint32_t>(0x1005, 0), 0x80u);
}

// ---- transmission type, inhibit time, SYNC start value -------------------------------------

TEST_F(DeviceDictionaryRules, TransmissionTypes241To253AreRefused) {
  for (uint16_t comm : {uint16_t{0x1400}, uint16_t{0x1800}, uint16_t{0x1405}, uint16_t{0x1806}}) {
    for (unsigned type = 0; type <= 255; ++type) {
      SdoAbort want = type <= 240 || type >= 254 ? SdoAbort::None : SdoAbort::InvalidValue;
      EXPECT_EQ(w8(comm, 2, type), want) << std::hex << comm << " type " << std::dec << type;
    }
    EXPECT_EQ(od.get<uint8_t>(comm, 2), 255);  // the last accepted value
  }
}

TEST_F(DeviceDictionaryRules, InhibitTimeAndSyncStartOnlyWhileThePdoIsInvalid) {
  EXPECT_EQ(od.get<uint16_t>(0x1801, 3), 100);  // TPDO2 of each axis: 10 ms
  EXPECT_EQ(w16(0x1800, 3, 10), SdoAbort::InvalidValue);
  EXPECT_EQ(w8(0x1800, 6, 3), SdoAbort::InvalidValue);
  EXPECT_EQ(w16(0x1800, 5, 500), SdoAbort::None);  // the event timer may change any time
  EXPECT_EQ(w32(0x1800, 1, kInvalid | kNoRtr | 0x185), SdoAbort::None);
  EXPECT_EQ(w16(0x1800, 3, 10), SdoAbort::None);
  EXPECT_EQ(w8(0x1800, 6, 3), SdoAbort::None);
  EXPECT_EQ(w8(0x1800, 6, 240), SdoAbort::None);
  EXPECT_EQ(w8(0x1800, 6, 241), SdoAbort::ValueTooHigh);  // 241..255 reserved
  EXPECT_EQ(w8(0x1800, 6, 255), SdoAbort::ValueTooHigh);
  EXPECT_EQ(w32(0x1800, 1, kNoRtr | 0x185), SdoAbort::None);
  EXPECT_EQ(w16(0x1800, 3, 20), SdoAbort::InvalidValue);
  EXPECT_EQ(od.get<uint16_t>(0x1800, 3), 10);
  EXPECT_EQ(od.get<uint8_t>(0x1800, 6), 240);
  EXPECT_EQ(od.get<uint16_t>(0x1800, 5), 500);
  EXPECT_EQ(w16(0x1400, 5, 100), SdoAbort::None);  // RPDO deadline timer
}

// ---- error history, SYNC counter, heartbeat consumer, store/restore ----------------------

TEST_F(DeviceDictionaryRules, ErrorHistoryWrite0ClearsOtherValuesRefused) {
  od.put<uint8_t>(0x1003, 0, 3);
  for (uint8_t i = 1; i <= 3; ++i) od.put<uint32_t>(0x1003, i, 0x8130u + i);
  for (unsigned v = 1; v <= 255; ++v) EXPECT_EQ(w8(0x1003, 0, v), SdoAbort::InvalidValue) << v;
  EXPECT_EQ(od.get<uint8_t>(0x1003, 0), 3);
  EXPECT_EQ(r32(0x1003, 1), 0x8131u);
  EXPECT_EQ(w32(0x1003, 1, 0), SdoAbort::ReadOnly);
  EXPECT_EQ(od.read(0x1003, kErrorHistoryLength + 1).abort, SdoAbort::NoSubindex);
  EXPECT_EQ(w8(0x1003, 0, 0), SdoAbort::None);
  EXPECT_EQ(od.get<uint8_t>(0x1003, 0), 0);
  for (uint8_t i = 1; i <= kErrorHistoryLength; ++i) EXPECT_EQ(r32(0x1003, i), 0u) << int(i);
}

TEST_F(DeviceDictionaryRules, SyncCounterOverflowValuesAndOnlyWhileThePeriodIs0) {
  for (unsigned v = 0; v <= 255; ++v) {
    SdoAbort want = v == 1 || v > 240 ? SdoAbort::InvalidValue : SdoAbort::None;
    EXPECT_EQ(w8(0x1019, 0, v), want) << v;
  }
  EXPECT_EQ(od.get<uint8_t>(0x1019, 0), 240);
  EXPECT_EQ(w32(0x1006, 0, 10000), SdoAbort::None);
  EXPECT_EQ(w8(0x1019, 0, 0), SdoAbort::DeviceState);
  EXPECT_EQ(w8(0x1019, 0, 240), SdoAbort::DeviceState);
  EXPECT_EQ(w8(0x1019, 0, 1), SdoAbort::InvalidValue);  // the value is checked first
  EXPECT_EQ(w32(0x1006, 0, 0), SdoAbort::None);
  EXPECT_EQ(w8(0x1019, 0, 10), SdoAbort::None);
}

TEST_F(DeviceDictionaryRules, HeartbeatConsumerOneEntryPerNode) {
  EXPECT_EQ(w32(0x1016, 1, 0x000701F4), SdoAbort::None);  // node 7, 500 ms
  EXPECT_EQ(w32(0x1016, 2, 0x00070064), SdoAbort::ParameterIncompatible);
  EXPECT_EQ(w32(0x1016, 4, 0x000703E8), SdoAbort::ParameterIncompatible);
  EXPECT_EQ(w32(0x1016, 2, 0x00070000), SdoAbort::None);          // time 0: entry not used
  EXPECT_EQ(w32(0x1016, 3, 0x00080064), SdoAbort::None);          // another node
  EXPECT_EQ(w32(0x1016, 1, 0x00070064), SdoAbort::None);          // its own entry may change
  EXPECT_EQ(w32(0x1016, 4, 0x00000064), SdoAbort::None);          // node 0: not used
  EXPECT_EQ(w32(0x1016, 4, 0x00800064), SdoAbort::None);          // node 128: not used
  EXPECT_EQ(w32(0x1016, 4, 0x01080064), SdoAbort::InvalidValue);  // bits 24..31 reserved
  EXPECT_EQ(w32(0x1016, 1, 0), SdoAbort::None);
  EXPECT_EQ(w32(0x1016, 2, 0x00070064), SdoAbort::None);  // node 7 free again
  EXPECT_EQ(r32(0x1016, 2), 0x00070064u);
}

TEST_F(DeviceDictionaryRules, StoreAndRestoreNeedTheirSignature) {
  EXPECT_EQ(encode<uint32_t>(kSaveSignature), encode_string("save"));
  EXPECT_EQ(encode<uint32_t>(kLoadSignature), encode_string("load"));
  for (const auto& g : kParameterGroups) {
    SCOPED_TRACE(g.name);
    EXPECT_EQ(r32(0x1010, g.sub), 1u);  // saves on command
    EXPECT_EQ(r32(0x1011, g.sub), 1u);
    EXPECT_EQ(w32(0x1010, g.sub, 0), SdoAbort::DataTransfer);
    EXPECT_EQ(w32(0x1010, g.sub, kLoadSignature), SdoAbort::DataTransfer);
    EXPECT_EQ(w32(0x1011, g.sub, kSaveSignature), SdoAbort::DataTransfer);
    EXPECT_EQ(w32(0x1010, g.sub, 0x45564153), SdoAbort::DataTransfer);  // "SAVE"
    EXPECT_EQ(od.write(0x1010, g.sub, Bytes{'s', 'a', 'v'}), SdoAbort::LengthTooLow);
    EXPECT_EQ(w32(0x1010, g.sub, kSaveSignature), SdoAbort::None);
    EXPECT_EQ(w32(0x1011, g.sub, kLoadSignature), SdoAbort::None);
    EXPECT_EQ(r32(0x1010, g.sub), 1u);  // reads the capability, not the signature
  }
  EXPECT_EQ(od.locate(0x1010, 5), SdoAbort::NoSubindex);
  EXPECT_EQ(static_cast<uint32_t>(SdoAbort::DataTransfer), 0x08000020u);
}

}  // namespace
}  // namespace stepnode::od
