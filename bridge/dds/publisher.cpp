#include "bridge/dds/publisher.hpp"

#include <spdlog/spdlog.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/topic/Topic.hpp>

#include <chrono>
#include <ctime>
#include <stdexcept>

#include "bridge/dds/convert.hpp"
#include "bridge/dds/qos.hpp"
#include "bridge/dds/types.hpp"

namespace stepnode::bridge::dds {
namespace efd = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

namespace {

// An axis instance in the sets of written instances: node << 8 | axis, so a node's
// instances are one range of the set.
uint16_t instance_key(uint8_t node, uint8_t axis) {
  return static_cast<uint16_t>(node << 8 | axis);
}

}  // namespace

uint64_t realtime_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<uint64_t>(ts.tv_nsec);
}

DdsPublisher::DdsPublisher(const PublisherOptions& options)
    : naming_(options.naming), domain_(options.participant.domain) {
  if (naming_.ros2) validate_ros2_prefix(naming_.ros2_prefix);
  participant_ = create_participant(options.participant);
  try {
    publisher_ = participant_->create_publisher(efd::PUBLISHER_QOS_DEFAULT);
    if (!publisher_) throw std::runtime_error("Fast DDS could not create a publisher");
    for (TopicKind kind : kAllTopics) {
      size_t i = static_cast<size_t>(kind);
      std::string type = type_name(kind, naming_);
      efd::TypeSupport support = make_type_support(kind, naming_);
      if (support.register_type(participant_, type) != ReturnCode_t::RETCODE_OK)
        throw std::runtime_error("type " + type + ": registration refused");
      std::string topic = topic_name(kind, naming_);
      topics_[i] = participant_->create_topic(topic, type, efd::TOPIC_QOS_DEFAULT);
      if (!topics_[i])
        throw std::runtime_error("topic " + topic + ": Fast DDS could not create it");
      bool from_profile = false;
      efd::DataWriterQos qos = writer_qos(kind, naming_.ros2, *publisher_, &from_profile);
      writers_[i] = publisher_->create_datawriter(topics_[i], qos);
      if (!writers_[i])
        throw std::runtime_error("topic " + topic + ": Fast DDS refused the writer QoS");
      spdlog::debug("DDS writer {} type {} ({} QoS)", topic, type,
                    from_profile ? "XML profile " + profile_name(kind) : "built-in");
    }
  } catch (...) {
    delete_participant(participant_);
    throw;
  }
  spdlog::info(
      "DDS domain {}: topics {} / {} / {} / {} / {}{}", domain_,
      topic_name(TopicKind::AxisStatus, naming_), topic_name(TopicKind::AxisPosition, naming_),
      topic_name(TopicKind::NodeHealth, naming_), topic_name(TopicKind::Emergency, naming_),
      topic_name(TopicKind::DriveStatus, naming_), naming_.ros2 ? " (ROS 2 naming, unkeyed)" : "");
}

DdsPublisher::~DdsPublisher() { delete_participant(participant_); }

bool DdsPublisher::write(TopicKind kind, void* data) {
  ReturnCode_t rc = writer(kind)->write(data, efd::HANDLE_NIL);  // write(void*) alone returns bool
  if (rc == ReturnCode_t::RETCODE_OK) {
    ++written_;
    return true;
  }
  // Logged at the 1st, 2nd, 4th, 8th ... failure so an overload cannot flood the log.
  ++write_failures_;
  if ((write_failures_ & (write_failures_ - 1)) == 0)
    spdlog::warn("DDS write on {} failed (code {}), {} failures so far", topic_name(kind, naming_),
                 rc(), write_failures_);
  return false;
}

void DdsPublisher::axis_status(const AxisStatusSample& sample) {
  ::stepnode::AxisStatus data = to_idl(sample);
  if (write(TopicKind::AxisStatus, &data))
    status_instances_.insert(instance_key(sample.node, sample.axis));
}

void DdsPublisher::axis_position(const AxisPositionSample& sample) {
  AxisPositionSample stamped = sample;
  stamped.publish_time_ns = realtime_ns();
  ::stepnode::AxisPosition data = to_idl(stamped);
  if (write(TopicKind::AxisPosition, &data))
    position_instances_.insert(instance_key(sample.node, sample.axis));
}

void DdsPublisher::node_health(const NodeHealthSample& sample) {
  ::stepnode::NodeHealth data = to_idl(sample);
  write(TopicKind::NodeHealth, &data);
}

void DdsPublisher::emergency(const EmergencySample& sample) {
  ::stepnode::Emergency data = to_idl(sample);
  write(TopicKind::Emergency, &data);
}

void DdsPublisher::drive_status(const DriveStatusSample& sample) {
  DriveStatusSample stamped = sample;
  stamped.publish_time_ns = realtime_ns();
  ::stepnode::DriveStatus data = to_idl(stamped);
  if (write(TopicKind::DriveStatus, &data))
    drive_instances_.insert(instance_key(sample.node, sample.axis));
}

void DdsPublisher::dispose_axes(uint8_t node, uint8_t axes) {
  if (naming_.ros2) return;  // unkeyed: no instances to dispose
  // `key` is a sample of the topic's type; only its key fields (node, axis) are set.
  auto dispose = [&](TopicKind kind, std::set<uint16_t>& instances, auto key) {
    key.node(node);
    for (auto it = instances.lower_bound(instance_key(node, 0));
         it != instances.end() && (*it >> 8) == node;) {
      key.axis(static_cast<uint8_t>(*it & 0xFF));
      ReturnCode_t rc = writer(kind)->dispose(&key, efd::HANDLE_NIL);
      if (rc != ReturnCode_t::RETCODE_OK)
        spdlog::warn("DDS dispose of node {} axis {} on {} failed (code {})", node, *it & 0xFF,
                     topic_name(kind, naming_), rc());
      it = instances.erase(it);
    }
  };
  dispose(TopicKind::AxisStatus, status_instances_, ::stepnode::AxisStatus{});
  dispose(TopicKind::AxisPosition, position_instances_, ::stepnode::AxisPosition{});
  dispose(TopicKind::DriveStatus, drive_instances_, ::stepnode::DriveStatus{});
  spdlog::debug("DDS: node {} ({} axes) disposed", node, axes);
}

void DdsPublisher::wait_acknowledged(uint32_t timeout_ms) {
  // One deadline for all writers, not one timeout each.
  auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  for (auto* w : writers_) {
    if (!w) continue;
    auto left = std::chrono::duration_cast<std::chrono::nanoseconds>(
                    deadline - std::chrono::steady_clock::now())
                    .count();
    if (left <= 0) break;
    w->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(
        static_cast<int32_t>(left / 1'000'000'000), static_cast<uint32_t>(left % 1'000'000'000)));
  }
}

int DdsPublisher::matched_readers(TopicKind kind) const {
  efd::PublicationMatchedStatus status;
  writer(kind)->get_publication_matched_status(status);
  return status.current_count;
}

}  // namespace stepnode::bridge::dds
