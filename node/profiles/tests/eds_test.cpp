// The EDS (CiA 306 v1.3): written from the device dictionary and read back. Checks the
// file structure of CiA 306 section 4 (FileInfo, DeviceInfo, DummyUsage, the three object
// lists, one section per object and sub-object with ObjectType/SubNumber/DataType/
// AccessType/DefaultValue/PDOMapping/limits), $NODEID defaults, and the reader's errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "node/profiles/tests/stepnode_device.hpp"
#include "od/eds.hpp"
#include "od/pdo_mapping.hpp"

namespace stepnode::od {
namespace {

std::string hex4(unsigned v) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "%04X", v);
  return buf;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

// The value an EDS DefaultValue stands for on node `node_id` ("$NODEID+0x180" included).
Bytes eds_default_bytes(DataType type, const std::string& text, uint8_t node_id) {
  const std::string kNodeId = "$NODEID+";
  if (text.rfind(kNodeId, 0) == 0) {
    Bytes offset = parse_value(type, text.substr(kNodeId.size()));
    uint64_t v = as_unsigned(type, offset) + node_id;
    Bytes all = encode<uint64_t>(v);
    return Bytes(all.begin(), all.begin() + static_cast<long>(fixed_size(type)));
  }
  if (type == DataType::OctetString || type == DataType::Domain) {
    Bytes out;
    for (size_t i = 0; i + 1 < text.size(); i += 2)
      out.push_back(static_cast<uint8_t>(std::stoul(text.substr(i, 2), nullptr, 16)));
    return out;
  }
  return parse_value(type, text);
}

class EdsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    build_stepnode_device(od, info);
    text = write_eds(od, info);
    eds = parse_eds(text);
  }
  const std::map<std::string, std::string>& section(const std::string& name) {
    auto it = eds.sections.find(lower(name));
    if (it == eds.sections.end()) throw std::runtime_error("no section [" + name + "]");
    return it->second;
  }
  std::string get(const std::string& sec, const std::string& key) {
    const auto& s = section(sec);
    auto it = s.find(lower(key));
    return it == s.end() ? "<missing>" : it->second;
  }
  std::vector<uint16_t> list(const std::string& name) {
    std::vector<uint16_t> out;
    unsigned n = static_cast<unsigned>(std::stoul(get(name, "SupportedObjects")));
    for (unsigned i = 1; i <= n; ++i)
      out.push_back(static_cast<uint16_t>(std::stoul(get(name, std::to_string(i)), nullptr, 16)));
    return out;
  }

  DeviceInfo info;
  Dictionary od;
  std::string text;
  EdsFile eds;
};

// ---- round trip -------------------------------------------------------------------------

TEST_F(EdsTest, EveryEntryRoundTripsTypeAccessPdoFlagAndDefault) {
  size_t entries = 0;
  for (const auto& [index, obj] : od.objects()) {
    for (const auto& [sub, e] : obj.entries) {
      SCOPED_TRACE(testing::Message() << std::hex << index << ":" << int(sub) << " " << e.name);
      ++entries;
      const EdsEntry* got = eds.find(index, sub);
      ASSERT_NE(got, nullptr);
      EXPECT_EQ(got->index, index);
      EXPECT_EQ(got->sub, sub);
      EXPECT_EQ(got->type, e.type);
      EXPECT_EQ(got->access, e.access);
      EXPECT_EQ(got->pdo_mappable, e.pdo_mappable);
      EXPECT_EQ(got->name, obj.code == ObjectCode::Var ? obj.name : obj.name + " / " + e.name);
      if (e.type == DataType::Domain) {
        EXPECT_EQ(got->default_value, "");  // CiA 306: no DefaultValue for a DOMAIN
        EXPECT_TRUE(e.default_value.empty());
      } else {
        EXPECT_EQ(eds_default_bytes(e.type, got->default_value, info.node_id), e.default_value)
            << got->default_value;
      }
    }
  }
  EXPECT_EQ(eds.entries.size(), entries);
}

TEST_F(EdsTest, LimitsAreWrittenInTheEntrysType) {
  for (const auto& [index, obj] : od.objects()) {
    for (const auto& [sub, e] : obj.entries) {
      SCOPED_TRACE(testing::Message() << std::hex << index << ":" << int(sub));
      std::string sec = obj.code == ObjectCode::Var
                            ? hex4(index)
                            : hex4(index) + "sub" + hex4(sub).substr(2 + (sub < 16));
      const auto& s = section(sec);
      EXPECT_EQ(s.count("lowlimit"), e.low ? 1u : 0u);
      EXPECT_EQ(s.count("highlimit"), e.high ? 1u : 0u);
      if (e.low) {
        EXPECT_EQ(parse_value(e.type, s.at("lowlimit")), *e.low);
      }
      if (e.high) {
        EXPECT_EQ(parse_value(e.type, s.at("highlimit")), *e.high);
      }
    }
  }
  EXPECT_EQ(get("1A00sub0", "HighLimit"), "8");
  EXPECT_EQ(get("1800sub6", "HighLimit"), "240");
  EXPECT_EQ(get("2002", "LowLimit"), "-8388608");
  EXPECT_EQ(get("2002", "HighLimit"), "8388607");
}

TEST_F(EdsTest, NodeDependentDefaultsAreNodeIdExpressions) {
  DeviceInfo other_info{.node_id = 77};
  Dictionary other;
  build_stepnode_device(other, other_info);
  std::set<std::pair<uint16_t, uint8_t>> node_dependent;
  for (const auto& [index, obj] : od.objects()) {
    for (const auto& [sub, e] : obj.entries) {
      SCOPED_TRACE(testing::Message() << std::hex << index << ":" << int(sub));
      const std::string& def = eds.find(index, sub)->default_value;
      bool depends = other.value(index, sub) != e.default_value;
      EXPECT_EQ(def.find("$NODEID") != std::string::npos, depends) << def;
      if (!depends) continue;
      node_dependent.insert({index, sub});
      EXPECT_EQ(eds_default_bytes(e.type, def, 77), other.value(index, sub)) << def;
    }
  }
  std::set<std::pair<uint16_t, uint8_t>> expected{{0x1014, 0}, {0x1200, 1}, {0x1200, 2}};
  for (uint16_t n = 0; n < 4; ++n) {
    expected.insert({static_cast<uint16_t>(0x1400 + n), 1});
    expected.insert({static_cast<uint16_t>(0x1800 + n), 1});
  }
  EXPECT_EQ(node_dependent, expected);
  EXPECT_EQ(get("1014", "DefaultValue"), "$NODEID+0x80");
  EXPECT_EQ(get("1200sub1", "DefaultValue"), "$NODEID+0x600");
  EXPECT_EQ(get("1200sub2", "DefaultValue"), "$NODEID+0x580");
  EXPECT_EQ(get("1400sub1", "DefaultValue"), "$NODEID+0x200");
  EXPECT_EQ(get("1803sub1", "DefaultValue"), "$NODEID+0x40000480");
  // So the file itself does not depend on the node-ID.
  EXPECT_EQ(write_eds(other, other_info), text);
}

TEST_F(EdsTest, WritingIsDeterministic) { EXPECT_EQ(write_eds(od, info), text); }

// ---- structure (CiA 306 section 4) ----------------------------------------------------------

TEST_F(EdsTest, EveryLineIsASectionAKeyValueOrBlank) {
  std::vector<std::string> lines = lines_of(text);
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines.front(), "[FileInfo]");
  std::regex header(R"(\[[A-Za-z0-9_]+\])"), key_value(R"([A-Za-z0-9_$]+=[^\r\n]*)");
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string& l = lines[i];
    EXPECT_TRUE(l.empty() || std::regex_match(l, header) || std::regex_match(l, key_value))
        << "line " << i + 1 << ": " << l;
    EXPECT_LE(l.size(), 255u) << "line " << i + 1;
    if (!l.empty()) {
      EXPECT_NE(l.back(), ' ') << "line " << i + 1;
    }
  }
  // Each section once.
  std::set<std::string> seen;
  for (const auto& l : lines)
    if (!l.empty() && l[0] == '[') {
      EXPECT_TRUE(seen.insert(lower(l)).second) << l;
    }
}

TEST_F(EdsTest, FileInfo) {
  EXPECT_EQ(get("FileInfo", "FileName"), "stepnode.eds");
  EXPECT_EQ(get("FileInfo", "EDSVersion"), "4.0");
  EXPECT_EQ(get("FileInfo", "FileVersion"), "1");
  EXPECT_EQ(get("FileInfo", "FileRevision"), "0");
  EXPECT_NE(get("FileInfo", "Description"), "<missing>");
  std::regex time(R"((0[1-9]|1[0-2]):[0-5][0-9](AM|PM))"),
      date(R"((0[1-9]|1[0-2])-(0[1-9]|[12][0-9]|3[01])-[0-9]{4})");
  for (const char* k : {"CreationTime", "ModificationTime"})
    EXPECT_TRUE(std::regex_match(get("FileInfo", k), time)) << k;
  for (const char* k : {"CreationDate", "ModificationDate"})
    EXPECT_TRUE(std::regex_match(get("FileInfo", k), date)) << k;
  EXPECT_NE(get("FileInfo", "CreatedBy"), "<missing>");
  EXPECT_NE(get("FileInfo", "ModifiedBy"), "<missing>");
}

TEST_F(EdsTest, DeviceInfo) {
  EXPECT_EQ(get("DeviceInfo", "VendorName"), "stepnode project");
  EXPECT_EQ(std::stoul(get("DeviceInfo", "VendorNumber"), nullptr, 16), info.vendor_id);
  EXPECT_EQ(get("DeviceInfo", "ProductName"), info.device_name);
  EXPECT_EQ(std::stoul(get("DeviceInfo", "ProductNumber"), nullptr, 16), info.product_code);
  EXPECT_EQ(std::stoul(get("DeviceInfo", "RevisionNumber"), nullptr, 16), info.revision);
  EXPECT_NE(get("DeviceInfo", "OrderCode"), "<missing>");
  for (int rate : {10, 20, 50, 125, 250, 500, 800, 1000})
    EXPECT_EQ(get("DeviceInfo", "BaudRate_" + std::to_string(rate)), "1") << rate;
  EXPECT_EQ(get("DeviceInfo", "SimpleBootUpMaster"), "0");
  EXPECT_EQ(get("DeviceInfo", "SimpleBootUpSlave"), "1");
  EXPECT_EQ(get("DeviceInfo", "DynamicChannelsSupported"), "0");
  EXPECT_EQ(get("DeviceInfo", "GroupMessaging"), "0");
  EXPECT_EQ(get("DeviceInfo", "LSS_Supported"), "0");
  EXPECT_EQ(get("DeviceInfo", "NrOfRXPDO"), "12");
  EXPECT_EQ(get("DeviceInfo", "NrOfTXPDO"), "12");
  // Granularity 8: every mappable entry is a whole number of bytes.
  EXPECT_EQ(get("DeviceInfo", "Granularity"), "8");
  for (const auto& [index, obj] : od.objects())
    for (const auto& [sub, e] : obj.entries)
      if (e.pdo_mappable) {
        EXPECT_EQ(e.bit_length() % 8, 0u) << std::hex << index;
      }
}

TEST(EdsPdoCount, NrOfPdosIsFourPerAxis) {
  for (unsigned axes : {1u, 2u, 8u}) {
    DeviceInfo info;
    Dictionary od;
    build_stepnode_device(od, info, {.axes = axes});
    EdsFile eds = parse_eds(write_eds(od, info));
    EXPECT_EQ(eds.sections["deviceinfo"]["nrofrxpdo"], std::to_string(4 * axes));
    EXPECT_EQ(eds.sections["deviceinfo"]["nroftxpdo"], std::to_string(4 * axes));
  }
}

TEST_F(EdsTest, DummyUsageMatchesWhatTheMappingAccepts) {
  for (uint16_t type = 1; type <= 7; ++type) {
    std::string key = "Dummy000" + std::to_string(type);
    size_t bits = fixed_size(static_cast<DataType>(type)) * 8;
    uint32_t word = (uint32_t{type} << 16) | static_cast<uint32_t>(bits);
    bool accepted = check_mapping_entry(od, word, PdoDirection::Receive) == SdoAbort::None;
    EXPECT_EQ(get("DummyUsage", key), accepted ? "1" : "0") << key;
  }
  EXPECT_EQ(get("DummyUsage", "Dummy0001"), "0");
  EXPECT_EQ(get("DummyUsage", "Dummy0007"), "1");
}

TEST_F(EdsTest, ObjectListsCoverEveryObjectOnce) {
  std::vector<uint16_t> mandatory = list("MandatoryObjects"), optional = list("OptionalObjects"),
                        manufacturer = list("ManufacturerObjects");
  EXPECT_EQ(mandatory, (std::vector<uint16_t>{0x1000, 0x1001, 0x1018}));
  std::multiset<uint16_t> all;
  for (uint16_t i : optional) {
    EXPECT_TRUE((i >= 0x1000 && i <= 0x1FFF) || (i >= 0x6000 && i <= 0x9FFF)) << std::hex << i;
    EXPECT_TRUE(i != 0x1000 && i != 0x1001 && i != 0x1018) << std::hex << i;
  }
  for (uint16_t i : manufacturer) EXPECT_TRUE(i >= 0x2000 && i <= 0x5FFF) << std::hex << i;
  for (const auto* l : {&mandatory, &optional, &manufacturer}) all.insert(l->begin(), l->end());
  std::multiset<uint16_t> objects;
  for (const auto& [index, obj] : od.objects()) objects.insert(index);
  EXPECT_EQ(all, objects);
  EXPECT_TRUE(std::is_sorted(optional.begin(), optional.end()));
  EXPECT_TRUE(std::is_sorted(manufacturer.begin(), manufacturer.end()));
  // The lists' own numbering is 1..n.
  EXPECT_EQ(get("MandatoryObjects", "SupportedObjects"), "3");
  EXPECT_EQ(get("MandatoryObjects", "1"), "0x1000");
  EXPECT_EQ(get("MandatoryObjects", "2"), "0x1001");
  EXPECT_EQ(get("MandatoryObjects", "3"), "0x1018");
  EXPECT_EQ(get("MandatoryObjects", "4"), "<missing>");
}

TEST_F(EdsTest, ObjectSectionsObjectTypeAndSubNumber) {
  for (const auto& [index, obj] : od.objects()) {
    SCOPED_TRACE(testing::Message() << std::hex << index);
    std::string name = hex4(index);
    EXPECT_EQ(get(name, "ParameterName"), obj.name);
    if (obj.code == ObjectCode::Var) {
      EXPECT_EQ(get(name, "ObjectType"), "0x7");
      EXPECT_EQ(get(name, "SubNumber"), "<missing>");
      EXPECT_EQ(eds.sections.count(lower(name) + "sub0"), 0u);
      continue;
    }
    EXPECT_EQ(get(name, "ObjectType"), obj.code == ObjectCode::Array ? "0x8" : "0x9");
    EXPECT_EQ(get(name, "SubNumber"), std::to_string(obj.entries.size()));
    EXPECT_EQ(get(name, "DataType"), "<missing>");
    size_t subs = 0;
    for (const auto& [sec, values] : eds.sections)
      if (sec.rfind(lower(name) + "sub", 0) == 0) {
        ++subs;
        EXPECT_EQ(values.at("objecttype"), "0x7") << sec;
      }
    EXPECT_EQ(subs, obj.entries.size());
  }
  EXPECT_EQ(get("1003", "ObjectType"), "0x8");
  EXPECT_EQ(get("1010", "ObjectType"), "0x8");
  EXPECT_EQ(get("1016", "ObjectType"), "0x8");
  EXPECT_EQ(get("1018", "ObjectType"), "0x9");
  EXPECT_EQ(get("1018", "SubNumber"), "5");
  EXPECT_EQ(get("1800", "SubNumber"), "6");  // 0, 1, 2, 3, 5, 6
  EXPECT_EQ(eds.sections.count("1800sub4"), 0u);
  EXPECT_EQ(get("1A00", "SubNumber"), "9");
  EXPECT_EQ(get("1000", "DataType"), "0x0007");
  EXPECT_EQ(get("1008", "AccessType"), "const");
  EXPECT_EQ(get("1008", "DefaultValue"), "stepnode");
  EXPECT_EQ(get("1001", "PDOMapping"), "1");
  EXPECT_EQ(get("1021", "DataType"), "0x000F");
  EXPECT_EQ(get("1021", "DefaultValue"), "<missing>");
}

// ---- reading: leniency of CiA 306 and errors naming the line ----------------------------------

TEST(EdsReader, AcceptsTheCiA306Variants) {
  const std::string text =
      "; a comment\r\n"
      "[FileInfo]\r\n"
      "FileName = x.eds \r\n"
      "\r\n"
      "[1000]\r\n"
      "ParameterName=Device type\r\n"
      "DataType=7\r\n"  // decimal
      "AccessType=RO\r\n"
      "DefaultValue=0x00020192\r\n"
      "[1003]\r\n"  // compact array: the header carries DataType, no sub sections
      "ParameterName=Pre-defined error field\r\n"
      "ObjectType=0x8\r\n"
      "DataType=0x0007\r\n"
      "AccessType=ro\r\n"
      "CompactSubObj=254\r\n"
      "[1003Name]\r\n"
      "NrOfEntries=0\r\n"
      "[1018]\r\n"
      "ParameterName=Identity\r\n"
      "ObjectType=9\r\n"
      "SubNumber=2\r\n"
      "[1018SUB0]\r\n"
      "ParameterName=Count\r\n"
      "DataType=0x0005\r\n"
      "AccessType=const\r\n"
      "DefaultValue=1\r\n"
      "[1018sub1]\r\n"
      "parametername=Vendor-ID\r\n"
      "datatype=0x0007\r\n"
      "accesstype=rwr\r\n"
      "pdomapping=0x1\r\n"
      "[2000]\r\n"
      "ParameterName=x\r\n"
      "DataType=0x0006\r\n"
      "AccessType=rww\r\n"
      "[Tools]\r\n"
      "Items=0\r\n";
  EdsFile eds = parse_eds(text);
  EXPECT_EQ(eds.sections["fileinfo"]["filename"], "x.eds");
  ASSERT_EQ(eds.entries.size(), 4u);
  EXPECT_EQ(eds.find(0x1003, 0), nullptr);  // not a bogus sub 0 of the element type
  const EdsEntry* dev = eds.find(0x1000, 0);
  ASSERT_NE(dev, nullptr);
  EXPECT_EQ(dev->type, DataType::Unsigned32);
  EXPECT_EQ(dev->access, Access::ReadOnly);
  EXPECT_FALSE(dev->pdo_mappable);
  EXPECT_EQ(dev->default_value, "0x00020192");
  const EdsEntry* vendor = eds.find(0x1018, 1);
  ASSERT_NE(vendor, nullptr);
  EXPECT_EQ(vendor->name, "Identity / Vendor-ID");
  EXPECT_EQ(vendor->access, Access::ReadWrite);
  EXPECT_TRUE(vendor->pdo_mappable);
  EXPECT_EQ(vendor->default_value, "");
  EXPECT_EQ(eds.find(0x1018, 0)->access, Access::Const);
  EXPECT_EQ(eds.find(0x2000, 0)->access, Access::ReadWrite);
  EXPECT_EQ(eds.find(0x2000, 1), nullptr);
}

void expect_error_at_line(const std::string& text, int line, const std::string& also = "") {
  try {
    parse_eds(text);
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const std::runtime_error& e) {
    std::string what = e.what();
    EXPECT_NE(what.find("EDS line " + std::to_string(line) + ":"), std::string::npos) << what;
    if (!also.empty()) {
      EXPECT_NE(what.find(also), std::string::npos) << what;
    }
  }
}

TEST(EdsReader, ErrorsNameTheLine) {
  expect_error_at_line("[FileInfo]\nFileName=x\n[DeviceInfo\n", 3, "unterminated");
  expect_error_at_line("[FileInfo]\n\n; comment\nnot a key value\n", 4, "key=value");
  expect_error_at_line("FileName=x\n[FileInfo]\n", 1, "before the first");
  expect_error_at_line("[FileInfo]\n=5\n", 2, "empty key");
  expect_error_at_line("[]\n", 1, "empty section");
  expect_error_at_line("[1000]\nParameterName=x\nDataType=0x0007\nAccessType=xx\n", 4,
                       "AccessType 'xx'");
  expect_error_at_line("[1000]\nParameterName=x\nDataType=0x00zz\nAccessType=ro\n", 3, "DataType");
  expect_error_at_line("[1000]\nParameterName=x\nDataType=-7\nAccessType=ro\n", 3, "DataType");
  expect_error_at_line("[1000]\nParameterName=x\nDataType=0x10007\nAccessType=ro\n", 3, "DataType");
  expect_error_at_line("[1000]\nParameterName=x\nDataType=0x0007\nAccessType=ro\nPDOMapping=yes\n",
                       5, "PDOMapping");
  expect_error_at_line("[FileInfo]\n[1000]\nParameterName=x\nAccessType=ro\n", 2, "no DataType");
  expect_error_at_line("[1000]\nDataType=0x0007\nAccessType=ro\n", 1, "no ParameterName");
  expect_error_at_line("[1000]\nParameterName=x\nDataType=0x0007\n", 1, "no AccessType");
  expect_error_at_line("\n\n[1018sub100]\nParameterName=x\nDataType=0x0007\nAccessType=ro\n", 3,
                       "sub-index");
  expect_error_at_line("[1018subx]\n", 1, "sub-index");
  expect_error_at_line("[1018]\nObjectType=nine\n", 2, "ObjectType");
  expect_error_at_line("[1018sub1]\nParameterName=x\nAccessType=ro\n", 1, "no DataType");
}

TEST_F(EdsTest, TheGeneratedFileParsesBackToTheSameSections) {
  size_t headers = 0;
  for (const auto& l : lines_of(text))
    if (!l.empty() && l[0] == '[') ++headers;
  EXPECT_EQ(eds.sections.size(), headers);
  EXPECT_EQ(parse_eds(text).entries.size(), eds.entries.size());
}

}  // namespace
}  // namespace stepnode::od
