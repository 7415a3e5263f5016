// The stepcalc command itself: exit codes, one-line refusals, --json, --plot.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tools/stepcalc/tests/xml_check.hpp"

namespace {

struct CliRun {
  int status = -1;
  std::string out;  // stdout and stderr together
};

CliRun stepcalc(const std::string& args, const std::string& env = "") {
  std::string cmd = env + " " STEPCALC_EXE " " + args + " 2>&1";
  CliRun r;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  int st = pclose(p);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

std::filesystem::path temp_file(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         ("stepcalc_test_" + std::to_string(getpid()) + "_" + name);
}

TEST(StepcalcCli, RefusesBadInputWithExit2AndOneLineGivingTheRange) {
  struct Case {
    const char* args;
    const char* range;
  };
  for (Case c :
       {Case{"16777216 600 100 1000 500 0", "0..16777215"},
        Case{"-1 600 100 1000 500 0", "0..16777215"}, Case{"ten 600 100 1000 500 0", "0..16777215"},
        Case{"100 10 100 1000 500 0", "20..65535"}, Case{"100 600 0 1000 500 0", "1..8190"},
        Case{"100 600 -3 1000 500 0", "1..8190"}, Case{"100 600 100 9000 500 0", "101..8191"},
        Case{"100 600 100 1000 27301 0", "1..27300"}, Case{"100 600 100 1000 500 x", "0..27300"},
        Case{"100 600 100 1000 500", "AQ3 AQ4 AQ5 AQ6 AQ7"},
        Case{"100 600 100 1000 500 0 9", "AQ3 AQ4 AQ5 AQ6 AQ7"},
        Case{"100 600 100 1000 500 0 --plot x.pdf", ".svg or .png"}}) {
    CliRun r = stepcalc(c.args);
    EXPECT_EQ(r.status, 2) << c.args << ": " << r.out;
    EXPECT_NE(r.out.find(c.range), std::string::npos) << c.args << ": " << r.out;
    EXPECT_EQ(r.out.rfind("stepcalc: ", 0), 0u) << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << c.args << ": " << r.out;
  }
}

TEST(StepcalcCli, PrintsTheReportAndJson) {
  CliRun text = stepcalc("10000 600 100 1000 500 0");
  EXPECT_EQ(text.status, 0) << text.out;
  EXPECT_NE(text.out.find("Actual acceleration rate ="), std::string::npos);
  CliRun none = stepcalc("- 20 1 8191 100 0");
  EXPECT_EQ(none.status, 0) << none.out;
  EXPECT_NE(none.out.find("Actual total acc/dec time ="), std::string::npos);
  CliRun json = stepcalc("- 20 1 8191 100 0 --json");
  ASSERT_EQ(json.status, 0) << json.out;
  nlohmann::json j = nlohmann::json::parse(json.out);
  EXPECT_DOUBLE_EQ(j["running_velocity"].get<double>(), 245730.0);
  EXPECT_DOUBLE_EQ(j["engine"]["acceleration_pulses"].get<double>(), 12491.0);
  EXPECT_EQ(stepcalc("--help").status, 0);
}

TEST(StepcalcCli, PlotsSvg) {
  auto path = temp_file("plot.svg");
  CliRun r = stepcalc("300 600 100 1000 500 250 --plot " + path.string());
  ASSERT_EQ(r.status, 0) << r.out;
  std::ifstream in(path);
  std::stringstream svg;
  svg << in.rdbuf();
  std::filesystem::remove(path);
  stepnode::tools::testing::XmlCheck xml(svg.str());
  int series = 0;
  for (const auto& e : xml.elements())
    if (e.name == "polyline") ++series;
  EXPECT_EQ(series, 2);
}

TEST(StepcalcCli, PlotsPngWithRsvgConvertOrSaysWhatIsMissing) {
  auto path = temp_file("plot.png");
  // Without rsvg-convert on the PATH: exit 1 and the Debian package to install.
  CliRun missing =
      stepcalc("300 600 100 1000 500 250 --plot " + path.string(), "PATH=/nonexistent");
  EXPECT_EQ(missing.status, 1) << missing.out;
  EXPECT_NE(missing.out.find("librsvg2-bin"), std::string::npos) << missing.out;
  if (std::system("command -v rsvg-convert >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "rsvg-convert not installed";
  CliRun r = stepcalc("300 600 100 1000 500 250 --plot " + path.string());
  ASSERT_EQ(r.status, 0) << r.out;
  std::ifstream in(path, std::ios::binary);
  char magic[8] = {};
  in.read(magic, 8);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
  EXPECT_GT(std::filesystem::file_size(path), 1000u);
  std::filesystem::remove(path);
}

TEST(StepcalcCli, Cia402MoveAndItsRefusals) {
  CliRun ok = stepcalc(
      "cia402 8000 --velocity 4000 --acceleration 5000 --profile-type 3 --jerk 10000 --json");
  ASSERT_EQ(ok.status, 0) << ok.out;
  auto j = nlohmann::json::parse(ok.out);
  EXPECT_NEAR(j["closed_form"]["time_ms"].get<double>(), 3300.0, 1e-6);  // 1.3 + 0.7 + 1.3 s
  EXPECT_EQ(j["deceleration"], 5000);                                    // 6084h defaults to 6083h
  for (const char* args : {"cia402 0 --velocity 1 --acceleration 1", "cia402 10 --acceleration 1",
                           "cia402 10 --velocity 1 --acceleration 1 --profile-type 2",
                           "cia402 10 --velocity 1 --acceleration 1 --jerk 5 --jerks 1 2 3 4",
                           "cia402 10 --velocity 1 --acceleration 1 --plot x.pdf"}) {
    CliRun bad = stepcalc(args);
    EXPECT_EQ(bad.status, 2) << args << ": " << bad.out;
    EXPECT_EQ(std::count(bad.out.begin(), bad.out.end(), '\n'), 1) << args << ": " << bad.out;
  }
}

}  // namespace
