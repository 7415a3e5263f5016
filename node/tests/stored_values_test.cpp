// Stored and configured values are checked as the dictionary would check them when they
// are loaded (issue 14): a stored or configured PDO mapping naming an object the device
// does not have, a damaged or foreign parameter file, a leftover temporary file. The node
// always starts, keeps the default, and says so by EMCY (0x5530 stored, 0x6100 configured).
#include <fstream>
#include <sstream>

#include "node/config.hpp"
#include "node/emcy.hpp"
#include "node/tests/node_harness.hpp"
#include "od/pdo_mapping.hpp"

namespace stepnode::node::test {
namespace {

constexpr uint32_t kSave = 0x65766173;  // "save"
constexpr uint32_t kTpdo1 = 0x180 + 5;

class StoredValues : public NodeHarness {
 protected:
  std::string file_text() const {
    std::ifstream in(node->parameter_file(), std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  void write_file(const std::string& text) const {
    std::ofstream(node->parameter_file(), std::ios::binary | std::ios::trunc) << text;
  }
  std::filesystem::path aside(int n = 1) const {
    return node->parameter_file().string() + ".corrupt-" + std::to_string(n);
  }
  // The EMCY frames with this error code since `from`.
  std::vector<CanFrame> emcys_with(uint16_t code, size_t from = 0) const {
    std::vector<CanFrame> out;
    for (const CanFrame& f : emcys(from))
      if (emcy_code(f) == code) out.push_back(f);
    return out;
  }
};

TEST_F(StoredValues, AStoredMappingToAnAxisTheDeviceNoLongerHasKeepsTheDefaultAndStarts) {
  // Saved with 2 axes: TPDO 1 carries axis 2's status word (0x2101). Restarted with 1 axis,
  // pack_pdo's Dictionary::at threw std::out_of_range at NMT start and main exited 2, on
  // every restart.
  make(2);
  map_tpdo(0, {0x21010010}, 255);
  ASSERT_EQ(sdo_write(0x1010, 1, kSave), 0u);
  make(1);
  EXPECT_EQ(node->state(), NmtState::PreOperational);
  // The default mapping of TPDO 1 (axis 1's status word) is back, the stored one refused.
  od::Dictionary defaults;
  od::DeviceInfo info;
  info.node_id = kId;
  build_device_objects(defaults, info, DeviceLayout{.axes = 1});
  EXPECT_EQ(od().get<uint8_t>(0x1A00, 0), defaults.get<uint8_t>(0x1A00, 0));
  EXPECT_EQ(od().get<uint32_t>(0x1A00, 1), defaults.get<uint32_t>(0x1A00, 1));
  // EMCY 0x5530 (data storage), error register bit 0; manufacturer bytes: the first
  // refused entry (stored objects of axis 2 come first), how many, 0 = the file was fine.
  auto e = emcys_with(emcy_code::kDataStorage);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].data[2] & error_bits::kGeneric, error_bits::kGeneric);
  EXPECT_GE(e[0].data[6], 2);
  EXPECT_EQ(e[0].data[7], 0);
  // Operational: the TPDOs go out, nothing throws.
  size_t from = sent.size();
  nmt(0x01);
  EXPECT_EQ(node->state(), NmtState::Operational);
  advance_ms(10);
  EXPECT_FALSE(with_id(kTpdo1, from).empty());
}

TEST_F(StoredValues, AConfiguredMappingNamingAMissingObjectKeepsTheBuiltInAndIsReported) {
  od::Dictionary& d = od();
  const uint32_t built_in = d.get<uint32_t>(0x1A00, 1);
  auto refused = apply_object_defaults(d, {{"1A00:1", "0x99990020"}, {"1017", "250"}});
  ASSERT_EQ(refused.size(), 1u);
  EXPECT_EQ(refused[0].index, 0x1A00);
  EXPECT_EQ(refused[0].reason, od::SdoAbort::NoObject);
  EXPECT_EQ(d.get<uint32_t>(0x1A00, 1), built_in);
  EXPECT_EQ(d.get<uint16_t>(0x1017, 0), 250);  // the rest of the file applies
  // A mapping the device can use is applied (axis 1's motor position, 32 bits).
  EXPECT_TRUE(apply_object_defaults(d, {{"1A00:1", "0x20050020"}}).empty());
  EXPECT_EQ(d.get<uint32_t>(0x1A00, 1), 0x20050020u);
}

TEST_F(StoredValues, AConfigurationErrorFoundBeforeBootUpGoesOutAfterIt) {
  make(1, {{"1A00:1", "0x99990020"}});  // the device refuses the record, then boots
  ASSERT_EQ(device->refused_mappings().size(), 1u);
  size_t from = 0;
  // Boot-up first (EMCY may not be sent before), then EMCY 0x6100.
  ASSERT_GE(sent.size(), from + 2);
  EXPECT_EQ(sent[from].id, kHeartbeatId);
  auto e = emcys_with(emcy_code::kSoftware, from);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].data[3], 0x00);
  EXPECT_EQ(e[0].data[4], 0x1A);
  // Reset node re-reads the same configuration: reported again.
  from = sent.size();
  nmt(0x81);
  advance_ms(10);
  EXPECT_EQ(emcys_with(emcy_code::kSoftware, from).size(), 1u);
}

TEST_F(StoredValues, TheFileIsVersionedAndChecksummed) {
  ASSERT_EQ(sdo_write(0x1017, 0, 250, 2), 0u);
  ASSERT_EQ(sdo_write(0x1010, 1, kSave), 0u);
  std::string text = file_text();
  EXPECT_EQ(text.rfind("# stepnode stored parameters v2\n", 0), 0u) << text;
  size_t crc = text.rfind("# crc32 ");
  ASSERT_NE(crc, std::string::npos);
  EXPECT_EQ(crc + 8 + 8 + 1, text.size());  // the last line: 8 hex digits
}

TEST_F(StoredValues, ADamagedFileIsSetAsideDefaultsApplyAndEmcySaysSo) {
  ASSERT_EQ(sdo_write(0x1017, 0, 250, 2), 0u);
  ASSERT_EQ(sdo_write(0x1010, 1, kSave), 0u);
  std::string text = file_text();
  size_t pos = text.find("1017:00 fa00");
  ASSERT_NE(pos, std::string::npos) << text;
  text[pos + 8] = 'e';  // one flipped digit: 0x00ea = 234 would load without the checksum
  write_file(text);
  make();
  EXPECT_EQ(od().get<uint16_t>(0x1017, 0), 1000);
  EXPECT_FALSE(std::filesystem::exists(node->parameter_file()));
  ASSERT_TRUE(std::filesystem::exists(aside()));
  {
    std::ifstream in(aside(), std::ios::binary);
    std::stringstream kept;
    kept << in.rdbuf();
    EXPECT_EQ(kept.str(), text);  // kept as it was, for a look
  }
  auto e = emcys_with(emcy_code::kDataStorage);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].data[7], 1);  // the file was set aside
  EXPECT_EQ(node->state(), NmtState::PreOperational);
  // A second damaged file goes beside the first; a save afterwards is a good file again.
  write_file("not ours\n");
  make();
  EXPECT_TRUE(std::filesystem::exists(aside(2)));
  ASSERT_EQ(sdo_write(0x1017, 0, 260, 2), 0u);
  ASSERT_EQ(sdo_write(0x1010, 1, kSave), 0u);
  make();
  EXPECT_EQ(od().get<uint16_t>(0x1017, 0), 260);
  EXPECT_TRUE(emcys_with(emcy_code::kDataStorage).empty());
}

TEST_F(StoredValues, ForeignEmptyAndTruncatedFilesAreSetAside) {
  ASSERT_EQ(sdo_write(0x1017, 0, 250, 2), 0u);
  ASSERT_EQ(sdo_write(0x1010, 1, kSave), 0u);
  const std::string good = file_text();
  int n = 0;
  for (const std::string& bad :
       {std::string("\0\xff\x01\n\n", 5), std::string(), good.substr(0, good.size() - 3),
        good + "1017:00 f401\n", std::string("[defaults]\n\"1017\" = 250\n")}) {
    write_file(bad);
    make();
    ++n;
    EXPECT_EQ(od().get<uint16_t>(0x1017, 0), 1000) << n;
    EXPECT_TRUE(std::filesystem::exists(aside(n))) << n;
    EXPECT_EQ(emcys_with(emcy_code::kDataStorage).size(), 1u) << n;
  }
}

TEST_F(StoredValues, AVersion1FileOfAnEarlierBuildStillLoads) {
  // Version 1 had no checksum: its readable lines load, the others are skipped.
  write_file(
      "# stepnode stored parameters v1\n1017:00 fa00\ngarbage line\n1017:01 zz\n2F00:01 "
      "efbeadde\n");
  make();
  EXPECT_EQ(od().get<uint16_t>(0x1017, 0), 250);
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 0xDEADBEEFu);
  EXPECT_TRUE(std::filesystem::exists(node->parameter_file()));
  EXPECT_TRUE(emcys_with(emcy_code::kDataStorage).empty());  // unreadable lines: logged only
  // A readable line the dictionary refuses (0x7777 does not exist) is reported.
  write_file("# stepnode stored parameters v1\n1017:00 fa00\n7777:01 00000000\n");
  make();
  EXPECT_EQ(od().get<uint16_t>(0x1017, 0), 250);
  auto e = emcys_with(emcy_code::kDataStorage);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].data[3], 0x77);
  EXPECT_EQ(e[0].data[4], 0x77);
  EXPECT_EQ(e[0].data[5], 0x01);
}

TEST_F(StoredValues, AVersion1FileWithCrLfLinesLoadsAndAStrangeHeaderIsNotOurs) {
  write_file("# stepnode stored parameters v1\r\n1017:00 fa00\r\n");
  make();
  EXPECT_EQ(od().get<uint16_t>(0x1017, 0), 250);
  EXPECT_TRUE(emcys_with(emcy_code::kDataStorage).empty());
  // "v2garbage" or "v20" is not version 2, whatever follows.
  ASSERT_EQ(sdo_write(0x1010, 1, kSave), 0u);
  std::string text = file_text();
  write_file("# stepnode stored parameters v20" + text.substr(text.find('\n')));
  make();
  EXPECT_EQ(od().get<uint16_t>(0x1017, 0), 1000);
  EXPECT_TRUE(std::filesystem::exists(aside()));
}

TEST_F(StoredValues, AStaleTemporaryFileIsRemovedAtStart) {
  std::filesystem::path tmp = node->parameter_file().string() + ".tmp";
  std::ofstream(tmp) << "# stepnode stored parameters v2\n1017:00 f401\n10";
  make();
  EXPECT_FALSE(std::filesystem::exists(tmp));
  EXPECT_EQ(od().get<uint16_t>(0x1017, 0), 1000);
}

TEST(PdoMappingRecord, PackingAnEntryTheDictionaryLacksGivesZerosNotAThrow) {
  od::Dictionary d;
  build_device_objects(d, od::DeviceInfo{}, DeviceLayout{.axes = 1});
  od::PdoMapping m{od::MappedEntry::from_word(0x99990020), od::MappedEntry::from_word(0x10010008)};
  std::vector<uint8_t> data;
  EXPECT_NO_THROW(data = od::pack_pdo(d, m));
  ASSERT_EQ(data.size(), 5u);
  EXPECT_EQ(data[0] | data[1] | data[2] | data[3], 0);
  // The record check names what the mapping procedure would answer.
  d.put<uint32_t>(0x1A00, 1, 0x99990020);
  EXPECT_EQ(od::check_mapping_record(d, 0x1A00), od::SdoAbort::NoObject);
  d.put<uint32_t>(0x1A00, 1, 0x10170010);  // 0x1017 is not PDO-mappable
  EXPECT_EQ(od::check_mapping_record(d, 0x1A00), od::SdoAbort::NotMappable);
  d.put<uint8_t>(0x1A00, 0, 0);
  EXPECT_EQ(od::check_mapping_record(d, 0x1A00), od::SdoAbort::None);  // nothing mapped
}

TEST(OneLine, ControlBytesAndLineBreaksNeverReachStderrRaw) {
  EXPECT_EQ(one_line("a\nb\tc\r"), "a b c ");
  EXPECT_EQ(one_line(std::string("x\x01y\x7f\xe9", 5)), "x\\x01y\\x7F\\xE9");
}

}  // namespace
}  // namespace stepnode::node::test
