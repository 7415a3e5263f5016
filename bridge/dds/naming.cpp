#include "bridge/dds/naming.hpp"

#include <stdexcept>

namespace stepnode::bridge::dds {

std::string_view idl_name(TopicKind kind) {
  switch (kind) {
    case TopicKind::AxisStatus: return "AxisStatus";
    case TopicKind::AxisPosition: return "AxisPosition";
    case TopicKind::NodeHealth: return "NodeHealth";
    case TopicKind::Emergency: return "Emergency";
    case TopicKind::DriveStatus: return "DriveStatus";
  }
  return "?";
}

std::string_view snake_name(TopicKind kind) {
  switch (kind) {
    case TopicKind::AxisStatus: return "axis_status";
    case TopicKind::AxisPosition: return "axis_position";
    case TopicKind::NodeHealth: return "node_health";
    case TopicKind::Emergency: return "emergency";
    case TopicKind::DriveStatus: return "drive_status";
  }
  return "?";
}

std::string type_name(TopicKind kind, const Naming& naming) {
  std::string name(idl_name(kind));
  if (naming.ros2) return "stepnode::msg::dds_::" + name + "_";
  return "stepnode::" + name;
}

std::string topic_name(TopicKind kind, const Naming& naming) {
  if (naming.ros2) return "rt/" + naming.ros2_prefix + "/" + std::string(snake_name(kind));
  return std::string(idl_name(kind));
}

std::string profile_name(TopicKind kind) { return "stepnode_" + std::string(snake_name(kind)); }

void validate_ros2_prefix(const std::string& prefix) {
  auto bad = [&](const std::string& rule) {
    throw std::invalid_argument("ROS 2 prefix \"" + prefix + "\": " + rule);
  };
  if (prefix.empty()) bad("must not be empty");
  bool segment_start = true;
  for (char c : prefix) {
    bool alpha = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_';
    bool digit = c >= '0' && c <= '9';
    if (c == '/') {
      if (segment_start) bad("empty segment (leading or doubled '/')");
      segment_start = true;
      continue;
    }
    if (!alpha && !digit)
      bad(std::string("character '") + c + "' is not allowed (A-Z a-z 0-9 _ /)");
    if (segment_start && digit) bad("a segment must not start with a digit");
    segment_start = false;
  }
  if (segment_start) bad("must not end with '/'");
}

}  // namespace stepnode::bridge::dds
