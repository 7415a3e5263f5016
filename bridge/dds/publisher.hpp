// The DDS side of stepbridge: a SampleSink that writes each sample to its topic.
// Single-threaded like the event loop that drives it. Writes never block (KEEP_LAST,
// 1 ms max_blocking_time); a failed write is counted and logged, never fatal.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <set>
#include <string>

#include "bridge/dds/naming.hpp"
#include "bridge/dds/participant.hpp"
#include "bridge/samples.hpp"

namespace eprosima::fastdds::dds {
class DomainParticipant;
class Publisher;
class Topic;
class DataWriter;
}  // namespace eprosima::fastdds::dds

namespace stepnode::bridge::dds {

struct PublisherOptions {
  ParticipantOptions participant;
  Naming naming;
};

class DdsPublisher final : public SampleSink {
 public:
  explicit DdsPublisher(const PublisherOptions& options);  // throws std::runtime_error
  ~DdsPublisher() override;                                // deletes the participant
  DdsPublisher(const DdsPublisher&) = delete;
  DdsPublisher& operator=(const DdsPublisher&) = delete;

  void axis_status(const AxisStatusSample& sample) override;
  void axis_position(const AxisPositionSample& sample) override;
  void node_health(const NodeHealthSample& sample) override;
  void emergency(const EmergencySample& sample) override;
  void drive_status(const DriveStatusSample& sample) override;
  // Disposes every AxisStatus, AxisPosition and DriveStatus instance this bridge wrote for `node`
  // (axes 1..axes, and any others it knows). Unkeyed ROS 2 topics have no instances:
  // nothing to dispose there, NodeHealth says LOST.
  void dispose_axes(uint8_t node, uint8_t axes) override;

  // Waits up to `timeout_ms` until reliable readers acknowledged everything written
  // (used before shutdown so the last samples and disposals reach the subscribers).
  void wait_acknowledged(uint32_t timeout_ms);
  // Readers currently matched on a topic.
  int matched_readers(TopicKind kind) const;
  uint64_t written() const { return written_; }
  uint64_t write_failures() const { return write_failures_; }
  uint32_t domain() const { return domain_; }

 private:
  bool write(TopicKind kind, void* data);
  eprosima::fastdds::dds::DataWriter* writer(TopicKind kind) const {
    return writers_[static_cast<size_t>(kind)];
  }

  Naming naming_;
  uint32_t domain_ = 0;
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  std::array<eprosima::fastdds::dds::Topic*, kTopicCount> topics_{};
  std::array<eprosima::fastdds::dds::DataWriter*, kTopicCount> writers_{};
  std::set<uint16_t> status_instances_;  // node << 8 | axis, written and not disposed
  std::set<uint16_t> position_instances_;
  std::set<uint16_t> drive_instances_;
  uint64_t written_ = 0;
  uint64_t write_failures_ = 0;
};

// CLOCK_REALTIME in nanoseconds (the publish timestamp).
uint64_t realtime_ns();

}  // namespace stepnode::bridge::dds
