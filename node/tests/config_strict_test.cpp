// The config file and command line refuse what they cannot honour (found in review): an
// unknown key, a setting another one overrides, a [defaults] value an SDO write refuses;
// and they keep what was given: the command line over the file, an explicit state
// directory, a REAL64 default to its last digit.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <string>
#include <vector>

#include "node/config.hpp"
#include "node/device.hpp"
#include "node/device_objects.hpp"
#include "node/profiles/hp44714a/objects.hpp"
#include "node/tests/command_line_test.hpp"

namespace stepnode::node::test {
namespace {

class ConfigStrict : public CommandLineTest {};

TEST_F(ConfigStrict, AnUnknownKeyIsNamed) {
  for (const char* text : {"nodeid = 7\n", "tick_usec = 500\n", "[defualts]\n\"1017\" = 250\n"}) {
    const std::string path = config(text);
    const std::string msg = error_of({"--iface", "vcan0", "--node-id", "5", "--config", path});
    EXPECT_TRUE(has(msg, "unknown key")) << text << " -> " << msg;
    EXPECT_TRUE(has(msg, path)) << msg;
  }
}

TEST_F(ConfigStrict, TheCommandLinesTickAndLogLevelWinOverTheFile) {
  const std::string path = config("tick_us = 500\nlog_level = \"debug\"\n");
  NodeConfig cfg = parse({"--iface", "vcan0", "--node-id", "5", "--config", path, "--tick-us",
                          "2000", "--log-level", "warn"});
  EXPECT_EQ(cfg.tick_us, 2000u);
  EXPECT_EQ(cfg.log_level, "warn");
  cfg = parse({"--iface", "vcan0", "--node-id", "5", "--config", path});
  EXPECT_EQ(cfg.tick_us, 500u);
  EXPECT_EQ(cfg.log_level, "debug");
}

TEST_F(ConfigStrict, ANegativeTickIsShownAsGiven) {
  EXPECT_EQ(error_of({"--iface", "vcan0", "--node-id", "5", "--tick-us", "-5"}),
            "--tick-us -5: must be 100..10000000");
}

// "." given is the current directory; only a state directory not given at all is the
// default ($STATE_DIRECTORY, ...).
TEST_F(ConfigStrict, AStateDirectoryDotGivenIsKept) {
  ::setenv("STATE_DIRECTORY", "/tmp/some-other-state-dir", 1);
  NodeConfig cfg = parse({"--iface", "vcan0", "--node-id", "5", "--state-dir", "."});
  EXPECT_EQ(cfg.options.state_dir, ".");
  cfg = parse({"--iface", "vcan0", "--node-id", "5", "--config", config("state_dir = \".\"\n")});
  EXPECT_EQ(cfg.options.state_dir, ".");
  cfg = parse({"--iface", "vcan0", "--node-id", "5"});
  EXPECT_EQ(cfg.options.state_dir, "/tmp/some-other-state-dir");
  ::unsetenv("STATE_DIRECTORY");
}

TEST_F(ConfigStrict, ThreeAxesWithTheMultiplexedSpm30AreAConflict) {
  const std::string path = config("axes = 3\nspm30_multiplexed = true\n");
  const std::string msg = error_of({"--iface", "vcan0", "--node-id", "5", "--config", path});
  EXPECT_TRUE(has(msg, "axes")) << msg;
  EXPECT_TRUE(has(msg, "spm30_multiplexed")) << msg;
  const NodeConfig cfg = parse(
      {"--iface", "vcan0", "--node-id", "5", "--config", config("spm30_multiplexed = true\n")});
  EXPECT_EQ(cfg.options.layout.axes, 1u);
}

// HP PSCALE (REAL64): 2.5e-6 was 3e-6 (six decimals), 1e-7 was 0.
TEST_F(ConfigStrict, ARealDefaultKeepsEveryDigit) {
  const std::string path =
      config("node_id = 5\naxes = 2\n[defaults]\n\"2011\" = 2.5e-6\n\"2111\" = 1e-7\n");
  NodeConfig cfg = parse({"--iface", "vcan0", "--config", path, "--state-dir", dir.path});
  Device device(cfg.options, cfg.object_defaults, [](const CanFrame&) {});
  device.start(0);
  od::Dictionary& d = device.canopen().dictionary();
  using namespace hp44714a::obj;
  EXPECT_EQ(d.get<double>(index(0, kPscale), 0), 2.5e-6);
  EXPECT_EQ(d.get<double>(index(1, kPscale), 0), 1e-7);
}

void build(od::Dictionary& d) {
  build_device_objects(d, od::DeviceInfo{}, DeviceLayout{.axes = 1});
}

bool refused(const std::string& key, const std::string& value) {
  od::Dictionary d;
  build(d);
  try {
    apply_object_defaults(d, {{key, value}});
  } catch (const UsageError&) {
    return true;
  }
  return false;
}

// "Checked as the dictionary checks an SDO write" (README): the objects' own rules too.
TEST(ObjectDefaults, ValuesAnSdoWriteRefusesAreRefused) {
  EXPECT_TRUE(refused("1F80", "1"));           // NMT master: not this device
  EXPECT_TRUE(refused("1005", "0x40000000"));  // SYNC producer on 0x000, the NMT's CAN-ID
  EXPECT_TRUE(refused("1014", "0x00000000"));  // EMCY on 0x000
  EXPECT_TRUE(refused("1019", "1"));           // a reserved counter overflow value
  EXPECT_TRUE(refused("1800:2", "252"));       // RTR-only transmission: not supported
  EXPECT_TRUE(refused("2009:C", "3"));         // 3 counts per quadrature line
}

// What a master configuring the device at boot may write stays allowed: a COB-ID moved
// (through invalid), a TPDO's inhibit time (while the TPDO is invalid), a SYNC counter
// overflow beside a SYNC period (a state rule for a running producer).
TEST(ObjectDefaults, WhatAMasterConfiguresAtBootIsAccepted) {
  od::Dictionary d;
  build(d);
  EXPECT_NO_THROW(apply_object_defaults(d, {{"1800:1", "0x40000195"},
                                            {"1800:3", "100"},
                                            {"1014", "0x00000095"},
                                            {"1006", "10000"},
                                            {"1019", "16"}}));
  EXPECT_EQ(d.get<uint32_t>(0x1800, 1), 0x40000195u);
  EXPECT_EQ(d.get<uint16_t>(0x1800, 3), 100);
  EXPECT_EQ(d.get<uint32_t>(0x1014, 0), 0x95u);
  EXPECT_EQ(d.get<uint8_t>(0x1019, 0), 16);
}

TEST(ObjectDefaults, AKeyIsHexIndexAndSubAndNothingElse) {
  for (const char* key : {"1017x", "1017 garbage", "1017-1", " 1017", "1017:", "1017:-1", ":1",
                          "10170", "1016:100", "+1017"})
    EXPECT_TRUE(refused(key, "250")) << "'" << key << "'";
  EXPECT_FALSE(refused("1017", "250"));
  EXPECT_FALSE(refused("1016:1", "0x000101F4"));
  EXPECT_FALSE(refused("1016:01", "0x000101F4"));
}

}  // namespace
}  // namespace stepnode::node::test
