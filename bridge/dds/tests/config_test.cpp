// stepbridge's command line and TOML config: the command line wins, bad input is one line.
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

BridgeConfig parse(std::vector<std::string> args) {
  return test::parse_command_line(std::move(args));
}

std::string write_file(const std::string& name, const std::string& text) {
  auto path = std::filesystem::temp_directory_path() / (name + "-" + std::to_string(getpid()));
  std::ofstream(path) << text;
  return path.string();
}

std::string error_of(std::vector<std::string> args) {
  try {
    parse(std::move(args));
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

TEST(BridgeConfig, Defaults) {
  auto cfg = parse({"--iface", "vcan0"});
  EXPECT_EQ(cfg.iface, "vcan0");
  EXPECT_EQ(cfg.domain, 0u);
  EXPECT_FALSE(cfg.ros2);
  EXPECT_EQ(cfg.ros2_prefix, "stepnode");
  EXPECT_EQ(cfg.profiles, "");
  EXPECT_EQ(cfg.log_level, "info");
  EXPECT_EQ(cfg.tick_ms, 10u);
}

TEST(BridgeConfig, Options) {
  auto cfg = parse({"--iface", "can1", "--domain", "42", "--ros2", "--ros2-prefix", "line/a",
                    "--log-level", "debug"});
  EXPECT_EQ(cfg.iface, "can1");
  EXPECT_EQ(cfg.domain, 42u);
  EXPECT_TRUE(cfg.ros2);
  EXPECT_EQ(cfg.ros2_prefix, "line/a");
  EXPECT_EQ(cfg.log_level, "debug");
}

TEST(BridgeConfig, FileKeysAndTheCommandLineWins) {
  auto file = write_file(
      "bridge.toml",
      "iface = \"can0\"\ndomain = 7\nros2 = true\nros2_prefix = \"cell\"\n"
      "log_level = \"warn\"\ntick_ms = 5\nheartbeat_timeout_ms = 2500\nsdo_timeout_ms = 800\n");
  auto cfg = parse({"--config", file, "--domain", "9"});
  EXPECT_EQ(cfg.iface, "can0");
  EXPECT_EQ(cfg.domain, 9u);
  EXPECT_TRUE(cfg.ros2);
  EXPECT_EQ(cfg.ros2_prefix, "cell");
  EXPECT_EQ(cfg.log_level, "warn");
  EXPECT_EQ(cfg.tick_ms, 5u);
  EXPECT_EQ(cfg.heartbeat_timeout_ms, 2500u);
  EXPECT_EQ(cfg.sdo_timeout_ms, 800u);
  std::filesystem::remove(file);
}

TEST(BridgeConfig, BadInputIsOneLineNamingTheProblem) {
  EXPECT_EQ(error_of({}), "no CAN interface: give --iface IFACE (or iface in the config file)");
  EXPECT_EQ(error_of({"--iface", "vcan0", "--domain", "233"}), "domain 233: must be 0..232");
  EXPECT_EQ(error_of({"--iface", "vcan0", "--ros2-prefix", "x"}), "--ros2-prefix needs --ros2");
  EXPECT_EQ(error_of({"--iface", "vcan0", "--profiles", "/nonexistent.xml"}),
            "profiles /nonexistent.xml: cannot read file");
  EXPECT_EQ(error_of({"--iface", "vcan0", "--log-level", "loud"}),
            "log level \"loud\": must be trace, debug, info, warn, error, critical or off");
  EXPECT_NE(error_of({"--iface", "vcan0", "--bogus"}), "");
  EXPECT_EQ(error_of({"--config", "/nonexistent.toml"}),
            "config /nonexistent.toml: cannot read file");
  auto file = write_file("bad.toml", "iface = \"can0\"\ndomain = \"one\"\n");
  EXPECT_EQ(error_of({"--config", file}), "config " + file + ": domain: must be an integer 0..232");
  auto unknown = write_file("unknown.toml", "iface = \"can0\"\nnode_id = 3\n");
  EXPECT_EQ(error_of({"--config", unknown}), "config " + unknown + ": node_id: unknown key");
  auto zero = write_file("zero.toml", "iface = \"can0\"\nsdo_timeout_ms = 0\n");
  EXPECT_EQ(error_of({"--config", zero}),
            "config " + zero + ": sdo_timeout_ms: must be an integer 10..60000");
  std::filesystem::remove(file);
  std::filesystem::remove(unknown);
  std::filesystem::remove(zero);
}

TEST(BridgeConfig, SdoChannelsFromTheCommandLineAndTheFile) {
  auto cfg = parse(
      {"--iface", "vcan0", "--sdo-channel", "5:0x685,0x6C5", "--sdo-channel", "6:0x686,1734"});
  ASSERT_EQ(cfg.sdo_channels.size(), 2u);
  EXPECT_EQ(cfg.sdo_channels[0].node, 5);
  EXPECT_EQ(cfg.sdo_channels[0].client_to_server, 0x685u);
  EXPECT_EQ(cfg.sdo_channels[0].server_to_client, 0x6C5u);
  EXPECT_EQ(cfg.sdo_channels[1].server_to_client, 1734u);
  auto file = write_file("channels.toml", "iface = \"can0\"\n[sdo_channels]\n5 = [0x685, 0x6C5]\n");
  cfg = parse({"--config", file});
  ASSERT_EQ(cfg.sdo_channels.size(), 1u);
  EXPECT_EQ(cfg.sdo_channels[0].node, 5);
  EXPECT_EQ(cfg.sdo_channels[0].server_to_client, 0x6C5u);
  EXPECT_EQ(parse({"--config", file, "--sdo-channel", "7:0x687,0x6C7"}).sdo_channels.at(0).node, 7)
      << "the command line wins";
  std::filesystem::remove(file);
}

TEST(BridgeConfig, BadSdoChannelsAreOneLine) {
  EXPECT_EQ(error_of({"--iface", "vcan0", "--sdo-channel", "5"}),
            "--sdo-channel 5: give NODE:CLIENT_TO_SERVER,SERVER_TO_CLIENT (e.g. 5:0x685,0x6C5)");
  EXPECT_EQ(error_of({"--iface", "vcan0", "--sdo-channel", "0:0x685,0x6C5"}),
            "--sdo-channel 0:0x685,0x6C5: node must be 1..127");
  EXPECT_EQ(error_of({"--iface", "vcan0", "--sdo-channel", "5:0x685,0x800"}),
            "--sdo-channel 5:0x685,0x800: '0x800' is not an 11-bit CAN-ID (1..0x7FF)");
  EXPECT_EQ(error_of({"--iface", "vcan0", "--sdo-channel", "5:0x685,0x685"}),
            "--sdo-channel 5:0x685,0x685: the two COB-IDs must differ");
  auto file = write_file("badchannels.toml", "iface = \"can0\"\n[sdo_channels]\n5 = 0x685\n");
  EXPECT_EQ(error_of({"--config", file}),
            "config " + file + ": sdo_channels.5: must be [CLIENT_TO_SERVER, SERVER_TO_CLIENT]");
  std::filesystem::remove(file);
}

// Found in review: a key that is no node-ID was read by its leading digits, and two nodes
// could share a channel's CAN-ID (one node's answers then routed to the other).
TEST(BridgeConfig, SdoChannelsNeedTheirOwnCanIdsAndRealNodeIds) {
  auto file =
      write_file("keychannels.toml", "iface = \"can0\"\n[sdo_channels]\n5x = [0x685, 0x6C5]\n");
  EXPECT_EQ(error_of({"--config", file}),
            "config " + file + ": sdo_channels.5x: node must be 1..127");
  std::filesystem::remove(file);
  EXPECT_EQ(error_of({"--iface", "vcan0", "--sdo-channel", "5:0x685,0x6C5", "--sdo-channel",
                      "6:0x686,0x6C5"}),
            "--sdo-channel 6:0x686,0x6C5: 0x6C5 is node 5's channel already");
  EXPECT_EQ(error_of({"--iface", "vcan0", "--sdo-channel", "6:0x606,0x6C6"}),
            "--sdo-channel 6:0x606,0x6C6: 0x606 is a restricted CAN-ID (CiA 301 7.3.5)");
  EXPECT_EQ(error_of({"--iface", "vcan0", "--sdo-channel", "6:0x686,0x080"}),
            "--sdo-channel 6:0x686,0x080: 0x80 is the SYNC's CAN-ID");
}

}  // namespace
}  // namespace stepnode::bridge
