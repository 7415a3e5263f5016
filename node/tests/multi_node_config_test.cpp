// `--node-id` with a list (issue 13) on the command line and in the config file: the ids,
// and bad input as one line (the process exits with status 2 for a UsageError).
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include "node/config.hpp"
#include "node/tests/command_line_test.hpp"

namespace stepnode::node::test {
namespace {

class MultiNodeConfigTest : public CommandLineTest {
 protected:
  MultiNodeConfigTest() { base_args = {"--iface", "vcan0"}; }
};

TEST_F(MultiNodeConfigTest, ARangeOrAListGivesEveryNode) {
  NodeConfig cfg = parse({"--node-id", "1-32"});
  ASSERT_EQ(cfg.node_ids.size(), 32u);
  EXPECT_EQ(cfg.node_ids.front(), 1);
  EXPECT_EQ(cfg.node_ids.back(), 32);
  EXPECT_EQ(cfg.options.device.node_id, 1);
  EXPECT_EQ(cfg.options.node_id_origin, NodeIdOrigin::CommandLine);
  EXPECT_EQ(parse({"--node-id", "1,5,10-12"}).node_ids, std::vector<uint8_t>({1, 5, 10, 11, 12}));
}

TEST_F(MultiNodeConfigTest, OneIdIsOneNodeAsBefore) {
  NodeConfig cfg = parse({"--node-id", "5"});
  EXPECT_TRUE(cfg.node_ids.empty());
  EXPECT_EQ(cfg.options.device.node_id, 5);
}

TEST_F(MultiNodeConfigTest, BadListsAreOneLineNamingTheArgument) {
  for (const char* bad : {"0-3", "1-128", "1-5,5", "1,none", "5-1", "1,,2", "1-"}) {
    const std::string msg = error_of({"--node-id", bad});
    EXPECT_EQ(msg.rfind(std::string("--node-id ") + bad + ": ", 0), 0u) << msg;
  }
}

TEST_F(MultiNodeConfigTest, SerialNumbersOfAllNodesMustFit) {
  EXPECT_EQ(parse({"--node-id", "1-2", "--serial-number", "4294967294"}).node_ids.size(), 2u);
  const std::string msg = error_of({"--node-id", "1-3", "--serial-number", "4294967294"});
  EXPECT_NE(msg.find("--serial-number 4294967294"), std::string::npos) << msg;
}

TEST_F(MultiNodeConfigTest, TheConfigFileMayListNodesAndTheCommandLineWins) {
  const std::string path = config("node_id = \"1-4\"\n");
  EXPECT_EQ(parse({"--config", path}).node_ids, std::vector<uint8_t>({1, 2, 3, 4}));
  EXPECT_EQ(parse({"--config", path}).options.node_id_origin, NodeIdOrigin::ConfigFile);
  NodeConfig one = parse({"--config", path, "--node-id", "9"});
  EXPECT_TRUE(one.node_ids.empty());
  EXPECT_EQ(one.options.device.node_id, 9);
  EXPECT_EQ(parse({"--config", path, "--node-id", "none"}).node_ids.size(), 4u);
  const std::string bad = config("node_id = \"1,1\"\n");
  EXPECT_THROW(parse({"--config", bad}), UsageError);
}

}  // namespace
}  // namespace stepnode::node::test
