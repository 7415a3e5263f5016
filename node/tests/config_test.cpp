// The node's command line and TOML config: bad input is a UsageError with one line that
// names the input; the [defaults] table sets object defaults.
#include "node/config.hpp"
#include "node/device.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include "node/tests/command_line_test.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

class ConfigTest : public CommandLineTest {};

TEST_F(ConfigTest, GoodCommandLine) {
  NodeConfig cfg = parse({"--iface", "vcan0", "--node-id", "5", "--state-dir", dir.path.string()});
  EXPECT_EQ(cfg.iface, "vcan0");
  EXPECT_EQ(cfg.options.device.node_id, 5);
  EXPECT_EQ(cfg.options.state_dir, dir.path);
  EXPECT_FALSE(exit_now);
  cfg = parse({"--iface", "can1", "--node-id", "127"});
  EXPECT_EQ(cfg.options.device.node_id, 127);
  cfg = parse({"--iface", "can1", "--node-id", "1"});
  EXPECT_EQ(cfg.options.device.node_id, 1);
}

TEST_F(ConfigTest, NodeIdOutOfRange) {
  for (const char* id : {"0", "128", "254", "-1", "1000", "5x"}) {
    std::string msg = error_of({"--iface", "vcan0", "--node-id", id});
    EXPECT_TRUE(has(msg, "--node-id")) << msg;
    EXPECT_TRUE(has(msg, id)) << msg;
  }
}

TEST_F(ConfigTest, NodeIdNoneStartsAnLssUnconfiguredNode) {
  // "none" or 255 (CiA 305's invalid node-ID): the node waits for an LSS master.
  for (const char* id : {"none", "255"}) {
    NodeConfig cfg = parse({"--iface", "vcan0", "--node-id", id});
    EXPECT_EQ(cfg.options.device.node_id, 0xFF) << id;
    EXPECT_EQ(cfg.options.node_id_origin, NodeIdOrigin::None) << id;
  }
  NodeConfig cfg = parse({"--iface", "vcan0", "--node-id", "5"});
  EXPECT_EQ(cfg.options.node_id_origin, NodeIdOrigin::CommandLine);
  // The config file's id applies when the command line gives none (an LSS-stored one
  // would come before it: the node decides that when it starts).
  std::string path = config("node_id = 9\n");
  cfg = parse({"--iface", "vcan0", "--node-id", "none", "--config", path});
  EXPECT_EQ(cfg.options.device.node_id, 9);
  EXPECT_EQ(cfg.options.node_id_origin, NodeIdOrigin::ConfigFile);
  cfg = parse({"--iface", "vcan0", "--config", path});
  EXPECT_EQ(cfg.options.node_id_origin, NodeIdOrigin::ConfigFile);
  cfg = parse({"--iface", "vcan0", "--node-id", "7", "--config", path});
  EXPECT_EQ(cfg.options.device.node_id, 7);
  EXPECT_EQ(cfg.options.node_id_origin, NodeIdOrigin::CommandLine);
  for (const char* none : {"node_id = \"none\"\n", "node_id = 255\n"}) {
    cfg = parse({"--iface", "vcan0", "--config", config(none)});
    EXPECT_EQ(cfg.options.device.node_id, 0xFF) << none;
    EXPECT_EQ(cfg.options.node_id_origin, NodeIdOrigin::None) << none;
  }
}

TEST_F(ConfigTest, SerialNumberFromTheCommandLineOrTheFile) {
  EXPECT_EQ(parse({"--iface", "vcan0", "--node-id", "5", "--serial-number", "7"})
                .options.device.serial_number,
            7u);
  EXPECT_EQ(parse({"--iface", "vcan0", "--node-id", "5", "--serial-number", "0x1A2B"})
                .options.device.serial_number,
            0x1A2Bu);
  EXPECT_EQ(parse({"--iface", "vcan0", "--node-id", "5", "--serial-number", "4294967295"})
                .options.device.serial_number,
            0xFFFFFFFFu);
  std::string path = config("serial_number = 12\n");
  EXPECT_EQ(
      parse({"--iface", "vcan0", "--node-id", "5", "--config", path}).options.device.serial_number,
      12u);
  EXPECT_EQ(parse({"--iface", "vcan0", "--node-id", "5", "--config", path, "--serial-number", "13"})
                .options.device.serial_number,
            13u);
  for (const char* bad : {"-1", "4294967296", "x", "12abc", ""}) {
    std::string msg = error_of({"--iface", "vcan0", "--node-id", "5", "--serial-number", bad});
    EXPECT_TRUE(has(msg, "--serial-number")) << bad << " -> " << msg;
  }
}

TEST_F(ConfigTest, BootListenFromTheCommandLineOrTheFile) {
  EXPECT_EQ(parse({"--iface", "vcan0", "--node-id", "5"}).options.boot_listen_us, 0u);
  EXPECT_EQ(parse({"--iface", "vcan0", "--node-id", "5", "--boot-listen-ms", "1500"})
                .options.boot_listen_us,
            1'500'000u);
  std::string path = config("boot_listen_ms = 250\n");
  EXPECT_EQ(parse({"--iface", "vcan0", "--node-id", "5", "--config", path}).options.boot_listen_us,
            250'000u);
  EXPECT_EQ(parse({"--iface", "vcan0", "--node-id", "5", "--config", path, "--boot-listen-ms", "0"})
                .options.boot_listen_us,
            0u);
  for (const char* bad : {"-1", "60001", "x"}) {
    std::string msg = error_of({"--iface", "vcan0", "--node-id", "5", "--boot-listen-ms", bad});
    EXPECT_TRUE(has(msg, "--boot-listen-ms")) << bad << " -> " << msg;
  }
  std::string msg =
      error_of({"--iface", "vcan0", "--node-id", "5", "--config", config("boot_listen_ms = -5\n")});
  EXPECT_TRUE(has(msg, "boot_listen_ms")) << msg;
}

TEST_F(ConfigTest, ApplyBitTimingFromTheCommandLineOrTheFile) {
  EXPECT_FALSE(parse({"--iface", "vcan0", "--node-id", "5"}).apply_bit_timing);
  EXPECT_TRUE(parse({"--iface", "vcan0", "--node-id", "5", "--apply-bit-timing"}).apply_bit_timing);
  EXPECT_TRUE(
      parse({"--iface", "vcan0", "--node-id", "5", "--config", config("apply_bit_timing = true\n")})
          .apply_bit_timing);
  // The command line wins over the file.
  EXPECT_TRUE(parse({"--iface", "vcan0", "--node-id", "5", "--config",
                     config("apply_bit_timing = false\n"), "--apply-bit-timing"})
                  .apply_bit_timing);
  std::string msg = error_of(
      {"--iface", "vcan0", "--node-id", "5", "--config", config("apply_bit_timing = 3\n")});
  EXPECT_TRUE(has(msg, "apply_bit_timing")) << msg;
}

TEST_F(ConfigTest, NodeIdNotANumber) {
  std::string msg = error_of({"--iface", "vcan0", "--node-id", "five"});
  EXPECT_TRUE(has(msg, "five") || has(msg, "node-id")) << msg;
}

TEST_F(ConfigTest, MissingIfaceOrNodeId) {
  EXPECT_TRUE(has(error_of({"--node-id", "5"}), "--iface"));
  EXPECT_TRUE(has(error_of({"--iface", "vcan0"}), "--node-id"));
  EXPECT_TRUE(has(error_of({}), "--iface"));
}

TEST_F(ConfigTest, UnknownOptionAndBadValues) {
  std::string msg = error_of({"--iface", "vcan0", "--node-id", "5", "--bogus"});
  EXPECT_TRUE(has(msg, "--bogus")) << msg;
  msg = error_of({"--iface", "vcan0", "--node-id", "5", "--tick-us", "50"});
  EXPECT_TRUE(has(msg, "--tick-us")) << msg;
  msg = error_of({"--iface", "vcan0", "--node-id", "5", "--log-level", "loud"});
  EXPECT_TRUE(has(msg, "loud")) << msg;
}

TEST_F(ConfigTest, UnreadableConfigFile) {
  std::string missing = (dir.path / "nope.toml").string();
  std::string msg = error_of({"--iface", "vcan0", "--node-id", "5", "--config", missing});
  EXPECT_TRUE(has(msg, missing)) << msg;
  // A directory is no config file either.
  msg = error_of({"--iface", "vcan0", "--node-id", "5", "--config", dir.path.string()});
  EXPECT_TRUE(has(msg, dir.path.string())) << msg;
}

TEST_F(ConfigTest, BadTomlNamesTheFileAndLine) {
  std::string path = config("iface = \"vcan0\"\nnode_id = [\n");
  std::string msg = error_of({"--config", path});
  EXPECT_TRUE(has(msg, path)) << msg;
  EXPECT_TRUE(has(msg, "line")) << msg;
  path = config("this is not toml\n");
  msg = error_of({"--iface", "vcan0", "--node-id", "5", "--config", path});
  EXPECT_TRUE(has(msg, path)) << msg;
}

TEST_F(ConfigTest, BadValuesInTheFileNameTheKey) {
  struct {
    const char* text;
    const char* key;
  } cases[] = {
      {"node_id = 0\n", "node_id"},     {"node_id = 128\n", "node_id"},
      {"node_id = \"5\"\n", "node_id"}, {"iface = 5\n", "iface"},
      {"tick_us = 1\n", "tick_us"},     {"axes = 9\n", "axes"},
      {"state_dir = 1\n", "state_dir"}, {"[defaults]\n\"1017\" = [1]\n", "1017"},
  };
  for (const auto& c : cases) {
    std::string path = config(c.text);
    std::string msg = error_of({"--iface", "vcan0", "--node-id", "5", "--config", path});
    EXPECT_TRUE(has(msg, path)) << c.text << " -> " << msg;
    EXPECT_TRUE(has(msg, c.key)) << c.text << " -> " << msg;
  }
}

TEST_F(ConfigTest, FileValuesAndCommandLineWins) {
  std::string path =
      config("iface = \"can0\"\nnode_id = 9\naxes = 2\ntick_us = 500\nstate_dir = \"/tmp/x\"\n");
  NodeConfig cfg = parse({"--config", path});
  EXPECT_EQ(cfg.iface, "can0");
  EXPECT_EQ(cfg.options.device.node_id, 9);
  EXPECT_EQ(cfg.options.layout.axes, 2u);
  EXPECT_EQ(cfg.tick_us, 500u);
  EXPECT_EQ(cfg.options.state_dir, "/tmp/x");
  cfg = parse({"--config", path, "--iface", "vcan3", "--node-id", "7"});
  EXPECT_EQ(cfg.iface, "vcan3");
  EXPECT_EQ(cfg.options.device.node_id, 7);
}

TEST_F(ConfigTest, HelpExitsAtOnceWithStatusZero) {
  parse({"--help"});
  EXPECT_TRUE(exit_now);
  EXPECT_EQ(exit_code, 0);
}

TEST_F(ConfigTest, DefaultsTableSetsObjectDefaults) {
  std::string path =
      config("node_id = 5\n[defaults]\n\"1017\" = 250\n\"1016:1\" = 0x00200064\n\"2F00:2\" = 7\n");
  NodeConfig cfg = parse({"--iface", "vcan0", "--config", path});
  ASSERT_EQ(cfg.object_defaults.size(), 3u);
  cfg.options.layout.axes = 1;
  cfg.options.state_dir = dir.path;
  std::vector<CanFrame> sent;
  Device device(cfg.options, cfg.object_defaults, [&](const CanFrame& f) { sent.push_back(f); });
  CanopenNode& node = device.canopen();
  node.start(0);
  EXPECT_EQ(node.dictionary().get<uint16_t>(0x1017, 0), 250);
  EXPECT_EQ(node.dictionary().get<uint32_t>(0x1016, 1), 0x00200064u);
  EXPECT_EQ(node.dictionary().get<uint32_t>(0x2F00, 2), 7u);
  // They are the defaults: changes are undone by a reset to them.
  node.dictionary().put<uint16_t>(0x1017, 0, 1000);
  node.dictionary().put<uint32_t>(0x2F00, 2, 1);
  node.on_frame(CanFrame(0, {0x81, 5}), 1000);
  EXPECT_EQ(node.dictionary().get<uint16_t>(0x1017, 0), 250);
  EXPECT_EQ(node.dictionary().get<uint32_t>(0x2F00, 2), 7u);
  // The heartbeat runs with the configured period.
  sent.clear();
  for (uint64_t t = 1000; t <= 1'001'000; t += 1000) node.on_tick(t);
  size_t hb = 0;
  for (const auto& f : sent) hb += f.id == 0x705;
  EXPECT_EQ(hb, 4u);
}

TEST_F(ConfigTest, BadDefaultsNameTheObject) {
  od::Dictionary d;
  build_device_objects(d, od::DeviceInfo{}, DeviceLayout{.axes = 1});
  auto error_of_defaults = [&](std::string key, std::string value) {
    try {
      apply_object_defaults(d, {{key, value}});
    } catch (const UsageError& e) {
      std::string msg = e.what();
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
      return msg;
    }
    ADD_FAILURE() << key << " = " << value << " accepted";
    return std::string();
  };
  EXPECT_TRUE(has(error_of_defaults("7777", "1"), "7777"));      // no such object
  EXPECT_TRUE(has(error_of_defaults("1000", "1"), "1000"));      // read-only
  EXPECT_TRUE(has(error_of_defaults("1017", "70000"), "1017"));  // does not fit U16
  EXPECT_TRUE(has(error_of_defaults("1017", "abc"), "1017"));
  EXPECT_TRUE(has(error_of_defaults("zz", "1"), "zz"));
  EXPECT_TRUE(has(error_of_defaults("1017:1:2", "1"), "1017:1:2"));
  EXPECT_EQ(d.get<uint16_t>(0x1017, 0), 1000);  // nothing half-applied
}

}  // namespace
}  // namespace stepnode::node::test
