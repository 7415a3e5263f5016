// The one TOML loader of the node and the bridge: every refusal is one line naming the
// file (and the key, or the parser's line), and values are taken without conversions.
#include "config/toml_file.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace stepnode::config {
namespace {

class TomlFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("stepnode-toml-" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string file(const std::string& text) {
    const std::string path = (dir_ / "c.toml").string();
    std::ofstream(path) << text;
    return path;
  }

  // The message of the UsageError `f` throws ("" and a failure when it throws none).
  template <class F>
  static std::string error_of(F f) {
    try {
      f();
    } catch (const UsageError& e) {
      return e.what();
    }
    ADD_FAILURE() << "no UsageError";
    return "";
  }

  std::filesystem::path dir_;
};

TEST_F(TomlFileTest, AMissingFileOrADirectoryCannotBeRead) {
  const std::string missing = (dir_ / "nope.toml").string();
  EXPECT_EQ(error_of([&] { TomlFile{missing}; }), "config " + missing + ": cannot read file");
  EXPECT_EQ(error_of([&] { TomlFile{dir_.string()}; }),
            "config " + dir_.string() + ": cannot read file");
}

TEST_F(TomlFileTest, AParseErrorNamesTheFileAndTheLineOnOneLine) {
  const std::string path = file("a = 1\nb = [\n\x01");
  const std::string msg = error_of([&] { TomlFile{path}; });
  EXPECT_EQ(msg.rfind("config " + path + ": ", 0), 0u) << msg;
  EXPECT_NE(msg.find("(line "), std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
}

TEST_F(TomlFileTest, ValuesOfTheRightTypeAreTakenAbsentKeysAreNullopt) {
  TomlFile f(file("s = \"x\"\nb = true\ni = 42\n"));
  EXPECT_EQ(f.string("s"), "x");
  EXPECT_EQ(f.boolean("b"), true);
  EXPECT_EQ(f.integer("i", 0, 42), 42);
  EXPECT_TRUE(f.has("i"));
  EXPECT_FALSE(f.has("none"));
  EXPECT_EQ(f.string("none"), std::nullopt);
  EXPECT_EQ(f.boolean("none"), std::nullopt);
  EXPECT_EQ(f.integer("none", 0, 1), std::nullopt);
}

TEST_F(TomlFileTest, NoConversionsAndNoValueOutOfRange) {
  TomlFile f(file("s = 5\nb = 1\nf = 5.0\nt = true\ni = 43\n"));
  const std::string p = "config " + f.path() + ": ";
  EXPECT_EQ(error_of([&] { (void)f.string("s"); }), p + "s: must be a string");
  EXPECT_EQ(error_of([&] { (void)f.boolean("b"); }), p + "b: must be true or false");
  EXPECT_EQ(error_of([&] { (void)f.integer("f", 0, 10); }), p + "f: must be an integer 0..10");
  EXPECT_EQ(error_of([&] { (void)f.integer("t", 0, 10); }), p + "t: must be an integer 0..10");
  EXPECT_EQ(error_of([&] { (void)f.integer("i", 0, 42); }), p + "i: must be an integer 0..42");
}

TEST_F(TomlFileTest, UnknownKeysAreRefusedByName) {
  TomlFile f(file("iface = \"can0\"\nspeed = 3\n"));
  EXPECT_EQ(error_of([&] { f.refuse_unknown_keys({"iface"}); }),
            "config " + f.path() + ": speed: unknown key");
  f.refuse_unknown_keys({"iface", "speed"});
}

TEST(OneLine, ControlBytesAreEscapedAndLineBreaksAreSpaces) {
  EXPECT_EQ(one_line("a\nb\tc\r"), "a b c ");
  EXPECT_EQ(one_line(std::string("x\x01y\x7f\xe9", 5)), "x\\x01y\\x7F\\xE9");
}

}  // namespace
}  // namespace stepnode::config
