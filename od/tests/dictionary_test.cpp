// The object dictionary model and the CiA 301 rules every SDO/PDO write passes
// (CiA 301 7.2.4.3.17 abort codes): existence (0x06020000 / 0x06090011), access
// (0x06010001 / 0x06010002), length (0x06070012 too long / 0x06070013 too short for a
// fixed-size type; 0x06070010 is the SDO layer's code for a size-indicated transfer whose
// data does not match and never comes from the dictionary), value (0x06090030 invalid,
// 0x06090031 / 0x06090032 above / below the limits), then the entry's validate hook.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "od/dictionary.hpp"

namespace stepnode::od {
namespace {

using DT = DataType;
using AC = Access;

class DictionaryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    od.var(0x2000, "u16 rw", DT::Unsigned16, AC::ReadWrite, encode<uint16_t>(7), true);
    od.var(0x2001, "u32 ro", DT::Unsigned32, AC::ReadOnly, encode<uint32_t>(0x11223344), true);
    od.var(0x2002, "u8 const", DT::Unsigned8, AC::Const, {42});
    od.var(0x2003, "i32 wo", DT::Integer32, AC::WriteOnly, encode<int32_t>(-1), true);
    od.var(0x2004, "bool", DT::Boolean, AC::ReadWrite, {0}, true);
    Entry& lim = od.var(0x2005, "i32 limited", DT::Integer32, AC::ReadWrite, encode<int32_t>(0));
    lim.low = encode<int32_t>(-100);
    lim.high = encode<int32_t>(100);
    Entry& ulim = od.var(0x2006, "u32 limited", DT::Unsigned32, AC::ReadWrite, encode<uint32_t>(5));
    ulim.low = encode<uint32_t>(5);
    ulim.high = encode<uint32_t>(0x80000000);  // a signed view would call it negative
    Entry& slim = od.var(0x2007, "i16 limited", DT::Integer16, AC::ReadWrite, encode<int16_t>(0));
    slim.low = encode<int16_t>(-10);
    slim.high = encode<int16_t>(10);
    Entry& rlim = od.var(0x2008, "real limited", DT::Real32, AC::ReadWrite, encode<float>(0));
    rlim.low = encode<float>(-1.5f);
    rlim.high = encode<float>(2.5f);
    od.var(0x2009, "string", DT::VisibleString, AC::ReadWrite, encode_string("abc"));
    od.var(0x200A, "domain", DT::Domain, AC::ReadWrite, {}).max_length = 10;
    od.var(0x200B, "u64", DT::Unsigned64, AC::ReadWrite, encode<uint64_t>(0));
    od.var(0x200C, "i8", DT::Integer8, AC::ReadWrite, {0});

    Object& rec = od.record(0x2100, "record");
    rec.add(1, "first", DT::Unsigned8, AC::ReadWrite, {1}, true);
    rec.add(3, "third", DT::Unsigned16, AC::ReadOnly, encode<uint16_t>(3));
    Object& arr = od.record(0x2200, "array", ObjectCode::Array);
    for (uint8_t i = 1; i <= 4; ++i)
      arr.add(i, "element", DT::Unsigned32, AC::ReadWrite, encode<uint32_t>(i));
  }

  SdoAbort w(uint16_t index, uint8_t sub, Bytes data) { return od.write(index, sub, data); }

  Dictionary od;
};

// ---- the model ------------------------------------------------------------------------

TEST_F(DictionaryTest, VarHasItsValueAtSubZero) {
  const Object* obj = od.object(0x2000);
  ASSERT_NE(obj, nullptr);
  EXPECT_EQ(obj->code, ObjectCode::Var);
  EXPECT_EQ(obj->name, "u16 rw");
  ASSERT_EQ(obj->entries.size(), 1u);
  const Entry& e = obj->entries.at(0);
  EXPECT_EQ(e.index, 0x2000);
  EXPECT_EQ(e.sub, 0);
  EXPECT_EQ(e.type, DT::Unsigned16);
  EXPECT_EQ(e.access, AC::ReadWrite);
  EXPECT_TRUE(e.pdo_mappable);
  EXPECT_EQ(e.value, e.default_value);
  EXPECT_EQ(e.size(), 2u);
  EXPECT_EQ(e.bit_length(), 16u);
  EXPECT_TRUE(e.persistent);  // writable entries are stored by default
  EXPECT_FALSE(od.find(0x2001, 0)->persistent);
  EXPECT_FALSE(od.find(0x2002, 0)->pdo_mappable);
}

TEST_F(DictionaryTest, RecordSubZeroIsAConstHighestSubIndex) {
  const Object* rec = od.object(0x2100);
  ASSERT_NE(rec, nullptr);
  EXPECT_EQ(rec->code, ObjectCode::Record);
  const Entry& count = rec->entries.at(0);
  EXPECT_EQ(count.type, DT::Unsigned8);
  EXPECT_EQ(count.access, AC::Const);
  EXPECT_EQ(count.value, (Bytes{3}));  // the highest sub-index, not the number of entries
  EXPECT_EQ(rec->entries.size(), 3u);
  EXPECT_EQ(od.object(0x2200)->code, ObjectCode::Array);
  EXPECT_EQ(od.value(0x2200, 0), (Bytes{4}));
  // Adding a lower sub later does not lower it.
  od.object(0x2100)->add(2, "second", DT::Unsigned8, AC::ReadWrite, {2});
  EXPECT_EQ(od.value(0x2100, 0), (Bytes{3}));
}

TEST_F(DictionaryTest, AWritableSubZeroIsLeftToItsOwner) {
  Object& obj = od.record(0x2300, "owner counts");
  obj.entries.at(0).access = AC::ReadWrite;
  obj.add(1, "a", DT::Unsigned8, AC::ReadWrite, {0});
  obj.add(2, "b", DT::Unsigned8, AC::ReadWrite, {0});
  EXPECT_EQ(od.value(0x2300, 0), (Bytes{0}));
}

TEST_F(DictionaryTest, MappingWordIsIndexSubAndBitLength) {
  EXPECT_EQ(od.at(0x2000, 0).mapping_word(), 0x20000010u);
  EXPECT_EQ(od.at(0x2001, 0).mapping_word(), 0x20010020u);
  EXPECT_EQ(od.at(0x2004, 0).mapping_word(), 0x20040008u);  // BOOLEAN: one byte here
  EXPECT_EQ(od.at(0x200B, 0).mapping_word(), 0x200B0040u);
  EXPECT_EQ(od.at(0x2100, 1).mapping_word(), 0x21000108u);
  EXPECT_EQ(od.at(0x2200, 4).mapping_word(), 0x22000420u);
}

TEST_F(DictionaryTest, FindAtValueSetGetPut) {
  EXPECT_EQ(od.find(0x2100, 2), nullptr);
  EXPECT_EQ(od.find(0x3000, 0), nullptr);
  EXPECT_EQ(od.object(0x3000), nullptr);
  EXPECT_NE(od.find(0x2100, 3), nullptr);
  const Dictionary& cod = od;
  EXPECT_NE(cod.find(0x2100, 1), nullptr);
  EXPECT_NE(cod.object(0x2100), nullptr);
  try {
    od.at(0x2100, 5);
    FAIL() << "0x2100:05 does not exist";
  } catch (const std::out_of_range& e) {
    EXPECT_NE(std::string(e.what()).find("0x2100:05"), std::string::npos) << e.what();
  }
  EXPECT_THROW(od.value(0x3000, 0), std::out_of_range);
  EXPECT_EQ(od.get<uint32_t>(0x2001, 0), 0x11223344u);
  od.put<uint32_t>(0x2001, 0, 0xCAFE);  // the device's own view: no access check
  EXPECT_EQ(od.value(0x2001, 0), encode<uint32_t>(0xCAFE));
  od.set(0x2002, 0, {9});  // const too
  EXPECT_EQ(od.get<uint8_t>(0x2002, 0), 9);
  EXPECT_EQ(od.objects().size(), 15u);
}

TEST_F(DictionaryTest, ResetToDefaultsOnlyInTheRange) {
  EXPECT_EQ(w(0x2000, 0, encode<uint16_t>(99)), SdoAbort::None);
  EXPECT_EQ(w(0x2200, 2, encode<uint32_t>(99)), SdoAbort::None);
  od.reset_to_defaults(0x2100, 0x2FFF);
  EXPECT_EQ(od.get<uint16_t>(0x2000, 0), 99);
  EXPECT_EQ(od.get<uint32_t>(0x2200, 2), 2u);
  od.reset_to_defaults(0x2000, 0x2000);
  EXPECT_EQ(od.get<uint16_t>(0x2000, 0), 7);
}

// ---- existence and access ---------------------------------------------------------------

TEST_F(DictionaryTest, MissingObjectIs06020000AndMissingSubIs06090011) {
  EXPECT_EQ(od.locate(0x3000, 0), SdoAbort::NoObject);
  EXPECT_EQ(od.locate(0x2000, 1), SdoAbort::NoSubindex);  // a VAR has sub 0 only
  EXPECT_EQ(od.locate(0x2100, 2), SdoAbort::NoSubindex);  // a gap in a record
  EXPECT_EQ(od.locate(0x2100, 3), SdoAbort::None);
  EXPECT_EQ(od.read(0x3000, 0).abort, SdoAbort::NoObject);
  EXPECT_EQ(od.read(0x2200, 5).abort, SdoAbort::NoSubindex);
  EXPECT_EQ(w(0x3000, 0, {1}), SdoAbort::NoObject);
  EXPECT_EQ(w(0x2100, 2, {1}), SdoAbort::NoSubindex);
  EXPECT_EQ(static_cast<uint32_t>(SdoAbort::NoObject), 0x06020000u);
  EXPECT_EQ(static_cast<uint32_t>(SdoAbort::NoSubindex), 0x06090011u);
}

TEST_F(DictionaryTest, ReadingAWriteOnlyEntryIs06010001) {
  ReadResult r = od.read(0x2003, 0);
  EXPECT_EQ(r.abort, SdoAbort::WriteOnly);
  EXPECT_EQ(static_cast<uint32_t>(r.abort), 0x06010001u);
  EXPECT_FALSE(r.ok());
  EXPECT_TRUE(r.data.empty());
  // It can still be written.
  EXPECT_EQ(od.check_write_access(0x2003, 0), SdoAbort::None);
  EXPECT_EQ(w(0x2003, 0, encode<int32_t>(5)), SdoAbort::None);
  EXPECT_EQ(od.get<int32_t>(0x2003, 0), 5);
}

TEST_F(DictionaryTest, WritingReadOnlyOrConstIs06010002AndChangesNothing) {
  bool validated = false, written = false;
  Entry& ro = od.at(0x2001, 0);
  ro.validate = [&](std::span<const uint8_t>) {
    validated = true;
    return SdoAbort::None;
  };
  listen(ro, [&] { written = true; });
  EXPECT_EQ(w(0x2001, 0, encode<uint32_t>(1)), SdoAbort::ReadOnly);
  EXPECT_EQ(static_cast<uint32_t>(SdoAbort::ReadOnly), 0x06010002u);
  EXPECT_EQ(w(0x2002, 0, {1}), SdoAbort::ReadOnly);  // const
  EXPECT_EQ(w(0x2100, 0, {5}), SdoAbort::ReadOnly);  // highest sub-index
  EXPECT_EQ(w(0x2100, 3, encode<uint16_t>(1)), SdoAbort::ReadOnly);
  EXPECT_EQ(w(0x2001, 0, {1}), SdoAbort::ReadOnly);  // access is checked before length
  EXPECT_EQ(od.check_write_access(0x2001, 0), SdoAbort::ReadOnly);
  EXPECT_EQ(od.check_write_access(0x2002, 0), SdoAbort::ReadOnly);
  EXPECT_EQ(od.check_write_access(0x2000, 0), SdoAbort::None);
  EXPECT_EQ(od.check_write_access(0x3000, 0), SdoAbort::NoObject);
  EXPECT_EQ(od.check_write_access(0x2000, 1), SdoAbort::NoSubindex);
  EXPECT_EQ(od.get<uint32_t>(0x2001, 0), 0x11223344u);
  EXPECT_EQ(od.get<uint8_t>(0x2002, 0), 42);
  EXPECT_FALSE(validated);
  EXPECT_FALSE(written);
  // Reading read-only and const entries works.
  EXPECT_EQ(od.read(0x2001, 0).data, encode<uint32_t>(0x11223344));
  EXPECT_EQ(od.read(0x2002, 0).data, (Bytes{42}));
}

TEST_F(DictionaryTest, ReadRunsTheOnReadHook) {
  int reads = 0;
  od.at(0x2001, 0).on_read = [&](Bytes& v) { v = encode<uint32_t>(++reads); };
  EXPECT_EQ(od.read(0x2001, 0).data, encode<uint32_t>(1));
  EXPECT_EQ(od.read(0x2001, 0).data, encode<uint32_t>(2));
  EXPECT_EQ(od.get<uint32_t>(0x2001, 0), 2u);  // the refreshed value stays
  EXPECT_TRUE(od.read(0x2001, 0).ok());
}

// ---- length -------------------------------------------------------------------------

TEST_F(DictionaryTest, FixedSizeTooLongIs06070012TooShortIs06070013) {
  struct Case {
    uint16_t index;
    size_t size;
  };
  for (Case c : {Case{0x2000, 2}, Case{0x2004, 1}, Case{0x2005, 4}, Case{0x2008, 4},
                 Case{0x200B, 8}, Case{0x200C, 1}}) {
    SCOPED_TRACE(c.index);
    Bytes before = od.value(c.index, 0);
    EXPECT_EQ(w(c.index, 0, Bytes(c.size + 1, 0)), SdoAbort::LengthTooHigh);
    EXPECT_EQ(w(c.index, 0, Bytes(c.size - 1, 0)), SdoAbort::LengthTooLow);
    EXPECT_EQ(w(c.index, 0, Bytes{}), SdoAbort::LengthTooLow);
    EXPECT_EQ(w(c.index, 0, Bytes(8 + c.size, 0)), SdoAbort::LengthTooHigh);
    EXPECT_EQ(od.value(c.index, 0), before);
    EXPECT_EQ(w(c.index, 0, Bytes(c.size, 0)), SdoAbort::None);
  }
  EXPECT_EQ(static_cast<uint32_t>(SdoAbort::LengthTooHigh), 0x06070012u);
  EXPECT_EQ(static_cast<uint32_t>(SdoAbort::LengthTooLow), 0x06070013u);
}

TEST_F(DictionaryTest, VariableLengthUpToItsMaximum) {
  EXPECT_EQ(od.at(0x2009, 0).max_length, 255u);  // strings: at least 255 by default
  EXPECT_EQ(w(0x2009, 0, encode_string("a longer text")), SdoAbort::None);
  EXPECT_EQ(od.value(0x2009, 0), encode_string("a longer text"));
  EXPECT_EQ(od.at(0x2009, 0).size(), 13u);
  EXPECT_EQ(w(0x2009, 0, Bytes{}), SdoAbort::None);
  EXPECT_EQ(od.at(0x2009, 0).size(), 0u);
  EXPECT_EQ(w(0x2009, 0, Bytes(255, 'x')), SdoAbort::None);
  EXPECT_EQ(w(0x2009, 0, Bytes(256, 'x')), SdoAbort::LengthTooHigh);
  EXPECT_EQ(w(0x200A, 0, Bytes(10, 1)), SdoAbort::None);
  EXPECT_EQ(w(0x200A, 0, Bytes(11, 1)), SdoAbort::LengthTooHigh);
  EXPECT_EQ(od.value(0x200A, 0), Bytes(10, 1));
  // A longer default raises the maximum to it.
  EXPECT_EQ(od.var(0x2400, "long", DT::OctetString, AC::ReadWrite, Bytes(300, 0)).max_length, 300u);
}

TEST_F(DictionaryTest, TheDictionaryNeverAnswers06070010) {
  for (const auto& [index, obj] : od.objects())
    for (const auto& [sub, e] : obj.entries)
      for (size_t n : {size_t{0}, size_t{1}, size_t{3}, size_t{9}, size_t{300}})
        EXPECT_NE(od.write(index, sub, Bytes(n, 0)), SdoAbort::LengthMismatch);
}

// ---- value --------------------------------------------------------------------------

TEST_F(DictionaryTest, BooleanOtherThan0Or1Is06090030) {
  EXPECT_EQ(w(0x2004, 0, {1}), SdoAbort::None);
  EXPECT_EQ(w(0x2004, 0, {0}), SdoAbort::None);
  for (int v : {2, 0x80, 0xFF})
    EXPECT_EQ(w(0x2004, 0, {static_cast<uint8_t>(v)}), SdoAbort::InvalidValue);
  EXPECT_EQ(od.get<uint8_t>(0x2004, 0), 0);
  EXPECT_EQ(static_cast<uint32_t>(SdoAbort::InvalidValue), 0x06090030u);
}

TEST_F(DictionaryTest, LimitsAreInclusiveAndComparedInTheEntrysType) {
  // INTEGER32 -100..100
  EXPECT_EQ(w(0x2005, 0, encode<int32_t>(-100)), SdoAbort::None);
  EXPECT_EQ(w(0x2005, 0, encode<int32_t>(100)), SdoAbort::None);
  EXPECT_EQ(w(0x2005, 0, encode<int32_t>(101)), SdoAbort::ValueTooHigh);
  EXPECT_EQ(w(0x2005, 0, encode<int32_t>(-101)), SdoAbort::ValueTooLow);
  EXPECT_EQ(w(0x2005, 0, encode<int32_t>(INT32_MIN)), SdoAbort::ValueTooLow);
  EXPECT_EQ(od.get<int32_t>(0x2005, 0), 100);
  // UNSIGNED32 5..0x80000000: 0xFFFFFFFF is above, not a negative below.
  EXPECT_EQ(w(0x2006, 0, encode<uint32_t>(0x80000000)), SdoAbort::None);
  EXPECT_EQ(w(0x2006, 0, encode<uint32_t>(0x80000001)), SdoAbort::ValueTooHigh);
  EXPECT_EQ(w(0x2006, 0, encode<uint32_t>(0xFFFFFFFF)), SdoAbort::ValueTooHigh);
  EXPECT_EQ(w(0x2006, 0, encode<uint32_t>(4)), SdoAbort::ValueTooLow);
  // INTEGER16 -10..10: 0xFFF0 is -16, below (an unsigned view would call it above).
  EXPECT_EQ(w(0x2007, 0, Bytes{0xF0, 0xFF}), SdoAbort::ValueTooLow);
  EXPECT_EQ(w(0x2007, 0, Bytes{0xF6, 0xFF}), SdoAbort::None);  // -10
  EXPECT_EQ(w(0x2007, 0, Bytes{0x0B, 0x00}), SdoAbort::ValueTooHigh);
  // REAL32 -1.5..2.5
  EXPECT_EQ(w(0x2008, 0, encode<float>(2.5f)), SdoAbort::None);
  EXPECT_EQ(w(0x2008, 0, encode<float>(2.6f)), SdoAbort::ValueTooHigh);
  EXPECT_EQ(w(0x2008, 0, encode<float>(-1.6f)), SdoAbort::ValueTooLow);
  EXPECT_EQ(static_cast<uint32_t>(SdoAbort::ValueTooHigh), 0x06090031u);
  EXPECT_EQ(static_cast<uint32_t>(SdoAbort::ValueTooLow), 0x06090032u);
}

TEST_F(DictionaryTest, CheckValueAlone) {
  const Entry& e = od.at(0x2005, 0);
  EXPECT_EQ(check_value(e, encode<int32_t>(0)), SdoAbort::None);
  EXPECT_EQ(check_value(e, encode<int32_t>(1000)), SdoAbort::ValueTooHigh);
  EXPECT_EQ(check_value(e, encode<int16_t>(0)), SdoAbort::LengthTooLow);
  EXPECT_EQ(check_value(od.at(0x2001, 0), encode<uint32_t>(1)), SdoAbort::None);  // no access check
  EXPECT_EQ(check_value(od.at(0x200A, 0), Bytes(11, 0)), SdoAbort::LengthTooHigh);
}

// ---- validate and reactions --------------------------------------------------------------

TEST_F(DictionaryTest, OrderAccessLengthRangeThenValidateThenStoreThenOnWritten) {
  std::vector<std::string> calls;
  Entry& e = od.at(0x2005, 0);
  e.validate = [&](std::span<const uint8_t> d) {
    calls.push_back("validate " + std::to_string(decode<int32_t>(d)));
    return decode<int32_t>(d) == 13 ? SdoAbort::DeviceState : SdoAbort::None;
  };
  listen(e, [&] { calls.push_back("written " + std::to_string(od.get<int32_t>(0x2005, 0))); });
  EXPECT_EQ(w(0x2005, 0, Bytes{1}), SdoAbort::LengthTooLow);              // no hook
  EXPECT_EQ(w(0x2005, 0, encode<int32_t>(500)), SdoAbort::ValueTooHigh);  // no hook
  EXPECT_TRUE(calls.empty());
  EXPECT_EQ(w(0x2005, 0, encode<int32_t>(13)), SdoAbort::DeviceState);  // refused by the hook
  EXPECT_EQ(od.get<int32_t>(0x2005, 0), 0);                             // nothing stored
  EXPECT_EQ(w(0x2005, 0, encode<int32_t>(12)), SdoAbort::None);
  EXPECT_EQ(calls, (std::vector<std::string>{"validate 13", "validate 12", "written 12"}));
}

TEST_F(DictionaryTest, ReactionsRunInOrderAndARefusalRestoresThePreviousValue) {
  std::vector<std::string> calls;
  Entry& e = od.at(0x2005, 0);
  listen(e, [&] { calls.push_back("first sees " + std::to_string(od.get<int32_t>(0x2005, 0))); });
  // A command the device cannot carry out now: the abort is the answer.
  react(e, [&] {
    calls.push_back("command");
    return od.get<int32_t>(0x2005, 0) == 7 ? SdoAbort::DeviceState : SdoAbort::None;
  });
  listen(e, [&] { calls.push_back("third"); });
  ASSERT_EQ(w(0x2005, 0, encode<int32_t>(5)), SdoAbort::None);
  EXPECT_EQ(w(0x2005, 0, encode<int32_t>(7)), SdoAbort::DeviceState);
  EXPECT_EQ(od.get<int32_t>(0x2005, 0), 5);  // the value before the refused write
  EXPECT_EQ(calls, (std::vector<std::string>{"first sees 5", "command", "third", "first sees 7",
                                             "command"}));
}

TEST_F(DictionaryTest, PdoWritesObeyTheSameRules) {
  EXPECT_EQ(od.write(0x2005, 0, encode<int32_t>(101), WriteOrigin::Pdo), SdoAbort::ValueTooHigh);
  EXPECT_EQ(od.write(0x2001, 0, encode<uint32_t>(1), WriteOrigin::Pdo), SdoAbort::ReadOnly);
  EXPECT_EQ(od.write(0x2004, 0, Bytes{3}, WriteOrigin::Pdo), SdoAbort::InvalidValue);
  EXPECT_EQ(od.write(0x2000, 0, encode<uint16_t>(3), WriteOrigin::Pdo), SdoAbort::None);
  EXPECT_EQ(od.get<uint16_t>(0x2000, 0), 3);
}

}  // namespace
}  // namespace stepnode::od
