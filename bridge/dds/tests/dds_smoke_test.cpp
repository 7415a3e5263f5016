// In-process DDS: the bridge's publisher and a reader in two participants on a
// domain no other test uses (so parallel test runs do not hear each other). Late joiner, dispose,
// ROS 2 names, the keyed/unkeyed trap, XML profiles, and (when built) a Cyclone DDS subscriber.
#include <gtest/gtest.h>
#include <unistd.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <optional>
#include <string>
#include <thread>

#include "bridge/dds/convert.hpp"
#include "bridge/dds/participant.hpp"
#include "bridge/dds/publisher.hpp"
#include "bridge/dds/qos.hpp"
#include "bridge/dds/tests/test_domain.hpp"
#include "bridge/dds/types.hpp"

namespace stepnode::bridge::dds {
namespace {
namespace efd = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;
using Clock = std::chrono::steady_clock;

// A reader on its own participant. Polls with take(), no listener.
class TestReader {
 public:
  TestReader(uint32_t domain, TopicKind kind, const Naming& naming, bool keyed_anyway = false) {
    ParticipantOptions options;
    options.domain = domain;
    options.name = "test reader";
    participant_ = create_participant(options);
    Naming type_naming = naming;
    if (keyed_anyway) type_naming.ros2 = false;  // the generated, keyed type
    efd::TypeSupport support = make_type_support(kind, type_naming);
    std::string type = type_name(kind, naming);
    EXPECT_EQ(support.register_type(participant_, type), ReturnCode_t::RETCODE_OK);
    topic_ = participant_->create_topic(topic_name(kind, naming), type, efd::TOPIC_QOS_DEFAULT);
    subscriber_ = participant_->create_subscriber(efd::SUBSCRIBER_QOS_DEFAULT);
    reader_ = subscriber_->create_datareader(
        topic_, builtin_reader_qos(kind, naming.ros2 && !keyed_anyway, 16));
    EXPECT_NE(reader_, nullptr);
  }
  ~TestReader() { delete_participant(participant_); }

  // The next sample (or instance-state change) within `timeout`.
  template <class T>
  std::optional<T> next(std::chrono::milliseconds timeout, efd::SampleInfo* info_out = nullptr) {
    auto end = Clock::now() + timeout;
    while (Clock::now() < end) {
      T data;
      efd::SampleInfo info;
      if (reader_->take_next_sample(&data, &info) == ReturnCode_t::RETCODE_OK) {
        if (info_out) *info_out = info;
        return data;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return std::nullopt;
  }
  int matched() const {
    efd::SubscriptionMatchedStatus status;
    reader_->get_subscription_matched_status(status);
    return status.current_count;
  }

 private:
  efd::DomainParticipant* participant_ = nullptr;
  efd::Topic* topic_ = nullptr;
  efd::Subscriber* subscriber_ = nullptr;
  efd::DataReader* reader_ = nullptr;
};

AxisStatusSample status(uint8_t node, uint8_t axis, uint16_t bits) {
  AxisStatusSample s;
  s.node = node;
  s.axis = axis;
  s.status_bits = bits;
  s.can_time_ns = 1234;
  return s;
}

TEST(DdsSmoke, LateJoinerGetsTheCurrentStatusOfEveryAxisThenTheDispose) {
  uint32_t domain = test::unique_test_domain();
  PublisherOptions options;
  options.participant.domain = domain;
  DdsPublisher publisher(options);
  publisher.axis_status(status(5, 1, 0x0100));
  publisher.axis_status(status(5, 1, 0x8100));  // KEEP_LAST 1: only this one survives
  publisher.axis_status(status(5, 2, 0x1100));

  TestReader reader(domain, TopicKind::AxisStatus, Naming{});  // joins after the writes
  std::map<int, uint16_t> seen;
  for (int i = 0; i < 2; ++i) {
    auto s = reader.next<::stepnode::AxisStatus>(std::chrono::seconds(10));
    ASSERT_TRUE(s) << "sample " << i << " of the late joiner";
    seen[s->axis()] = s->status_bits();
    EXPECT_EQ(s->node(), 5);
    EXPECT_EQ(s->can_time_ns(), 1234u);
  }
  EXPECT_EQ(seen[1], 0x8100);
  EXPECT_EQ(seen[2], 0x1100);
  EXPECT_FALSE(reader.next<::stepnode::AxisStatus>(std::chrono::milliseconds(200)));

  publisher.dispose_axes(5, 2);
  int disposed = 0;
  for (int i = 0; i < 2; ++i) {
    efd::SampleInfo info;
    auto s = reader.next<::stepnode::AxisStatus>(std::chrono::seconds(5), &info);
    ASSERT_TRUE(s);
    EXPECT_FALSE(info.valid_data);
    disposed += info.instance_state == efd::NOT_ALIVE_DISPOSED_INSTANCE_STATE;
  }
  EXPECT_EQ(disposed, 2);
  EXPECT_EQ(publisher.write_failures(), 0u);
}

TEST(DdsSmoke, LateJoinerGetsEveryDrivesStateThenTheDispose) {
  uint32_t domain = test::unique_test_domain();
  PublisherOptions options;
  options.participant.domain = domain;
  DdsPublisher publisher(options);
  DriveStatusSample d;
  d.node = 5;
  d.axis = 1;
  d.statusword_known = true;
  d.statusword = 0x0250;
  publisher.drive_status(d);
  d.statusword = 0x0637;  // KEEP_LAST 1: only this one survives
  d.mode_display = 1;
  d.position_actual = 4000;
  d.can_time_ns = realtime_ns();
  publisher.drive_status(d);
  d.axis = 2;
  d.statusword = 0x0218;
  d.error_code = 0x8611;
  publisher.drive_status(d);

  TestReader reader(domain, TopicKind::DriveStatus, Naming{});  // joins after the writes
  std::map<int, ::stepnode::DriveStatus> seen;
  for (int i = 0; i < 2; ++i) {
    auto s = reader.next<::stepnode::DriveStatus>(std::chrono::seconds(10));
    ASSERT_TRUE(s) << "sample " << i << " of the late joiner";
    seen[s->axis()] = *s;
  }
  EXPECT_EQ(seen[1].state(), ::stepnode::DRIVE_OPERATION_ENABLED);
  EXPECT_EQ(seen[1].statusword(), 0x0637);
  EXPECT_EQ(seen[1].position_actual(), 4000);
  EXPECT_TRUE(seen[1].target_reached());
  EXPECT_GE(seen[1].publish_time_ns(), d.can_time_ns);
  EXPECT_EQ(seen[2].state(), ::stepnode::DRIVE_FAULT);
  EXPECT_EQ(seen[2].error_code(), 0x8611);

  publisher.dispose_axes(5, 2);
  int disposed = 0;
  for (int i = 0; i < 2; ++i) {
    efd::SampleInfo info;
    auto s = reader.next<::stepnode::DriveStatus>(std::chrono::seconds(5), &info);
    ASSERT_TRUE(s);
    EXPECT_FALSE(info.valid_data);
    disposed += info.instance_state == efd::NOT_ALIVE_DISPOSED_INSTANCE_STATE;
  }
  EXPECT_EQ(disposed, 2);
  EXPECT_EQ(publisher.write_failures(), 0u);
}

TEST(DdsSmoke, PositionCarriesPublishTimeAndMatchesAVolatileReader) {
  uint32_t domain = test::unique_test_domain();
  PublisherOptions options;
  options.participant.domain = domain;
  DdsPublisher publisher(options);
  TestReader reader(domain, TopicKind::AxisPosition, Naming{});
  auto until = Clock::now() + std::chrono::seconds(10);
  while (publisher.matched_readers(TopicKind::AxisPosition) == 0 && Clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_EQ(publisher.matched_readers(TopicKind::AxisPosition), 1);
  AxisPositionSample p;
  p.node = 7;
  p.axis = 3;
  p.motor_position = -400;
  p.velocity = 1200;
  p.can_time_ns = realtime_ns();
  publisher.axis_position(p);
  auto d = reader.next<::stepnode::AxisPosition>(std::chrono::seconds(5));
  ASSERT_TRUE(d);
  EXPECT_EQ(d->node(), 7);
  EXPECT_EQ(d->axis(), 3);
  EXPECT_EQ(d->motor_position(), -400);
  EXPECT_EQ(d->velocity(), 1200);
  EXPECT_GE(d->publish_time_ns(), p.can_time_ns);
}

TEST(DdsSmoke, Ros2NamesMatchAnUnkeyedReaderAndNotAKeyedOne) {
  uint32_t domain = test::unique_test_domain();
  Naming ros2{true, "cell4"};
  PublisherOptions options;
  options.participant.domain = domain;
  options.naming = ros2;
  DdsPublisher publisher(options);
  NodeHealthSample h;
  h.node = 3;
  h.state = NodeState::Operational;
  h.device_name = "stepnode";
  publisher.node_health(h);

  // What rmw_fastrtps registers for a ROS 2 subscriber of stepnode/msg/NodeHealth on
  // /cell4/node_health: unkeyed type "stepnode::msg::dds_::NodeHealth_", topic
  // "rt/cell4/node_health".
  TestReader ros_reader(domain, TopicKind::NodeHealth, ros2);
  auto d = ros_reader.next<::stepnode::NodeHealth>(std::chrono::seconds(10));
  ASSERT_TRUE(d);
  EXPECT_EQ(d->node(), 3);
  EXPECT_EQ(d->state(), ::stepnode::NODE_OPERATIONAL);
  EXPECT_EQ(d->device_name(), "stepnode");

  // The same names with a keyed type never match (Fast DDS compares topic kinds), which
  // is why ROS 2 mode publishes unkeyed.
  TestReader keyed(domain, TopicKind::NodeHealth, ros2, /*keyed_anyway=*/true);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  EXPECT_EQ(keyed.matched(), 0);
  EXPECT_FALSE(keyed.next<::stepnode::NodeHealth>(std::chrono::milliseconds(100)));
  EXPECT_EQ(publisher.matched_readers(TopicKind::NodeHealth), 1);
}

TEST(DdsSmoke, BadRos2PrefixIsRefused) {
  PublisherOptions options;
  options.participant.domain = test::unique_test_domain();
  options.naming = Naming{true, "bad-prefix"};
  EXPECT_THROW(DdsPublisher{options}, std::invalid_argument);
}

TEST(DdsQos, BuiltInTable) {
  auto status = builtin_writer_qos(TopicKind::AxisStatus, false);
  EXPECT_EQ(status.reliability().kind, efd::RELIABLE_RELIABILITY_QOS);
  EXPECT_EQ(status.durability().kind, efd::TRANSIENT_LOCAL_DURABILITY_QOS);
  EXPECT_EQ(status.history().kind, efd::KEEP_LAST_HISTORY_QOS);
  EXPECT_EQ(status.history().depth, 1);
  EXPECT_EQ(status.resource_limits().max_instances, kMaxInstances);
  EXPECT_EQ(status.data_sharing().kind(), efd::OFF);
  auto position = builtin_writer_qos(TopicKind::AxisPosition, false);
  EXPECT_EQ(position.reliability().kind, efd::RELIABLE_RELIABILITY_QOS);
  EXPECT_EQ(position.durability().kind, efd::VOLATILE_DURABILITY_QOS);
  EXPECT_EQ(position.history().depth, 1);
  EXPECT_EQ(position.data_sharing().kind(), efd::OFF);
  auto health = builtin_writer_qos(TopicKind::NodeHealth, false);
  EXPECT_EQ(health.durability().kind, efd::TRANSIENT_LOCAL_DURABILITY_QOS);
  EXPECT_EQ(health.history().depth, 1);
  auto emcy = builtin_writer_qos(TopicKind::Emergency, false);
  EXPECT_EQ(emcy.reliability().kind, efd::RELIABLE_RELIABILITY_QOS);
  EXPECT_EQ(emcy.history().depth, kEmergencyDepth);
  auto drive = builtin_writer_qos(TopicKind::DriveStatus, false);
  EXPECT_EQ(drive.reliability().kind, efd::RELIABLE_RELIABILITY_QOS);
  EXPECT_EQ(drive.durability().kind, efd::TRANSIENT_LOCAL_DURABILITY_QOS);
  EXPECT_EQ(drive.history().depth, 1);
  EXPECT_EQ(drive.resource_limits().max_instances, kMaxInstances);
  EXPECT_EQ(drive.data_sharing().kind(), efd::OFF);
  EXPECT_EQ(drive.reliable_writer_qos().times.nackSupressionDuration,
            position.reliable_writer_qos().times.nackSupressionDuration);
  EXPECT_LE(status.reliability().max_blocking_time.to_ns(), 1'000'000);
  // ROS 2 mode is unkeyed: one topic-wide history, deep enough for every axis.
  auto ros_status = builtin_writer_qos(TopicKind::AxisStatus, true);
  EXPECT_EQ(ros_status.history().depth, kRos2Depth);
  EXPECT_EQ(ros_status.resource_limits().max_instances, 1);
}

// A data_reader profile here (profiles are process-wide and cannot be unloaded; the
// shipped file's data_writer profiles are checked in profiles_test.cpp).
TEST(DdsQos, XmlProfileReplacesTheBuiltInQos) {
  const std::string xml = R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <profiles>
    <data_reader profile_name="stepnode_emergency">
      <topic><historyQos><kind>KEEP_LAST</kind><depth>7</depth></historyQos></topic>
      <qos><reliability><kind>RELIABLE</kind></reliability><data_sharing><kind>AUTOMATIC</kind></data_sharing></qos>
    </data_reader>
  </profiles>
</dds>)";
  auto* factory = efd::DomainParticipantFactory::get_instance();
  ASSERT_EQ(factory->load_XML_profiles_string(xml.c_str(), xml.size()), ReturnCode_t::RETCODE_OK);
  ParticipantOptions options;
  options.domain = test::unique_test_domain();
  auto* participant = create_participant(options);
  auto* subscriber = participant->create_subscriber(efd::SUBSCRIBER_QOS_DEFAULT);
  bool from_profile = false;
  auto emcy = reader_qos(TopicKind::Emergency, false, *subscriber, 0, &from_profile);
  EXPECT_TRUE(from_profile);
  EXPECT_EQ(emcy.history().depth, 7);
  EXPECT_EQ(emcy.data_sharing().kind(), efd::AUTO);
  auto status = reader_qos(TopicKind::AxisStatus, false, *subscriber, 0, &from_profile);
  EXPECT_FALSE(from_profile);
  EXPECT_EQ(status.data_sharing().kind(), efd::OFF);
  delete_participant(participant);
}

#ifdef CYCLONE_SUB_EXE
// Cyclone DDS, built from the IDL alone, receives the bridge's AxisStatus (as a late
// joiner) and AxisPosition over UDP: the topics are standard DDS.
TEST(DdsInterop, CycloneSubscriberReceivesStatusAndPosition) {
  uint32_t domain = test::unique_test_domain();
  PublisherOptions options;
  options.participant.domain = domain;
  DdsPublisher publisher(options);
  publisher.axis_status(status(6, 2, 0x8100));

  std::string command = std::string(CYCLONE_SUB_EXE) + " --domain " + std::to_string(domain) +
                        " --until-both --timeout-ms 20000 2>/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::atomic<bool> done{false};
  std::thread writer([&] {
    AxisPositionSample p;
    p.node = 6;
    p.axis = 2;
    p.motor_position = 4242;
    p.velocity = -17;
    while (!done) {  // VOLATILE: keep writing until Cyclone has matched and printed
      if (publisher.matched_readers(TopicKind::AxisPosition) > 0) publisher.axis_position(p);
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });
  std::string out;
  char line[1024];
  while (fgets(line, sizeof line, pipe)) out += line;
  done = true;
  writer.join();
  int rc = pclose(pipe);
  EXPECT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("AxisStatus node=6 axis=2 status_bits=0x8100 error_bits=0x00"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("position_valid=1"), std::string::npos) << out;
  EXPECT_NE(out.find("moving=1"), std::string::npos) << out;
  EXPECT_NE(out.find("AxisPosition node=6 axis=2 motor_position=4242"), std::string::npos) << out;
  EXPECT_NE(out.find("velocity=-17"), std::string::npos) << out;
}
#endif

}  // namespace
}  // namespace stepnode::bridge::dds
