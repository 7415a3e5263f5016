// Topic and type names of the bridge's five topics, plain (default) or ROS 2.
//
// Plain: topics "AxisStatus", "AxisPosition", "NodeHealth", "Emergency", "DriveStatus" with the
// IDL's own type names "stepnode::AxisStatus" ... (what fastddsgen and Cyclone's idlc generate).
//
// ROS 2 (rmw_fastrtps conventions): topic "rt/<prefix>/axis_status" ... and type
// "stepnode::msg::dds_::AxisStatus_" ..., what a ROS 2 package `stepnode` with
// msg/AxisStatus.msg would register. A mismatch in either string fails silently (no match,
// no error), so tests check them exactly. ROS 2 messages have no keys and Fast DDS never
// matches a keyed writer with an unkeyed reader (EDP compares the topic kinds), so in ROS 2
// mode the topics are unkeyed: see types.hpp.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace stepnode::bridge::dds {

enum class TopicKind : uint8_t { AxisStatus, AxisPosition, NodeHealth, Emergency, DriveStatus };
constexpr std::array<TopicKind, 5> kAllTopics{TopicKind::AxisStatus, TopicKind::AxisPosition,
                                              TopicKind::NodeHealth, TopicKind::Emergency,
                                              TopicKind::DriveStatus};
constexpr std::size_t kTopicCount = kAllTopics.size();

struct Naming {
  bool ros2 = false;
  std::string ros2_prefix = "stepnode";  // topics rt/<prefix>/<snake_name>; may contain '/'
};

// "AxisStatus" (the IDL struct name).
std::string_view idl_name(TopicKind kind);
// "axis_status" (ROS 2 topic style).
std::string_view snake_name(TopicKind kind);
std::string type_name(TopicKind kind, const Naming& naming);
std::string topic_name(TopicKind kind, const Naming& naming);
// Name of the XML profile (data_writer and data_reader) that overrides the built-in QoS of
// a topic: "stepnode_axis_status", ...
std::string profile_name(TopicKind kind);

// Throws std::invalid_argument naming the rule when `prefix` is not a valid ROS 2 name
// part: [A-Za-z_][A-Za-z0-9_]* segments separated by single '/', no leading/trailing '/'.
void validate_ros2_prefix(const std::string& prefix);

}  // namespace stepnode::bridge::dds
