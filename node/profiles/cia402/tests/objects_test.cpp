// The CiA 402 object table (node/profiles/cia402/objects.*) in a dictionary with the CiA 301
// communication objects: each object as CiA 402-2 describes it (index, axis 2 at +0x800,
// data type, access, PDO mapping) with its default, the value ranges (6060h refuses a mode
// this drive does not have), what is stored, the default PDOs, and the objects in the EDS.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "node/profiles/cia402/drive_state.hpp"
#include "node/profiles/cia402/objects.hpp"
#include "od/communication_objects.hpp"
#include "od/eds.hpp"
#include "od/pdo_mapping.hpp"

namespace stepnode::cia402 {
namespace {

using od::Access;
using od::DataType;
using od::SdoAbort;
using DT = od::DataType;
constexpr Access RO = Access::ReadOnly, RW = Access::ReadWrite;

struct Row {
  uint16_t index;  // axis 1
  uint8_t sub;
  DataType type;
  Access access;
  bool pdo;         // PDO-mappable (CiA 402-2 "PDO mapping": yes, or optional and chosen here)
  bool persistent;  // stored by 0x1010: the settings, not the commands and set-points
  int64_t value;    // default: the standard's where it gives one, else this drive's (objects.cpp)
};

// The table as CiA 402-2 describes the objects.
const std::vector<Row> kTable = {
    {0x6007, 0, DT::Integer16, RW, false, true, 1},  // abort connection: 1 fault signal
    {0x603F, 0, DT::Unsigned16, RO, true, false, 0},
    {0x6040, 0, DT::Unsigned16, RW, true, false, 0},
    {0x6041, 0, DT::Unsigned16, RO, true, false, 0x0200},
    {0x605A, 0, DT::Integer16, RW, false, true, 2},
    {0x605B, 0, DT::Integer16, RW, false, true, 0},
    {0x605C, 0, DT::Integer16, RW, false, true, 1},
    {0x605D, 0, DT::Integer16, RW, false, true, 1},
    {0x605E, 0, DT::Integer16, RW, false, true, 2},
    {0x6060, 0, DT::Integer8, RW, true, false, 0},
    {0x6061, 0, DT::Integer8, RO, true, false, 0},
    {0x6062, 0, DT::Integer32, RO, true, false, 0},
    {0x6063, 0, DT::Integer32, RO, true, false, 0},
    {0x6064, 0, DT::Integer32, RO, true, false, 0},
    {0x6065, 0, DT::Unsigned32, RW, false, true, 0xFFFFFFFF},  // following error control off
    {0x6066, 0, DT::Unsigned16, RW, false, true, 0},
    {0x6067, 0, DT::Unsigned32, RW, false, true, 0},
    {0x6068, 0, DT::Unsigned16, RW, false, true, 0},
    {0x606C, 0, DT::Integer32, RO, true, false, 0},
    {0x607A, 0, DT::Integer32, RW, true, false, 0},
    {0x607C, 0, DT::Integer32, RW, false, true, 0},
    {0x607D, 1, DT::Integer32, RW, false, true, INT32_MIN},
    {0x607D, 2, DT::Integer32, RW, false, true, INT32_MAX},
    {0x607F, 0, DT::Unsigned32, RW, false, true, 10000},
    {0x6081, 0, DT::Unsigned32, RW, true, true, 1000},
    {0x6083, 0, DT::Unsigned32, RW, false, true, 1000},
    {0x6084, 0, DT::Unsigned32, RW, false, true, 1000},
    {0x6085, 0, DT::Unsigned32, RW, false, true, 10000},
    {0x6086, 0, DT::Integer16, RW, false, true, 0},  // linear ramp
    {0x608F, 1, DT::Unsigned32, RW, false, true, 1},
    {0x608F, 2, DT::Unsigned32, RW, false, true, 1},
    {0x6091, 1, DT::Unsigned32, RW, false, true, 1},
    {0x6091, 2, DT::Unsigned32, RW, false, true, 1},
    {0x6092, 1, DT::Unsigned32, RW, false, true, 1},
    {0x6092, 2, DT::Unsigned32, RW, false, true, 1},
    {0x6098, 0, DT::Integer8, RW, false, true, 0},
    {0x6099, 1, DT::Unsigned32, RW, false, true, 1000},
    {0x6099, 2, DT::Unsigned32, RW, false, true, 100},
    {0x609A, 0, DT::Unsigned32, RW, false, true, 1000},
    {0x60A4, 1, DT::Unsigned32, RW, false, true, 10000},  // begin acceleration jerk
    {0x60A4, 2, DT::Unsigned32, RW, false, true, 10000},  // begin deceleration jerk
    {0x60A4, 3, DT::Unsigned32, RW, false, true, 10000},  // end acceleration jerk
    {0x60A4, 4, DT::Unsigned32, RW, false, true, 10000},  // end deceleration jerk
    {0x60B0, 0, DT::Integer32, RW, true, false, 0},
    {0x60B1, 0, DT::Integer32, RW, true, false, 0},
    {0x60C0, 0, DT::Integer16, RW, false, true, 0},  // linear interpolation
    {0x60C1, 1, DT::Integer32, RW, true, false, 0},
    {0x60C2, 1, DT::Unsigned8, RW, false, true, 1},  // 1 ms = 1 * 10^-3 s
    {0x60C2, 2, DT::Integer8, RW, false, true, -3},
    {0x60F4, 0, DT::Integer32, RO, true, false, 0},
    {0x60FD, 0, DT::Unsigned32, RO, true, false, 0},
    {0x60FF, 0, DT::Integer32, RW, true, false, 0},
    {0x6502, 0, DT::Unsigned32, RO, false, false, 0x1E5},       // pp, pv, hm, ip, csp, csv
    {0x67FF, 0, DT::Unsigned32, RO, false, false, 0x00040192},  // profile 402, stepper drive
};
// The arrays and the record (the others are VARs), with their highest sub-index.
const std::vector<std::pair<uint16_t, uint8_t>> kComposite = {
    {0x607D, 2}, {0x608F, 2}, {0x6091, 2}, {0x6092, 2}, {0x6099, 2}, {0x60C1, 1}, {0x60C2, 2}};

int64_t number(DataType type, const od::Bytes& v) {
  if (od::is_signed_integer(type)) return od::as_signed(type, v);
  return static_cast<int64_t>(od::as_unsigned(type, v));
}

class Cia402Objects : public ::testing::Test {
 protected:
  void SetUp() override {
    od::build_communication_objects(od, info, 4);
    add_objects(od, 2);
    set_default_pdos(od, 0, 0, 0);
    set_default_pdos(od, 1, 2, 2);
  }
  template <class T>
  SdoAbort write(uint16_t index, uint8_t sub, T v, od::WriteOrigin origin = od::WriteOrigin::Sdo) {
    return od.write(index, sub, od::encode<T>(v), origin);
  }
  od::DeviceInfo info{.node_id = 5};
  od::Dictionary od;
};

TEST_F(Cia402Objects, EachObjectAsTheStandardDescribesIt) {
  for (unsigned axis = 0; axis < 2; ++axis) {
    for (const Row& row : kTable) {
      const uint16_t index = static_cast<uint16_t>(row.index + 0x800 * axis);
      SCOPED_TRACE(testing::Message() << std::hex << index << ":" << int{row.sub});
      EXPECT_EQ(index, obj::index(axis, row.index));
      const od::Entry* e = od.find(index, row.sub);
      ASSERT_NE(e, nullptr);
      EXPECT_EQ(e->type, row.type);
      EXPECT_EQ(e->access, row.access);
      EXPECT_EQ(e->pdo_mappable, row.pdo);
      EXPECT_EQ(e->persistent, row.persistent);
      EXPECT_EQ(number(row.type, e->default_value), row.value);
      EXPECT_EQ(e->value, e->default_value);
    }
    for (auto [index, highest] : kComposite) {
      const od::Object* o = od.object(obj::index(axis, index));
      ASSERT_NE(o, nullptr);
      const auto code = index == 0x60C2 ? od::ObjectCode::Record : od::ObjectCode::Array;
      EXPECT_EQ(o->code, code) << std::hex << index;
      EXPECT_EQ(od.get<uint8_t>(o->index, 0), highest) << std::hex << index;
    }
  }
  EXPECT_EQ(od.object(0x7040), nullptr);  // only the configured axes: axis 3 would be there
  // Every object of axis 1 is one of the table's.
  std::set<uint16_t> table, present;
  for (const Row& row : kTable) table.insert(row.index);
  for (const auto& [index, object] : od.objects())
    if (index >= 0x6000 && index <= 0x67FF) present.insert(index);
  EXPECT_EQ(present, table);
  EXPECT_EQ(table.size(), 45u);
}

TEST_F(Cia402Objects, SampledValuesAreThePositionsAndVelocities) {
  for (uint16_t index : {0x6062, 0x6063, 0x6064, 0x606C, 0x60F4})
    EXPECT_TRUE(od.at(index, 0).pdo_sampled);
  for (uint16_t index : {0x6041, 0x6061, 0x60FD, 0x603F}) EXPECT_FALSE(od.at(index, 0).pdo_sampled);
}

TEST_F(Cia402Objects, ModesOfOperationRefusesAModeThisDriveHasNot) {
  const std::vector<int> supported = {0, 1, 3, 6, 7, 8, 9};  // 6502h
  for (uint16_t index : {obj::index(0, 0x6060), obj::index(1, 0x6060)}) {
    for (int mode = -128; mode <= 127; ++mode) {
      const bool ok = std::find(supported.begin(), supported.end(), mode) != supported.end();
      const SdoAbort expected = ok ? SdoAbort::None : SdoAbort::InvalidValue;
      EXPECT_EQ(write<int8_t>(index, 0, static_cast<int8_t>(mode)), expected) << mode;
      EXPECT_EQ(mode_supported(static_cast<int8_t>(mode)), ok) << mode;
    }
    EXPECT_EQ(od.get<int8_t>(index, 0), 9);  // the last mode accepted stays
  }
  // An RPDO carrying profile torque (4) is refused the same way.
  EXPECT_EQ(write<int8_t>(0x6060, 0, 4, od::WriteOrigin::Pdo), SdoAbort::InvalidValue);
}

TEST_F(Cia402Objects, OptionCodesTakeTheStandardsValuesOnly) {
  struct Range {
    uint16_t index;
    int16_t low, high;
  };
  // 605Ah 0..8, 605Bh/605Ch 0..1, 605Dh 1..4 (0 reserved), 605Eh 0..4, 6007h 0..3.
  for (Range r : {Range{0x605A, 0, 8}, Range{0x605B, 0, 1}, Range{0x605C, 0, 1},
                  Range{0x605D, 1, 4}, Range{0x605E, 0, 4}, Range{0x6007, 0, 3}}) {
    SCOPED_TRACE(testing::Message() << std::hex << r.index);
    EXPECT_EQ(write<int16_t>(r.index, 0, r.low), SdoAbort::None);
    EXPECT_EQ(write<int16_t>(r.index, 0, r.high), SdoAbort::None);
    EXPECT_EQ(write<int16_t>(r.index, 0, static_cast<int16_t>(r.high + 1)), SdoAbort::ValueTooHigh);
    EXPECT_EQ(write<int16_t>(r.index, 0, static_cast<int16_t>(r.low - 1)), SdoAbort::ValueTooLow);
  }
  EXPECT_EQ(write<int16_t>(0x6086, 0, 0), SdoAbort::None);          // linear ramp
  EXPECT_EQ(write<int16_t>(0x6086, 0, 3), SdoAbort::None);          // jerk-limited ramp
  EXPECT_EQ(write<int16_t>(0x6086, 0, 1), SdoAbort::InvalidValue);  // sin^2 ramp: not offered
  EXPECT_EQ(write<int16_t>(0x6086, 0, 2), SdoAbort::InvalidValue);  // jerk-free ramp: not offered
  EXPECT_EQ(write<int16_t>(0x6086, 0, -1), SdoAbort::InvalidValue);
  EXPECT_EQ(write<int16_t>(0x60C0, 0, 1), SdoAbort::InvalidValue);
  // The standard's methods, and the manufacturer's on a hard stop (homing.hpp).
  for (int8_t method : {0, 1, 14, 17, 30, 33, 35, 37, -1, -2, -17, -18})
    EXPECT_EQ(write<int8_t>(0x6098, 0, method), SdoAbort::None) << int{method};
  for (int8_t method : {15, 16, 31, 32, 36, 38, -3, -16, -19, -128})
    EXPECT_EQ(write<int8_t>(0x6098, 0, method), SdoAbort::InvalidValue) << int{method};
  EXPECT_EQ(write<int8_t>(0x60C2, 2, 64), SdoAbort::ValueTooHigh);  // time index -128..63
  EXPECT_EQ(write<uint32_t>(0x6091, 2, 0), SdoAbort::ValueTooLow);  // a ratio term divides
  EXPECT_EQ(write<uint16_t>(0x6041, 0, 0), SdoAbort::ReadOnly);
}

TEST_F(Cia402Objects, TheDefaultsAreWhatTheStateMachineStartsWith) {
  const Options o;
  EXPECT_EQ(od.get<int16_t>(0x605A, 0), o.quick_stop);
  EXPECT_EQ(od.get<int16_t>(0x605B, 0), o.shutdown);
  EXPECT_EQ(od.get<int16_t>(0x605C, 0), o.disable_operation);
  EXPECT_EQ(od.get<int16_t>(0x605D, 0), o.halt);
  EXPECT_EQ(od.get<int16_t>(0x605E, 0), o.fault_reaction);
  EXPECT_EQ(od.get<uint16_t>(0x6041, 0), state_bits(State::NotReadyToSwitchOn));
}

TEST_F(Cia402Objects, DefaultPdoMappings) {
  struct Map {
    uint16_t index;
    std::vector<uint32_t> words;
  };
  const std::vector<Map> maps = {
      {0x1600, {0x60400010, 0x60600008}}, {0x1601, {0x607A0020, 0x60FF0020}},  // axis 1 RPDO 1, 2
      {0x1A00, {0x60410010, 0x60610008}}, {0x1A01, {0x60640020, 0x606C0020}},  // axis 1 TPDO 1, 2
      {0x1602, {0x68400010, 0x68600008}}, {0x1603, {0x687A0020, 0x68FF0020}},  // axis 2 RPDO 3, 4
      {0x1A02, {0x68410010, 0x68610008}}, {0x1A03, {0x68640020, 0x686C0020}},  // axis 2 TPDO 3, 4
  };
  for (const Map& m : maps) {
    SCOPED_TRACE(testing::Message() << std::hex << m.index);
    ASSERT_EQ(od.get<uint8_t>(m.index, 0), m.words.size());
    for (size_t i = 0; i < m.words.size(); ++i)
      EXPECT_EQ(od.get<uint32_t>(m.index, static_cast<uint8_t>(i + 1)), m.words[i]);
    EXPECT_EQ(od::check_mapping_record(od, m.index), SdoAbort::None);
  }
  for (uint16_t tpdo : {0x1800, 0x1801, 0x1802, 0x1803}) EXPECT_EQ(od.get<uint8_t>(tpdo, 2), 254);
  EXPECT_EQ(od.get<uint16_t>(0x1800, 3), 0);    // the status at every change
  EXPECT_EQ(od.get<uint16_t>(0x1801, 3), 100);  // the positions at most every 10 ms
  EXPECT_EQ(od.get<uint16_t>(0x1803, 3), 100);
}

TEST_F(Cia402Objects, TheObjectsAreInTheEds) {
  const od::EdsFile eds = od::parse_eds(od::write_eds(od, info));
  std::vector<std::string> listed;
  for (const auto& [key, value] : eds.sections.at("optionalobjects")) listed.push_back(value);
  for (unsigned axis = 0; axis < 2; ++axis) {
    for (const Row& row : kTable) {
      const uint16_t index = obj::index(axis, row.index);
      SCOPED_TRACE(testing::Message() << std::hex << index << ":" << int{row.sub});
      const od::EdsEntry* e = eds.find(index, row.sub);
      ASSERT_NE(e, nullptr);
      EXPECT_EQ(e->type, row.type);
      EXPECT_EQ(e->access, row.access);
      EXPECT_EQ(e->pdo_mappable, row.pdo);
      EXPECT_EQ(number(row.type, od::parse_value(row.type, e->default_value)), row.value);
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%04X", index);
      EXPECT_NE(std::find(listed.begin(), listed.end(), hex), listed.end());
    }
  }
}

}  // namespace
}  // namespace stepnode::cia402
