// PDO mapping (CiA 301 7.4.7, 7.5.2.36 / 7.5.2.38): one mapping word is index<<16 | sub<<8 |
// length in bits; the mapped values are laid out one after another, each least significant
// bit first, so a PDO is the little-endian concatenation of its entries. RPDOs may map
// dummy entries (a data type index 0x0002..0x0007) to skip bits.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "od/pdo_mapping.hpp"

namespace stepnode::od {
namespace {

using DT = DataType;
using AC = Access;
using Frame = std::vector<uint8_t>;

void fill(Dictionary& od) {
  od.var(0x2000, "u8", DT::Unsigned8, AC::ReadWrite, {0xAB}, true);
  od.var(0x2001, "i16", DT::Integer16, AC::ReadWrite, encode<int16_t>(-2), true);
  od.var(0x2002, "u32", DT::Unsigned32, AC::ReadWrite, encode<uint32_t>(0x11223344), true);
  od.var(0x2003, "i32 ro", DT::Integer32, AC::ReadOnly, encode<int32_t>(-8'388'608), true);
  od.var(0x2004, "u16 wo", DT::Unsigned16, AC::WriteOnly, encode<uint16_t>(0), true);
  od.var(0x2005, "not mappable", DT::Unsigned8, AC::ReadWrite, {0}, false);
  od.var(0x2006, "string", DT::VisibleString, AC::ReadWrite, encode_string("x"), true);
  od.var(0x2007, "bool", DT::Boolean, AC::ReadWrite, {1}, true);
  od.var(0x2008, "u64", DT::Unsigned64, AC::ReadWrite, encode<uint64_t>(0x0102030405060708), true);
  od.var(0x2009, "real", DT::Real32, AC::ReadWrite, encode<float>(1.0f), true);
  od.var(0x200A, "const", DT::Unsigned8, AC::Const, {0x5A}, true);
  Entry& lim = od.var(0x200B, "limited", DT::Unsigned8, AC::ReadWrite, {10}, true);
  lim.high = Bytes{100};
  Object& rec = od.record(0x2100, "record");
  rec.add(1, "a", DT::Unsigned8, AC::ReadWrite, {0x01}, true);
  rec.add(2, "b", DT::Integer8, AC::ReadWrite, {0x80}, true);
}

class PdoMappingTest : public ::testing::Test {
 protected:
  void SetUp() override { fill(od); }
  SdoAbort tx(uint32_t word) { return check_mapping_entry(od, word, PdoDirection::Transmit); }
  SdoAbort rx(uint32_t word) { return check_mapping_entry(od, word, PdoDirection::Receive); }
  Dictionary od;
};

// ---- mapping words ----------------------------------------------------------------------

TEST(MappedEntryTest, FromWordAndDummies) {
  MappedEntry m = MappedEntry::from_word(0x60410210);
  EXPECT_EQ(m.index, 0x6041);
  EXPECT_EQ(m.sub, 0x02);
  EXPECT_EQ(m.bits, 0x10);
  EXPECT_FALSE(m.dummy());
  for (uint16_t i = 1; i <= 7; ++i) EXPECT_TRUE((MappedEntry{i, 0, 8}.dummy())) << i;
  EXPECT_FALSE((MappedEntry{0, 0, 8}.dummy()));
  EXPECT_FALSE((MappedEntry{8, 0, 32}.dummy()));  // REAL32 is not a dummy here
  EXPECT_EQ(kMaxPdoBits, 64u);
  EXPECT_EQ(kMaxMappedEntries, 8u);
}

TEST(MappedEntryTest, BitsAndBytes) {
  EXPECT_EQ(mapping_bits({}), 0u);
  EXPECT_EQ(mapping_bytes({}), 0u);
  EXPECT_EQ(mapping_bits({{0x2000, 0, 8}, {0x2001, 0, 16}, {0x2002, 0, 32}}), 56u);
  EXPECT_EQ(mapping_bytes({{0x2000, 0, 8}, {0x2001, 0, 16}, {0x2002, 0, 32}}), 7u);
  EXPECT_EQ(mapping_bytes({{0x2000, 0, 7}}), 1u);
  EXPECT_EQ(mapping_bytes({{0x2000, 0, 9}}), 2u);
  EXPECT_EQ(mapping_bytes({{0x2000, 0, 64}}), 8u);
}

TEST_F(PdoMappingTest, EntryChecksAndTheirAbortCodes) {
  EXPECT_EQ(tx(0x20000008), SdoAbort::None);
  EXPECT_EQ(rx(0x20000008), SdoAbort::None);
  EXPECT_EQ(tx(0x20030020), SdoAbort::None);  // read-only: transmit only
  EXPECT_EQ(rx(0x20030020), SdoAbort::NotMappable);
  EXPECT_EQ(rx(0x20040010), SdoAbort::None);  // write-only: receive only
  EXPECT_EQ(tx(0x20040010), SdoAbort::NotMappable);
  EXPECT_EQ(tx(0x200A0008), SdoAbort::None);  // const: transmit only
  EXPECT_EQ(rx(0x200A0008), SdoAbort::NotMappable);
  // 0x06040041: not mappable at all, or of variable length.
  EXPECT_EQ(tx(0x20050008), SdoAbort::NotMappable);
  EXPECT_EQ(rx(0x20050008), SdoAbort::NotMappable);
  EXPECT_EQ(tx(0x20060008), SdoAbort::NotMappable);
  EXPECT_EQ(static_cast<uint32_t>(SdoAbort::NotMappable), 0x06040041u);
  // 0x06020000 / 0x06090011: no such object / sub-index.
  EXPECT_EQ(tx(0x30000008), SdoAbort::NoObject);
  EXPECT_EQ(tx(0x00000000), SdoAbort::NoObject);
  EXPECT_EQ(tx(0x21000308), SdoAbort::NoSubindex);
  EXPECT_EQ(rx(0x20000108), SdoAbort::NoSubindex);
  // 0x06040043: the length in the word is not the entry's.
  EXPECT_EQ(tx(0x20000010), SdoAbort::ParameterIncompatible);
  EXPECT_EQ(tx(0x20020010), SdoAbort::ParameterIncompatible);
  EXPECT_EQ(tx(0x20020000), SdoAbort::ParameterIncompatible);
  EXPECT_EQ(rx(0x20070001), SdoAbort::ParameterIncompatible);  // BOOLEAN maps as 8 bits
  EXPECT_EQ(rx(0x20070008), SdoAbort::None);
  EXPECT_EQ(tx(0x20080040), SdoAbort::None);
  EXPECT_EQ(tx(0x20090020), SdoAbort::None);
  EXPECT_EQ(tx(0x21000208), SdoAbort::None);
  EXPECT_EQ(static_cast<uint32_t>(SdoAbort::ParameterIncompatible), 0x06040043u);
}

TEST_F(PdoMappingTest, DummyEntriesOnlyInReceivePdos) {
  // INTEGER8..UNSIGNED32 (0x0002..0x0007) as dummies of their own length.
  EXPECT_EQ(rx(0x00020008), SdoAbort::None);
  EXPECT_EQ(rx(0x00030010), SdoAbort::None);
  EXPECT_EQ(rx(0x00040020), SdoAbort::None);
  EXPECT_EQ(rx(0x00050008), SdoAbort::None);
  EXPECT_EQ(rx(0x00060010), SdoAbort::None);
  EXPECT_EQ(rx(0x00070020), SdoAbort::None);
  EXPECT_EQ(rx(0x00070010), SdoAbort::ParameterIncompatible);  // wrong length
  EXPECT_EQ(rx(0x00050108), SdoAbort::NotMappable);            // a dummy has sub 0
  EXPECT_EQ(rx(0x00010001), SdoAbort::NotMappable);            // BOOLEAN: DummyUsage 0
  EXPECT_EQ(rx(0x00010008), SdoAbort::NotMappable);
  for (uint32_t word : {0x00020008u, 0x00050008u, 0x00070020u})
    EXPECT_EQ(tx(word), SdoAbort::NotMappable) << std::hex << word;
}

TEST_F(PdoMappingTest, WholeMappingAtMost64Bits) {
  std::vector<uint32_t> words{0x20020020, 0x20030020};
  EXPECT_EQ(check_mapping(od, words, PdoDirection::Transmit), SdoAbort::None);  // 64 bits
  words.push_back(0x20000008);
  EXPECT_EQ(check_mapping(od, words, PdoDirection::Transmit), SdoAbort::PdoTooLong);  // 72
  EXPECT_EQ(static_cast<uint32_t>(SdoAbort::PdoTooLong), 0x06040042u);
  std::vector<uint32_t> eight(8, 0x20000008);  // 8 x UNSIGNED8 = 64 bits
  EXPECT_EQ(check_mapping(od, eight, PdoDirection::Receive), SdoAbort::None);
  eight.push_back(0x20000008);
  EXPECT_EQ(check_mapping(od, eight, PdoDirection::Receive), SdoAbort::PdoTooLong);
  EXPECT_EQ(check_mapping(od, std::vector<uint32_t>{0x20080040, 0x00050008}, PdoDirection::Receive),
            SdoAbort::PdoTooLong);  // dummies count
  EXPECT_EQ(check_mapping(od, std::vector<uint32_t>{}, PdoDirection::Transmit), SdoAbort::None);
  // An entry error comes first, even past 64 bits.
  EXPECT_EQ(
      check_mapping(od, std::vector<uint32_t>{0x20080040, 0x20050008}, PdoDirection::Transmit),
      SdoAbort::NotMappable);
}

// ---- bits ---------------------------------------------------------------------------------

TEST(PdoBits, LeastSignificantBitFirstAcrossByteBoundaries) {
  Frame f(3, 0);
  write_bits(f, 4, 0xABC, 12);  // starts in the high nibble of byte 0
  EXPECT_EQ(f, (Frame{0xC0, 0xAB, 0x00}));
  EXPECT_EQ(read_bits(f, 4, 12), 0xABCu);
  EXPECT_EQ(read_bits(f, 0, 4), 0u);
  write_bits(f, 0, 0xF, 4);
  write_bits(f, 16, 0x1, 1);
  write_bits(f, 23, 0x1, 1);
  EXPECT_EQ(f, (Frame{0xCF, 0xAB, 0x81}));
  write_bits(f, 4, 0, 12);  // clears only its own bits
  EXPECT_EQ(f, (Frame{0x0F, 0x00, 0x81}));
  Frame g(8, 0);
  write_bits(g, 0, 0x0102030405060708, 64);
  EXPECT_EQ(g, (Frame{8, 7, 6, 5, 4, 3, 2, 1}));
  EXPECT_EQ(read_bits(g, 0, 64), 0x0102030405060708u);
  EXPECT_EQ(read_bits(g, 8, 16), 0x0607u);
  write_bits(g, 3, 0xFFFFFFFF, 5);  // only the low 5 bits of the value
  EXPECT_EQ(g[0], 0xF8);
  EXPECT_EQ(g[1], 0x07);
}

// ---- pack / unpack ------------------------------------------------------------------------

TEST_F(PdoMappingTest, PackMixedSizesLittleEndian) {
  PdoMapping map{{0x2000, 0, 8}, {0x2001, 0, 16}, {0x2002, 0, 32}};
  EXPECT_EQ(pack_pdo(od, map), (Frame{0xAB, 0xFE, 0xFF, 0x44, 0x33, 0x22, 0x11}));
  PdoMapping reversed{{0x2002, 0, 32}, {0x2001, 0, 16}, {0x2000, 0, 8}};
  EXPECT_EQ(pack_pdo(od, reversed), (Frame{0x44, 0x33, 0x22, 0x11, 0xFE, 0xFF, 0xAB}));
  PdoMapping signed_ro{{0x2003, 0, 32}, {0x2100, 2, 8}, {0x2007, 0, 8}, {0x200A, 0, 8}};
  EXPECT_EQ(pack_pdo(od, signed_ro), (Frame{0x00, 0x00, 0x80, 0xFF, 0x80, 0x01, 0x5A}));
  EXPECT_EQ(pack_pdo(od, {{0x2008, 0, 64}}), (Frame{8, 7, 6, 5, 4, 3, 2, 1}));
  EXPECT_EQ(pack_pdo(od, {{0x2009, 0, 32}}), (Frame{0x00, 0x00, 0x80, 0x3F}));  // REAL32 1.0
  EXPECT_TRUE(pack_pdo(od, {}).empty());
}

TEST_F(PdoMappingTest, PackRefreshesComputedValues) {
  int n = 0;
  od.at(0x2003, 0).on_read = [&](Bytes& v) { v = encode<int32_t>(++n * 1000); };
  EXPECT_EQ(pack_pdo(od, {{0x2003, 0, 32}}), encode<int32_t>(1000));
  EXPECT_EQ(pack_pdo(od, {{0x2003, 0, 32}}), encode<int32_t>(2000));
}

TEST_F(PdoMappingTest, UnpackMixedSizes) {
  PdoMapping map{{0x2000, 0, 8}, {0x2001, 0, 16}, {0x2002, 0, 32}};
  EXPECT_EQ(unpack_pdo(od, map, Frame{0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07}), SdoAbort::None);
  EXPECT_EQ(od.get<uint8_t>(0x2000, 0), 0x01);
  EXPECT_EQ(od.get<int16_t>(0x2001, 0), 0x0302);
  EXPECT_EQ(od.get<uint32_t>(0x2002, 0), 0x07060504u);
  EXPECT_EQ(unpack_pdo(od, map, Frame{0xFF, 0x00, 0x80, 0, 0, 0, 0x80}), SdoAbort::None);
  EXPECT_EQ(od.get<int16_t>(0x2001, 0), -32768);
  EXPECT_EQ(od.get<uint32_t>(0x2002, 0), 0x80000000u);
  EXPECT_EQ(od.value(0x2001, 0).size(), 2u);  // stored in the entry's own size
  EXPECT_EQ(unpack_pdo(od, {{0x2004, 0, 16}}, Frame{0x34, 0x12}), SdoAbort::None);  // write-only
  EXPECT_EQ(od.get<uint16_t>(0x2004, 0), 0x1234);
}

TEST_F(PdoMappingTest, UnpackSkipsDummyEntries) {
  // dummy U8 | u8 | dummy U16 | i16 | dummy U8
  PdoMapping map{{0x0005, 0, 8}, {0x2000, 0, 8}, {0x0006, 0, 16}, {0x2001, 0, 16}, {0x0002, 0, 8}};
  EXPECT_EQ(mapping_bytes(map), 7u);
  EXPECT_EQ(unpack_pdo(od, map, Frame{0xEE, 0x42, 0xDD, 0xDD, 0x39, 0x30, 0xEE}), SdoAbort::None);
  EXPECT_EQ(od.get<uint8_t>(0x2000, 0), 0x42);
  EXPECT_EQ(od.get<int16_t>(0x2001, 0), 12345);
  // A dummy packs as zero bits (not used for TPDOs, but harmless).
  EXPECT_EQ(pack_pdo(od, {{0x0005, 0, 8}, {0x2000, 0, 8}}), (Frame{0x00, 0x42}));
}

TEST_F(PdoMappingTest, UnpackLengthRules) {
  PdoMapping map{{0x2000, 0, 8}, {0x2001, 0, 16}};
  // Too short: nothing is written (and nothing is read beyond the data).
  EXPECT_EQ(unpack_pdo(od, map, Frame{0x11, 0x22}), SdoAbort::LengthTooLow);
  EXPECT_EQ(unpack_pdo(od, map, Frame{}), SdoAbort::LengthTooLow);
  EXPECT_EQ(od.get<uint8_t>(0x2000, 0), 0xAB);
  EXPECT_EQ(od.get<int16_t>(0x2001, 0), -2);
  // Longer: the mapped part is used, the rest ignored.
  EXPECT_EQ(unpack_pdo(od, map, Frame{0x11, 0x22, 0x33, 0x44, 0x55}), SdoAbort::None);
  EXPECT_EQ(od.get<uint8_t>(0x2000, 0), 0x11);
  EXPECT_EQ(od.get<int16_t>(0x2001, 0), 0x3322);
  // An empty mapping takes anything.
  EXPECT_EQ(unpack_pdo(od, {}, Frame{}), SdoAbort::None);
}

TEST_F(PdoMappingTest, UnpackReportsTheFirstRefusedWriteAndStoresTheOthers) {
  PdoMapping map{{0x2000, 0, 8}, {0x200B, 0, 8}, {0x2007, 0, 8}, {0x2100, 1, 8}};
  EXPECT_EQ(unpack_pdo(od, map, Frame{0x05, 200, 2, 0x09}), SdoAbort::ValueTooHigh);
  EXPECT_EQ(od.get<uint8_t>(0x2000, 0), 0x05);
  EXPECT_EQ(od.get<uint8_t>(0x200B, 0), 10);  // refused: out of range
  EXPECT_EQ(od.get<uint8_t>(0x2007, 0), 1);   // refused: BOOLEAN 2
  EXPECT_EQ(od.get<uint8_t>(0x2100, 1), 0x09);
}

TEST_F(PdoMappingTest, ReactionsRunOnceTheWholePdoIsStoredAndOnlyForStoredEntries) {
  std::vector<std::string> calls;
  listen(od.at(0x2000, 0),
         [&] { calls.push_back("u8 sees u32=" + std::to_string(od.get<uint32_t>(0x2002, 0))); });
  listen(od.at(0x2002, 0), [&] { calls.push_back("u32"); });
  listen(od.at(0x200B, 0), [&] { calls.push_back("limited"); });
  // The command (u8) comes before its argument (u32) in the PDO, yet sees the new argument.
  PdoMapping map{{0x2000, 0, 8}, {0x200B, 0, 8}, {0x2002, 0, 32}};
  EXPECT_EQ(unpack_pdo(od, map, Frame{1, 200, 0x78, 0x56, 0x34, 0x12}), SdoAbort::ValueTooHigh);
  EXPECT_EQ(calls, (std::vector<std::string>{"u8 sees u32=305419896", "u32"}));
  // A PDO-origin write alone stores without reacting; unpack_pdo runs the reactions.
  calls.clear();
  EXPECT_EQ(od.write(0x2002, 0, encode<uint32_t>(1), WriteOrigin::Pdo), SdoAbort::None);
  EXPECT_TRUE(calls.empty());
  EXPECT_EQ(od.write(0x2002, 0, encode<uint32_t>(2)), SdoAbort::None);
  EXPECT_EQ(calls, (std::vector<std::string>{"u32"}));
}

TEST(PdoRoundTrip, TransmitOnOneDeviceReceiveOnAnother) {
  Dictionary producer, consumer;
  fill(producer);
  fill(consumer);
  producer.put<uint8_t>(0x2000, 0, 0x5C);
  producer.put<int16_t>(0x2001, 0, -12345);
  producer.put<uint32_t>(0x2002, 0, 0xDEADBEEF);
  producer.put<int8_t>(0x2100, 2, -7);
  PdoMapping map{{0x2001, 0, 16}, {0x2000, 0, 8}, {0x2100, 2, 8}, {0x2002, 0, 32}};
  std::vector<uint32_t> words;
  for (const auto& m : map) words.push_back(producer.at(m.index, m.sub).mapping_word());
  ASSERT_EQ(check_mapping(producer, words, PdoDirection::Transmit), SdoAbort::None);
  ASSERT_EQ(check_mapping(consumer, words, PdoDirection::Receive), SdoAbort::None);
  Frame frame = pack_pdo(producer, map);
  EXPECT_EQ(frame, (Frame{0xC7, 0xCF, 0x5C, 0xF9, 0xEF, 0xBE, 0xAD, 0xDE}));
  EXPECT_EQ(unpack_pdo(consumer, map, frame), SdoAbort::None);
  for (const auto& m : map)
    EXPECT_EQ(consumer.value(m.index, m.sub), producer.value(m.index, m.sub));
}

}  // namespace
}  // namespace stepnode::od
