// The exact topic and type names: a one-character mismatch makes DDS match nothing,
// silently, so every string is spelled out here.
#include <gtest/gtest.h>

#include <stdexcept>

#include "bridge/dds/naming.hpp"

namespace stepnode::bridge::dds {
namespace {

TEST(Naming, PlainTopicsAreTheIdlStructNames) {
  Naming plain;
  EXPECT_EQ(topic_name(TopicKind::AxisStatus, plain), "AxisStatus");
  EXPECT_EQ(topic_name(TopicKind::AxisPosition, plain), "AxisPosition");
  EXPECT_EQ(topic_name(TopicKind::NodeHealth, plain), "NodeHealth");
  EXPECT_EQ(topic_name(TopicKind::Emergency, plain), "Emergency");
  EXPECT_EQ(topic_name(TopicKind::DriveStatus, plain), "DriveStatus");
}

TEST(Naming, PlainTypesAreTheIdlScopedNames) {
  Naming plain;
  EXPECT_EQ(type_name(TopicKind::AxisStatus, plain), "stepnode::AxisStatus");
  EXPECT_EQ(type_name(TopicKind::AxisPosition, plain), "stepnode::AxisPosition");
  EXPECT_EQ(type_name(TopicKind::NodeHealth, plain), "stepnode::NodeHealth");
  EXPECT_EQ(type_name(TopicKind::Emergency, plain), "stepnode::Emergency");
  EXPECT_EQ(type_name(TopicKind::DriveStatus, plain), "stepnode::DriveStatus");
}

TEST(Naming, Ros2TopicsAreRtPrefixSnakeCase) {
  Naming ros2{true, "stepnode"};
  EXPECT_EQ(topic_name(TopicKind::AxisStatus, ros2), "rt/stepnode/axis_status");
  EXPECT_EQ(topic_name(TopicKind::AxisPosition, ros2), "rt/stepnode/axis_position");
  EXPECT_EQ(topic_name(TopicKind::NodeHealth, ros2), "rt/stepnode/node_health");
  EXPECT_EQ(topic_name(TopicKind::Emergency, ros2), "rt/stepnode/emergency");
  EXPECT_EQ(topic_name(TopicKind::DriveStatus, ros2), "rt/stepnode/drive_status");
  Naming nested{true, "line2/cell_4"};
  EXPECT_EQ(topic_name(TopicKind::AxisStatus, nested), "rt/line2/cell_4/axis_status");
}

TEST(Naming, Ros2TypesAreMsgDdsUnderscore) {
  Naming ros2{true, "anything"};  // the prefix names topics, never types
  EXPECT_EQ(type_name(TopicKind::AxisStatus, ros2), "stepnode::msg::dds_::AxisStatus_");
  EXPECT_EQ(type_name(TopicKind::AxisPosition, ros2), "stepnode::msg::dds_::AxisPosition_");
  EXPECT_EQ(type_name(TopicKind::NodeHealth, ros2), "stepnode::msg::dds_::NodeHealth_");
  EXPECT_EQ(type_name(TopicKind::Emergency, ros2), "stepnode::msg::dds_::Emergency_");
  EXPECT_EQ(type_name(TopicKind::DriveStatus, ros2), "stepnode::msg::dds_::DriveStatus_");
}

TEST(Naming, ProfileNames) {
  EXPECT_EQ(profile_name(TopicKind::AxisStatus), "stepnode_axis_status");
  EXPECT_EQ(profile_name(TopicKind::AxisPosition), "stepnode_axis_position");
  EXPECT_EQ(profile_name(TopicKind::NodeHealth), "stepnode_node_health");
  EXPECT_EQ(profile_name(TopicKind::Emergency), "stepnode_emergency");
  EXPECT_EQ(profile_name(TopicKind::DriveStatus), "stepnode_drive_status");
}

TEST(Naming, Ros2PrefixRules) {
  EXPECT_NO_THROW(validate_ros2_prefix("stepnode"));
  EXPECT_NO_THROW(validate_ros2_prefix("_a/b2/c_3"));
  for (const char* bad : {"", "/stepnode", "stepnode/", "a//b", "2fast", "a/9b", "a-b", "a b", "ä"})
    EXPECT_THROW(validate_ros2_prefix(bad), std::invalid_argument) << '"' << bad << '"';
  try {
    validate_ros2_prefix("a-b");
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "ROS 2 prefix \"a-b\": character '-' is not allowed (A-Z a-z 0-9 _ /)");
  }
}

}  // namespace
}  // namespace stepnode::bridge::dds
