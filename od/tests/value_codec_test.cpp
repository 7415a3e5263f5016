// CiA 301 data types (7.1), their little-endian encoding (7.1.3: "the least significant
// byte first"), the typed views used for limits, and value text (parse_value/format_value).
// Also the abort code texts of CiA 301 7.2.4.3.17 (table 22).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "od/data_type.hpp"
#include "od/sdo_abort.hpp"
#include "od/value_codec.hpp"

namespace stepnode::od {
namespace {

using DT = DataType;

// ---- data types ---------------------------------------------------------------------

TEST(DataTypes, IndicesAreTheCiA301DataTypeIndices) {
  EXPECT_EQ(static_cast<uint16_t>(DT::Boolean), 0x0001);
  EXPECT_EQ(static_cast<uint16_t>(DT::Integer8), 0x0002);
  EXPECT_EQ(static_cast<uint16_t>(DT::Integer16), 0x0003);
  EXPECT_EQ(static_cast<uint16_t>(DT::Integer32), 0x0004);
  EXPECT_EQ(static_cast<uint16_t>(DT::Unsigned8), 0x0005);
  EXPECT_EQ(static_cast<uint16_t>(DT::Unsigned16), 0x0006);
  EXPECT_EQ(static_cast<uint16_t>(DT::Unsigned32), 0x0007);
  EXPECT_EQ(static_cast<uint16_t>(DT::Real32), 0x0008);
  EXPECT_EQ(static_cast<uint16_t>(DT::VisibleString), 0x0009);
  EXPECT_EQ(static_cast<uint16_t>(DT::OctetString), 0x000A);
  EXPECT_EQ(static_cast<uint16_t>(DT::Domain), 0x000F);
  EXPECT_EQ(static_cast<uint16_t>(DT::Real64), 0x0011);
  EXPECT_EQ(static_cast<uint16_t>(DT::Integer64), 0x0015);
  EXPECT_EQ(static_cast<uint16_t>(DT::Unsigned64), 0x001B);
}

struct TypeRow {
  DT type;
  const char* name;
  size_t size;
  bool is_signed, is_unsigned, is_real;
};

constexpr TypeRow kTypes[] = {
    {DT::Boolean, "BOOLEAN", 1, false, true, false},
    {DT::Integer8, "INTEGER8", 1, true, false, false},
    {DT::Integer16, "INTEGER16", 2, true, false, false},
    {DT::Integer32, "INTEGER32", 4, true, false, false},
    {DT::Integer64, "INTEGER64", 8, true, false, false},
    {DT::Unsigned8, "UNSIGNED8", 1, false, true, false},
    {DT::Unsigned16, "UNSIGNED16", 2, false, true, false},
    {DT::Unsigned32, "UNSIGNED32", 4, false, true, false},
    {DT::Unsigned64, "UNSIGNED64", 8, false, true, false},
    {DT::Real32, "REAL32", 4, false, false, true},
    {DT::Real64, "REAL64", 8, false, false, true},
    {DT::VisibleString, "VISIBLE_STRING", 0, false, false, false},
    {DT::OctetString, "OCTET_STRING", 0, false, false, false},
    {DT::Domain, "DOMAIN", 0, false, false, false},
};

TEST(DataTypes, SizesClassesAndNames) {
  for (const auto& t : kTypes) {
    SCOPED_TRACE(t.name);
    EXPECT_EQ(fixed_size(t.type), t.size);
    EXPECT_EQ(is_variable_length(t.type), t.size == 0);
    EXPECT_EQ(is_signed_integer(t.type), t.is_signed);
    EXPECT_EQ(is_unsigned_integer(t.type), t.is_unsigned);
    EXPECT_EQ(is_real(t.type), t.is_real);
    EXPECT_EQ(type_name(t.type), t.name);
    ASSERT_TRUE(type_from_name(t.name).has_value());
    EXPECT_EQ(*type_from_name(t.name), t.type);
  }
  EXPECT_EQ(type_name(static_cast<DT>(0x0010)), "UNKNOWN");  // INTEGER24: not supported
  EXPECT_EQ(fixed_size(static_cast<DT>(0x0010)), 0u);
  EXPECT_FALSE(type_from_name("unsigned8").has_value());  // names are the CiA spelling
  EXPECT_FALSE(type_from_name("").has_value());
}

TEST(DataTypes, AccessRights) {
  EXPECT_EQ(access_eds_name(Access::ReadOnly), "ro");
  EXPECT_EQ(access_eds_name(Access::WriteOnly), "wo");
  EXPECT_EQ(access_eds_name(Access::ReadWrite), "rw");
  EXPECT_EQ(access_eds_name(Access::Const), "const");
  EXPECT_TRUE(readable(Access::ReadOnly));
  EXPECT_FALSE(readable(Access::WriteOnly));
  EXPECT_TRUE(readable(Access::ReadWrite));
  EXPECT_TRUE(readable(Access::Const));
  EXPECT_FALSE(writable(Access::ReadOnly));
  EXPECT_TRUE(writable(Access::WriteOnly));
  EXPECT_TRUE(writable(Access::ReadWrite));
  EXPECT_FALSE(writable(Access::Const));
}

// ---- abort codes ----------------------------------------------------------------------

TEST(SdoAbortCodes, ValuesAndTextsOfCiA301Table22) {
  struct Row {
    SdoAbort code;
    uint32_t value;
    const char* text;
  };
  const Row rows[] = {
      {SdoAbort::ToggleBit, 0x05030000, "Toggle bit not alternated"},
      {SdoAbort::Timeout, 0x05040000, "SDO protocol timed out"},
      {SdoAbort::BadCommand, 0x05040001, "Client/server command specifier not valid or unknown"},
      {SdoAbort::InvalidBlockSize, 0x05040002, "Invalid block size"},
      {SdoAbort::InvalidSequence, 0x05040003, "Invalid sequence number"},
      {SdoAbort::CrcError, 0x05040004, "CRC error"},
      {SdoAbort::OutOfMemory, 0x05040005, "Out of memory"},
      {SdoAbort::UnsupportedAccess, 0x06010000, "Unsupported access to an object"},
      {SdoAbort::WriteOnly, 0x06010001, "Attempt to read a write only object"},
      {SdoAbort::ReadOnly, 0x06010002, "Attempt to write a read only object"},
      {SdoAbort::NoObject, 0x06020000, "Object does not exist in the object dictionary"},
      {SdoAbort::NotMappable, 0x06040041, "Object cannot be mapped to the PDO"},
      {SdoAbort::PdoTooLong, 0x06040042,
       "The number and length of the objects to be mapped would exceed PDO length"},
      {SdoAbort::ParameterIncompatible, 0x06040043, "General parameter incompatibility reason"},
      {SdoAbort::DeviceIncompatible, 0x06040047, "General internal incompatibility in the device"},
      {SdoAbort::Hardware, 0x06060000, "Access failed due to a hardware error"},
      {SdoAbort::LengthMismatch, 0x06070010,
       "Data type does not match, length of service parameter does not match"},
      {SdoAbort::LengthTooHigh, 0x06070012,
       "Data type does not match, length of service parameter too high"},
      {SdoAbort::LengthTooLow, 0x06070013,
       "Data type does not match, length of service parameter too low"},
      {SdoAbort::NoSubindex, 0x06090011, "Sub-index does not exist"},
      {SdoAbort::InvalidValue, 0x06090030, "Invalid value for parameter"},
      {SdoAbort::ValueTooHigh, 0x06090031, "Value of parameter written too high"},
      {SdoAbort::ValueTooLow, 0x06090032, "Value of parameter written too low"},
      {SdoAbort::MaxBelowMin, 0x06090036, "Maximum value is less than minimum value"},
      {SdoAbort::General, 0x08000000, "General error"},
      {SdoAbort::DataTransfer, 0x08000020,
       "Data cannot be transferred or stored to the application"},
      {SdoAbort::LocalControl, 0x08000021,
       "Data cannot be transferred or stored to the application because of local control"},
      {SdoAbort::DeviceState, 0x08000022,
       "Data cannot be transferred or stored to the application because of the present device "
       "state"},
      {SdoAbort::NoDictionary, 0x08000023,
       "Object dictionary dynamic generation fails or no object dictionary is present"},
      {SdoAbort::NoData, 0x08000024, "No data available"},
  };
  for (const auto& r : rows) {
    EXPECT_EQ(static_cast<uint32_t>(r.code), r.value);
    EXPECT_EQ(abort_text(r.code), r.text);
    EXPECT_EQ(abort_text(r.value), r.text);
  }
  EXPECT_EQ(static_cast<uint32_t>(SdoAbort::None), 0u);
  EXPECT_EQ(abort_text(0x060A0023), "Resource not available: SDO connection");
  EXPECT_EQ(abort_text(0x12345678), "unknown abort code");
}

// ---- encode / decode ------------------------------------------------------------------

TEST(Encode, LittleEndianLeastSignificantByteFirst) {
  EXPECT_EQ(encode<uint8_t>(0xAB), (Bytes{0xAB}));
  EXPECT_EQ(encode<uint16_t>(0x1234), (Bytes{0x34, 0x12}));
  EXPECT_EQ(encode<uint32_t>(0x11223344), (Bytes{0x44, 0x33, 0x22, 0x11}));
  EXPECT_EQ(encode<uint64_t>(0x0102030405060708), (Bytes{8, 7, 6, 5, 4, 3, 2, 1}));
  EXPECT_EQ(encode<int8_t>(-1), (Bytes{0xFF}));
  EXPECT_EQ(encode<int16_t>(-2), (Bytes{0xFE, 0xFF}));
  EXPECT_EQ(encode<int32_t>(-8'388'608), (Bytes{0x00, 0x00, 0x80, 0xFF}));
  EXPECT_EQ(encode<int64_t>(std::numeric_limits<int64_t>::min()),
            (Bytes{0, 0, 0, 0, 0, 0, 0, 0x80}));
  // IEEE 754 (CiA 301 7.1.4.4 / 7.1.4.5).
  EXPECT_EQ(encode<float>(1.0f), (Bytes{0x00, 0x00, 0x80, 0x3F}));
  EXPECT_EQ(encode<float>(-2.5f), (Bytes{0x00, 0x00, 0x20, 0xC0}));
  EXPECT_EQ(encode<double>(1.0), (Bytes{0, 0, 0, 0, 0, 0, 0xF0, 0x3F}));
  EXPECT_EQ(encode_string("ab"), (Bytes{'a', 'b'}));
  EXPECT_TRUE(encode_string("").empty());
}

TEST(Decode, ReadsLittleEndianAndToleratesShortOrLongInput) {
  EXPECT_EQ(decode<uint32_t>(Bytes{0x44, 0x33, 0x22, 0x11}), 0x11223344u);
  EXPECT_EQ(decode<int16_t>(Bytes{0xFE, 0xFF}), -2);
  EXPECT_EQ(decode<int64_t>(encode<int64_t>(-1234567890123)), -1234567890123);
  EXPECT_EQ(decode<float>(Bytes{0x00, 0x00, 0x80, 0x3F}), 1.0f);
  EXPECT_EQ(decode<double>(encode<double>(-0.125)), -0.125);
  // Missing bytes read as zero, and the sign is not extended.
  EXPECT_EQ(decode<uint32_t>(Bytes{0x01, 0x02}), 0x0201u);
  EXPECT_EQ(decode<int32_t>(Bytes{0xFF, 0xFF}), 0xFFFF);
  EXPECT_EQ(decode<uint16_t>(Bytes{}), 0u);
  // Extra bytes are not read.
  EXPECT_EQ(decode<uint8_t>(Bytes{0x12, 0x34}), 0x12);
  EXPECT_EQ(decode<uint16_t>(Bytes{0x12, 0x34, 0x56}), 0x3412);
}

TEST(TypedViews, SignExtensionZeroExtensionAndReal) {
  EXPECT_EQ(as_signed(DT::Integer8, Bytes{0x80}), -128);
  EXPECT_EQ(as_signed(DT::Integer16, Bytes{0x00, 0x80}), -32768);
  EXPECT_EQ(as_signed(DT::Integer32, Bytes{0xFF, 0xFF, 0xFF, 0xFF}), -1);
  EXPECT_EQ(as_signed(DT::Integer64, encode<int64_t>(INT64_MIN)), INT64_MIN);
  EXPECT_EQ(as_signed(DT::Unsigned8, Bytes{0x80}), 128);  // unsigned types are not extended
  EXPECT_EQ(as_signed(DT::Unsigned32, Bytes{0xFF, 0xFF, 0xFF, 0xFF}), 0xFFFFFFFF);
  EXPECT_EQ(as_unsigned(DT::Unsigned16, Bytes{0x34, 0x12}), 0x1234u);
  EXPECT_EQ(as_unsigned(DT::Integer16, Bytes{0xFE, 0xFF}), 0xFFFEu);
  EXPECT_EQ(as_unsigned(DT::Unsigned8, Bytes{0x12, 0x34}), 0x12u);       // only the type's size
  EXPECT_EQ(as_unsigned(DT::Unsigned32, Bytes{0x12}), 0x12u);            // short: what is there
  EXPECT_EQ(as_unsigned(DT::Domain, Bytes{1, 2, 3}), 0x030201u);         // variable: up to 8 bytes
  EXPECT_EQ(as_unsigned(DT::Real32, encode<float>(1.0f)), 0x3F800000u);  // raw bit pattern
  EXPECT_EQ(as_real(DT::Real32, encode<float>(-2.5f)), -2.5);
  EXPECT_EQ(as_real(DT::Real64, encode<double>(1e300)), 1e300);
  EXPECT_EQ(as_real(DT::Integer16, encode<int16_t>(-7)), -7.0);
  EXPECT_EQ(as_real(DT::Unsigned32, encode<uint32_t>(0xFFFFFFFF)), 4294967295.0);
}

TEST(TypedViews, CompareByTheNumericMeaningOfTheType) {
  Bytes ff{0xFF}, one{0x01};
  EXPECT_LT(compare_values(DT::Integer8, ff, one), 0);   // -1 < 1
  EXPECT_GT(compare_values(DT::Unsigned8, ff, one), 0);  // 255 > 1
  EXPECT_EQ(compare_values(DT::Unsigned8, one, one), 0);
  EXPECT_LT(compare_values(DT::Integer32, encode<int32_t>(INT32_MIN), encode<int32_t>(INT32_MAX)),
            0);
  EXPECT_GT(compare_values(DT::Unsigned32, encode<uint32_t>(0x80000000), encode<uint32_t>(1)), 0);
  EXPECT_LT(compare_values(DT::Integer64, encode<int64_t>(-1), encode<int64_t>(0)), 0);
  EXPECT_GT(compare_values(DT::Unsigned64, encode<uint64_t>(UINT64_MAX), encode<uint64_t>(0)), 0);
  EXPECT_LT(compare_values(DT::Real32, encode<float>(-1.5f), encode<float>(0.25f)), 0);
  EXPECT_GT(compare_values(DT::Real64, encode<double>(2.0), encode<double>(-3.0)), 0);
  EXPECT_EQ(compare_values(DT::Real32, encode<float>(0.0f), encode<float>(-0.0f)), 0);
}

// ---- format_value ---------------------------------------------------------------------

TEST(FormatValue, DecimalHexStringsAndReals) {
  EXPECT_EQ(format_value(DT::Unsigned16, encode<uint16_t>(1000)), "1000");
  EXPECT_EQ(format_value(DT::Integer8, Bytes{0xFB}), "-5");
  EXPECT_EQ(format_value(DT::Integer32, encode<int32_t>(INT32_MIN)), "-2147483648");
  EXPECT_EQ(format_value(DT::Unsigned32, encode<uint32_t>(0xFFFFFFFF)), "4294967295");
  EXPECT_EQ(format_value(DT::Unsigned64, encode<uint64_t>(UINT64_MAX)), "18446744073709551615");
  EXPECT_EQ(format_value(DT::Integer64, encode<int64_t>(INT64_MIN)), "-9223372036854775808");
  EXPECT_EQ(format_value(DT::Boolean, Bytes{1}), "1");
  // Hex: zero-padded to the type's width; signed types show their bit pattern.
  EXPECT_EQ(format_value(DT::Unsigned32, encode<uint32_t>(0x191), true), "0x00000191");
  EXPECT_EQ(format_value(DT::Unsigned16, encode<uint16_t>(0x80), true), "0x0080");
  EXPECT_EQ(format_value(DT::Unsigned8, Bytes{0x0A}, true), "0x0a");
  EXPECT_EQ(format_value(DT::Integer16, encode<int16_t>(-2), true), "0xfffe");
  EXPECT_EQ(format_value(DT::Unsigned64, encode<uint64_t>(1), true), "0x0000000000000001");
  // Strings and domains.
  EXPECT_EQ(format_value(DT::VisibleString, encode_string("stepnode")), "\"stepnode\"");
  EXPECT_EQ(format_value(DT::VisibleString, Bytes{}), "\"\"");
  EXPECT_EQ(format_value(DT::OctetString, Bytes{0x01, 0xAB, 0xFF}), "3 bytes: 01 ab ff");
  EXPECT_EQ(format_value(DT::Domain, Bytes{}), "0 bytes");
  Bytes big(20, 0x11);
  EXPECT_EQ(format_value(DT::Domain, big),
            "20 bytes: 11 11 11 11 11 11 11 11 11 11 11 11 11 11 11 11 ...");
  // Reals: the shortest text that reads back to the same value of the type.
  EXPECT_EQ(format_value(DT::Real32, encode<float>(0.1f)), "0.1");
  EXPECT_EQ(format_value(DT::Real32, encode<float>(-2.5f)), "-2.5");
  EXPECT_EQ(format_value(DT::Real64, encode<double>(0.1)), "0.1");
  EXPECT_EQ(format_value(DT::Real64, encode<double>(1e300)), "1e+300");
  EXPECT_EQ(format_value(DT::Real32, encode<float>(1.0f), true), "1");  // hex ignored for reals
}

// ---- parse_value ----------------------------------------------------------------------

TEST(ParseValue, IntegersDecimalAndHexIntoTheTypeSize) {
  EXPECT_EQ(parse_value(DT::Unsigned8, "255"), (Bytes{0xFF}));
  EXPECT_EQ(parse_value(DT::Unsigned16, "0x1234"), (Bytes{0x34, 0x12}));
  EXPECT_EQ(parse_value(DT::Unsigned16, "0X00ff"), (Bytes{0xFF, 0x00}));
  EXPECT_EQ(parse_value(DT::Unsigned32, "0x40000185"), encode<uint32_t>(0x40000185));
  EXPECT_EQ(parse_value(DT::Unsigned32, "+7"), encode<uint32_t>(7));
  EXPECT_EQ(parse_value(DT::Unsigned32, "-0"), encode<uint32_t>(0));
  EXPECT_EQ(parse_value(DT::Integer8, "-128"), (Bytes{0x80}));
  EXPECT_EQ(parse_value(DT::Integer16, "-2"), (Bytes{0xFE, 0xFF}));
  EXPECT_EQ(parse_value(DT::Integer16, "-0x10"), encode<int16_t>(-16));
  EXPECT_EQ(parse_value(DT::Integer32, "-8388608"), encode<int32_t>(-8'388'608));
  EXPECT_EQ(parse_value(DT::Boolean, "0"), (Bytes{0}));
  EXPECT_EQ(parse_value(DT::Boolean, "1"), (Bytes{1}));
}

TEST(ParseValue, EveryIntegerTypeAcceptsItsRangeAndRefusesOneBeyond) {
  struct Range {
    DT type;
    const char *min, *max, *below, *above;
  };
  const Range ranges[] = {
      {DT::Integer8, "-128", "127", "-129", "128"},
      {DT::Integer16, "-32768", "32767", "-32769", "32768"},
      {DT::Integer32, "-2147483648", "2147483647", "-2147483649", "2147483648"},
      {DT::Integer64, "-9223372036854775808", "9223372036854775807", "-9223372036854775809",
       "9223372036854775808"},
      {DT::Unsigned8, "0", "255", "-1", "256"},
      {DT::Unsigned16, "0", "0xFFFF", "-1", "0x10000"},
      {DT::Unsigned32, "0", "4294967295", "-1", "4294967296"},
      {DT::Unsigned64, "0", "18446744073709551615", "-1", "18446744073709551616"},
      {DT::Boolean, "0", "1", "-1", "2"},
  };
  for (const auto& r : ranges) {
    SCOPED_TRACE(type_name(r.type));
    Bytes lo = parse_value(r.type, r.min), hi = parse_value(r.type, r.max);
    EXPECT_EQ(lo.size(), fixed_size(r.type));
    EXPECT_EQ(hi.size(), fixed_size(r.type));
    EXPECT_EQ(format_value(r.type, lo), r.min);
    EXPECT_LT(compare_values(r.type, lo, hi), 0);
    EXPECT_THROW(parse_value(r.type, r.below), std::invalid_argument);
    EXPECT_THROW(parse_value(r.type, r.above), std::invalid_argument);
  }
  EXPECT_EQ(parse_value(DT::Integer64, "-9223372036854775808"), encode<int64_t>(INT64_MIN));
  EXPECT_EQ(parse_value(DT::Unsigned64, "0xFFFFFFFFFFFFFFFF"), encode<uint64_t>(UINT64_MAX));
}

TEST(ParseValue, SignedHexIsTheTwosComplementPatternOfTheTypeWidth) {
  EXPECT_EQ(parse_value(DT::Integer16, "0xFFFE"), encode<int16_t>(-2));
  EXPECT_EQ(parse_value(DT::Integer8, "0x80"), encode<int8_t>(-128));
  EXPECT_EQ(parse_value(DT::Integer32, "0x80000000"), encode<int32_t>(INT32_MIN));
  EXPECT_EQ(parse_value(DT::Integer32, "0x7FFFFFFF"), encode<int32_t>(INT32_MAX));
  EXPECT_EQ(parse_value(DT::Integer64, "0xFFFFFFFFFFFFFFFF"), encode<int64_t>(-1));
  EXPECT_THROW(parse_value(DT::Integer16, "0x10000"), std::invalid_argument);  // wider
  EXPECT_THROW(parse_value(DT::Integer8, "-0x81"), std::invalid_argument);     // signed: range
  EXPECT_THROW(parse_value(DT::Integer8, "128"), std::invalid_argument);       // decimal: range
}

TEST(ParseValue, MalformedTextIsRefusedWithAMessageNamingTextAndType) {
  for (const char* text : {"", "abc", "0x", "0xg1", "1.5", " 5", "5 ", "--5", "+-5", "-+5", "+",
                           "-", "5k", "1e3", "0b101"}) {
    SCOPED_TRACE(text);
    EXPECT_THROW(parse_value(DT::Unsigned32, text), std::invalid_argument);
    EXPECT_THROW(parse_value(DT::Integer32, text), std::invalid_argument);
  }
  try {
    parse_value(DT::Unsigned8, "300");
    FAIL() << "300 fits no UNSIGNED8";
  } catch (const std::invalid_argument& e) {
    std::string what = e.what();
    EXPECT_NE(what.find("'300'"), std::string::npos) << what;
    EXPECT_NE(what.find("UNSIGNED8"), std::string::npos) << what;
    EXPECT_NE(what.find("out of range"), std::string::npos) << what;
  }
  try {
    parse_value(DT::Unsigned16, "-3");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("negative"), std::string::npos) << e.what();
  }
}

TEST(ParseValue, Reals) {
  EXPECT_EQ(parse_value(DT::Real32, "1"), encode<float>(1.0f));
  EXPECT_EQ(parse_value(DT::Real32, "-2.5"), encode<float>(-2.5f));
  EXPECT_EQ(parse_value(DT::Real32, "0.1"), encode<float>(0.1f));
  EXPECT_EQ(parse_value(DT::Real64, "0.1"), encode<double>(0.1));
  EXPECT_EQ(parse_value(DT::Real64, "1e300"), encode<double>(1e300));
  EXPECT_EQ(parse_value(DT::Real32, "3.4028234e38"),
            encode<float>(std::numeric_limits<float>::max()));
  EXPECT_TRUE(std::isinf(decode<float>(parse_value(DT::Real32, "-inf"))));
  // A finite number beyond REAL32 has no REAL32 value.
  EXPECT_THROW(parse_value(DT::Real32, "1e39"), std::invalid_argument);
  EXPECT_THROW(parse_value(DT::Real32, "-1e39"), std::invalid_argument);
  EXPECT_THROW(parse_value(DT::Real64, "1e999"), std::invalid_argument);  // ERANGE
  for (const char* text : {"", "x", "1.5.5", "1,5", " 1.5", "1.5 "}) {
    SCOPED_TRACE(text);
    EXPECT_THROW(parse_value(DT::Real32, text), std::invalid_argument);
    EXPECT_THROW(parse_value(DT::Real64, text), std::invalid_argument);
  }
}

TEST(ParseValue, StringsAndDomainsAreTakenAsTheyAre) {
  EXPECT_EQ(parse_value(DT::VisibleString, "step node"), encode_string("step node"));
  EXPECT_EQ(parse_value(DT::VisibleString, ""), Bytes{});
  EXPECT_EQ(parse_value(DT::OctetString, "0x12"), encode_string("0x12"));
  EXPECT_EQ(parse_value(DT::Domain, "abc"), encode_string("abc"));
}

TEST(ParseValue, FormatThenParseGivesTheSameBytes) {
  const std::pair<DT, Bytes> values[] = {
      {DT::Boolean, {1}},
      {DT::Integer8, {0x80}},
      {DT::Integer16, encode<int16_t>(-12345)},
      {DT::Integer32, encode<int32_t>(INT32_MIN)},
      {DT::Integer64, encode<int64_t>(INT64_MAX)},
      {DT::Unsigned8, {0xFF}},
      {DT::Unsigned16, encode<uint16_t>(0xBEEF)},
      {DT::Unsigned32, encode<uint32_t>(0xC0000000)},
      {DT::Unsigned64, encode<uint64_t>(0x8000000000000001)},
      {DT::Real32, encode<float>(0.1f)},
      {DT::Real32, encode<float>(-1.17549435e-38f)},
      {DT::Real64, encode<double>(3.141592653589793)},
      {DT::VisibleString, encode_string("stepnode 0.1.0")},
  };
  for (const auto& [type, bytes] : values) {
    SCOPED_TRACE(type_name(type));
    std::string text = format_value(type, bytes);
    if (type == DT::VisibleString) text = text.substr(1, text.size() - 2);  // the quotes
    EXPECT_EQ(parse_value(type, text), bytes) << text;
    if (!is_real(type) && !is_variable_length(type)) {
      EXPECT_EQ(parse_value(type, format_value(type, bytes, true)), bytes);
    }
  }
}

}  // namespace
}  // namespace stepnode::od
