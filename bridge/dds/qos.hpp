// The QoS of each topic (issue 5), built in, or from an XML profile of the same name.
//
//   topic         reliability  durability       history (per instance)
//   AxisStatus    RELIABLE     TRANSIENT_LOCAL  KEEP_LAST 1
//   AxisPosition  RELIABLE     VOLATILE         KEEP_LAST 1
//   NodeHealth    RELIABLE     TRANSIENT_LOCAL  KEEP_LAST 1
//   Emergency     RELIABLE     TRANSIENT_LOCAL  KEEP_LAST 32
//   DriveStatus   RELIABLE     TRANSIENT_LOCAL  KEEP_LAST 1
//
// Heartbeat period 500 ms (Fast DDS: 3 s), so a reader that missed the first push of
// the history (another vendor's, before it discovered the writer) catches up quickly.
// AxisPosition and DriveStatus (one sample per TPDO) have a nack suppression duration of
// 1 ms (Fast DDS: 0, which wakes the writer's event thread on every write; see qos.cpp).
// DriveStatus is TRANSIENT_LOCAL although it comes per TPDO: a late joiner must get each
// drive's state at once, as it gets each axis's AxisStatus.
// Writers never block on a slow subscriber: KEEP_LAST replaces the oldest sample instead
// of waiting, and max_blocking_time is 1 ms for the rare resource-limit case. Data-sharing
// delivery is OFF (Fast DDS 2.9 lost RELIABLE samples under overload and crashed
// subscribers with it, measured here) unless an XML profile turns it on: a data_writer /
// data_reader profile named profile_name(kind) ("stepnode_axis_status", ...) replaces the
// built-in QoS of that topic whole. In ROS 2 mode the topics are unkeyed, so the
// TRANSIENT_LOCAL histories are deeper (kRos2Depth) to keep every axis's last samples.
#pragma once
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>

#include "bridge/dds/naming.hpp"

namespace stepnode::bridge::dds {

constexpr int32_t kMaxInstances = 127 * 8;  // nodes x axes
constexpr int32_t kRos2Depth = 256;
constexpr int32_t kEmergencyDepth = 32;

// Built-in QoS (no profile): what the table above says.
eprosima::fastdds::dds::DataWriterQos builtin_writer_qos(TopicKind kind, bool ros2);
// `depth` 0: the writer's depth.
eprosima::fastdds::dds::DataReaderQos builtin_reader_qos(TopicKind kind, bool ros2,
                                                         int32_t depth = 0);

// The profile's QoS when one named profile_name(kind) is loaded, else the built-in one.
// `from_profile` tells which (logged by the callers).
eprosima::fastdds::dds::DataWriterQos writer_qos(TopicKind kind, bool ros2,
                                                 const eprosima::fastdds::dds::Publisher& publisher,
                                                 bool* from_profile = nullptr);
eprosima::fastdds::dds::DataReaderQos reader_qos(
    TopicKind kind, bool ros2, const eprosima::fastdds::dds::Subscriber& subscriber,
    int32_t depth = 0, bool* from_profile = nullptr);

}  // namespace stepnode::bridge::dds
