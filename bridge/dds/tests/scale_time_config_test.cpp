// stepbridge's keys of issues 13 and 12: the SDO pacing and the timestamps' clock.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "bridge/config.hpp"
#include "bridge/dds/tests/command_line.hpp"

namespace stepnode::bridge {
namespace {

BridgeConfig parse_args(std::vector<std::string> args) {
  return test::parse_command_line(std::move(args));
}

std::string config_file(const std::string& text) {
  auto path = std::filesystem::temp_directory_path() /
              ("bridge-scale-" + std::to_string(getpid()) + ".toml");
  std::ofstream(path) << text;
  return path.string();
}

TEST(BridgeScaleConfig, DefaultsPaceAndStampOnTheHostClock) {
  const BridgeConfig cfg = parse_args({"--iface", "vcan0"});
  EXPECT_EQ(cfg.sdo_max_outstanding, 8u);
  EXPECT_EQ(cfg.sdo_rate_per_s, 1000u);
  EXPECT_FALSE(cfg.network_time);
}

TEST(BridgeScaleConfig, FileKeysAndTheOption) {
  const std::string file = config_file(
      "iface = \"vcan0\"\nsdo_max_outstanding = 4\nsdo_rate_per_s = 250\ntimestamps = "
      "\"network\"\n");
  BridgeConfig cfg = parse_args({"--config", file});
  EXPECT_EQ(cfg.sdo_max_outstanding, 4u);
  EXPECT_EQ(cfg.sdo_rate_per_s, 250u);
  EXPECT_TRUE(cfg.network_time);
  cfg = parse_args({"--config", file, "--timestamps", "host"});
  EXPECT_FALSE(cfg.network_time) << "the command line wins";
  EXPECT_TRUE(parse_args({"--iface", "vcan0", "--timestamps", "network"}).network_time);
  std::filesystem::remove(file);
}

TEST(BridgeScaleConfig, BadValuesAreOneLine) {
  EXPECT_THROW(parse_args({"--iface", "vcan0", "--timestamps", "gps"}), UsageError);
  const std::string file = config_file("iface = \"vcan0\"\nsdo_max_outstanding = 0\n");
  EXPECT_THROW(parse_args({"--config", file}), UsageError);
  std::filesystem::remove(file);
}

}  // namespace
}  // namespace stepnode::bridge
