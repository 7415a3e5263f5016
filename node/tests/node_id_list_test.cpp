// `--node-id 1-32`, `1,5,10-12`: the node-IDs of the nodes of one process (issue 13), and
// what each node's options differ in (node-ID, serial number of 0x1018 sub 4).
#include "node/node_id_list.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace stepnode::node {
namespace {

using Ids = std::vector<uint8_t>;

TEST(NodeIdList, OneIdARangeAndAList) {
  EXPECT_EQ(parse_node_id_list("5"), Ids({5}));
  EXPECT_EQ(parse_node_id_list("1-4"), Ids({1, 2, 3, 4}));
  EXPECT_EQ(parse_node_id_list("1,5,10-12"), Ids({1, 5, 10, 11, 12}));
  EXPECT_EQ(parse_node_id_list("12,3"), Ids({3, 12}));  // ascending
  EXPECT_EQ(parse_node_id_list("7-7"), Ids({7}));
  EXPECT_EQ(parse_node_id_list("1-127").size(), 127u);
}

TEST(NodeIdList, BadListsSayWhatIsWrong) {
  auto reason = [](const char* text) {
    try {
      parse_node_id_list(text);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(reason("0"), "node-ID 0 is outside 1..127");
  EXPECT_EQ(reason("120-128"), "node-ID 128 is outside 1..127");
  EXPECT_EQ(reason("1-5,3"), "node-ID 3 is given twice");
  EXPECT_EQ(reason("1-5,4-8"), "node-ID 4 is given twice");
  EXPECT_EQ(reason("9-3"), "range 9-3 runs backwards");
  EXPECT_EQ(reason("1,none"), "'none' is not a node-ID (1..127)");
  EXPECT_EQ(reason("1,,2"), "'' is not a node-ID (1..127)");
  EXPECT_EQ(reason(""), "'' is not a node-ID (1..127)");
  EXPECT_EQ(reason("-1"), "'-1' is not a node-ID or a range");
  EXPECT_EQ(reason("3-"), "'3-' is not a node-ID or a range");
  EXPECT_EQ(reason("1-2-3"), "'2-3' is not a node-ID (1..127)");
  EXPECT_EQ(reason(" 1"), "' 1' is not a node-ID (1..127)");
}

TEST(NodeIdList, EachNodeGetsItsIdAndTheConfiguredSerialPlusItsIndex) {
  NodeOptions base;
  base.device.node_id = 9;
  base.device.serial_number = 0x100;
  base.layout.axes = 2;
  const auto all = options_per_node(base, {10, 20, 30});
  ASSERT_EQ(all.size(), 3u);
  for (unsigned i = 0; i < 3; ++i) {
    EXPECT_EQ(all[i].device.node_id, 10 * (i + 1));
    EXPECT_EQ(all[i].device.serial_number, 0x100 + i);
    EXPECT_EQ(all[i].layout.axes, 2u);  // the same configuration otherwise
  }
  const auto one = options_per_node(base, {});  // one node: the options as they are
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].device.node_id, 9);
  EXPECT_EQ(one[0].device.serial_number, 0x100u);
}

}  // namespace
}  // namespace stepnode::node
