// The shipped XML profiles load in Fast DDS 2.9 and say what the built-in QoS says.
#include <gtest/gtest.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

#include <string>

#include "bridge/dds/naming.hpp"
#include "bridge/dds/participant.hpp"
#include "bridge/dds/qos.hpp"
#include "bridge/dds/tests/test_domain.hpp"

namespace stepnode::bridge::dds {
namespace {
namespace efd = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

TEST(ShippedProfiles, StepbridgeXmlEqualsTheBuiltInWriterQos) {
  ParticipantOptions options;
  options.domain = test::unique_test_domain();
  options.profiles_file = STEPNODE_SOURCE_DIR "/bridge/profiles/stepbridge.xml";
  auto* participant = create_participant(options);
  auto* publisher = participant->create_publisher(efd::PUBLISHER_QOS_DEFAULT);
  for (TopicKind kind : kAllTopics) {
    SCOPED_TRACE(profile_name(kind));
    bool from_profile = false;
    auto xml = writer_qos(kind, false, *publisher, &from_profile);
    auto builtin = builtin_writer_qos(kind, false);
    EXPECT_TRUE(from_profile);
    EXPECT_EQ(xml.reliability().kind, builtin.reliability().kind);
    EXPECT_EQ(xml.reliability().max_blocking_time, builtin.reliability().max_blocking_time);
    EXPECT_EQ(xml.durability().kind, builtin.durability().kind);
    EXPECT_EQ(xml.history().kind, builtin.history().kind);
    EXPECT_EQ(xml.history().depth, builtin.history().depth);
    EXPECT_EQ(xml.data_sharing().kind(), efd::OFF);
    EXPECT_EQ(xml.publish_mode().kind, builtin.publish_mode().kind);
    EXPECT_EQ(xml.reliable_writer_qos().times.heartbeatPeriod,
              builtin.reliable_writer_qos().times.heartbeatPeriod);
    EXPECT_EQ(xml.reliable_writer_qos().times.nackSupressionDuration,
              builtin.reliable_writer_qos().times.nackSupressionDuration);
    EXPECT_EQ(xml.resource_limits().max_samples_per_instance,
              builtin.resource_limits().max_samples_per_instance);
    // Every axis of every node fits (NodeHealth and Emergency: one instance per node).
    const bool per_axis = kind == TopicKind::AxisStatus || kind == TopicKind::AxisPosition ||
                          kind == TopicKind::DriveStatus;
    EXPECT_GE(xml.resource_limits().max_instances, per_axis ? kMaxInstances : 127);
  }
  delete_participant(participant);
}

TEST(ShippedProfiles, DiscoveryClientXmlMakesAClientOfServer0) {
  auto* factory = efd::DomainParticipantFactory::get_instance();
  ASSERT_EQ(
      factory->load_XML_profiles_file(STEPNODE_SOURCE_DIR "/bridge/profiles/discovery-client.xml"),
      ReturnCode_t::RETCODE_OK);
  efd::DomainParticipantQos qos;
  ASSERT_EQ(factory->get_participant_qos_from_profile(kParticipantProfile, qos),
            ReturnCode_t::RETCODE_OK);
  const auto& discovery = qos.wire_protocol().builtin.discovery_config;
  EXPECT_EQ(discovery.discoveryProtocol, eprosima::fastrtps::rtps::DiscoveryProtocol_t::CLIENT);
  ASSERT_EQ(discovery.m_DiscoveryServers.size(), 1u);
  EXPECT_EQ(discovery.m_DiscoveryServers.front().metatrafficUnicastLocatorList.begin()->port,
            11811u);
}

}  // namespace
}  // namespace stepnode::bridge::dds
