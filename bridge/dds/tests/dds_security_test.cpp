// DDS Security end to end in one process: the bridge's own publisher (DdsPublisher) with
// the stepbridge identity of tools/dds-security-certs, and subscriber participants that
// should and should not get its samples. Intra-process delivery is switched off so every
// sample goes through the transports (and their encryption) as between processes.
#include <fastrtps/xmlparser/XMLProfileManager.h>
#include <gtest/gtest.h>
#include <unistd.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>

#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/lsan_interface.h>
#endif

#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "bridge/dds/convert.hpp"
#include "bridge/dds/participant.hpp"
#include "bridge/dds/publisher.hpp"
#include "bridge/dds/qos.hpp"
#include "bridge/dds/security.hpp"
#include "bridge/dds/tests/security_pki.hpp"
#include "bridge/dds/tests/test_domain.hpp"
#include "bridge/dds/types.hpp"

namespace stepnode::bridge::dds {
namespace {
namespace efd = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;
using Clock = std::chrono::steady_clock;

void no_intraprocess_delivery() {
  eprosima::fastrtps::LibrarySettingsAttributes settings;
  settings.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_OFF;
  eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(settings);
}

// An AxisStatus reader on a participant of its own, made from `qos` (the properties
// decide its security). reader() is null when Fast DDS refused to create it.
class StatusReader {
 public:
  StatusReader(uint32_t domain, const efd::DomainParticipantQos& qos) {
    participant_ = efd::DomainParticipantFactory::get_instance()->create_participant(domain, qos);
    if (!participant_) return;
    const Naming naming;
    const std::string type = type_name(TopicKind::AxisStatus, naming);
    make_type_support(TopicKind::AxisStatus, naming).register_type(participant_, type);
    auto* topic = participant_->create_topic(topic_name(TopicKind::AxisStatus, naming), type,
                                             efd::TOPIC_QOS_DEFAULT);
    auto* subscriber = participant_->create_subscriber(efd::SUBSCRIBER_QOS_DEFAULT);
    if (topic && subscriber)
      reader_ = subscriber->create_datareader(topic,
                                              builtin_reader_qos(TopicKind::AxisStatus, false, 16));
  }
  ~StatusReader() { delete_participant(participant_); }

  efd::DomainParticipant* participant() const { return participant_; }
  efd::DataReader* reader() const { return reader_; }
  // Samples taken so far (all of them are counted, whatever axis).
  int poll() {
    if (!reader_) return received_;
    ::stepnode::AxisStatus s;
    efd::SampleInfo info;
    while (reader_->take_next_sample(&s, &info) == ReturnCode_t::RETCODE_OK)
      if (info.valid_data) ++received_;
    return received_;
  }
  int matched() const {
    if (!reader_) return 0;
    efd::SubscriptionMatchedStatus status;
    reader_->get_subscription_matched_status(status);
    return status.current_count;
  }

 private:
  efd::DomainParticipant* participant_ = nullptr;
  efd::DataReader* reader_ = nullptr;
  int received_ = 0;
};

efd::DomainParticipantQos secured_qos(const SecurityFiles& files) {
  efd::DomainParticipantQos qos;
  add_security_properties(files, qos);
  return qos;
}

// Authentication only (a valid certificate of the identity CA), no permissions at all.
efd::DomainParticipantQos authenticated_only_qos(const SecurityFiles& files) {
  efd::DomainParticipantQos qos;
  auto& p = qos.properties().properties();
  p.emplace_back("dds.sec.auth.plugin", "builtin.PKI-DH");
  p.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_ca", "file://" + files.identity_ca);
  p.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_certificate",
                 "file://" + files.identity_certificate);
  p.emplace_back("dds.sec.auth.builtin.PKI-DH.private_key", "file://" + files.private_key);
  return qos;
}

AxisStatusSample status(uint16_t bits) {
  AxisStatusSample s;
  s.node = 5;
  s.axis = 1;
  s.status_bits = bits;
  return s;
}

TEST(DdsSecurity, OnlyThePermittedSupervisorReadsTheBridge) {
  no_intraprocess_delivery();
  const uint32_t domain = test::unique_test_domain();
  PublisherOptions options;
  options.participant.domain = domain;
  options.participant.security = test::security_of("stepbridge");
  DdsPublisher publisher(options);

  StatusReader supervisor(domain, secured_qos(test::security_of("supervisor")));
  StatusReader plain(domain, efd::PARTICIPANT_QOS_DEFAULT);  // no security at all
  StatusReader rogue(domain,
                     secured_qos(test::security_of("intruder")));  // permissions of a rogue CA
  StatusReader auth_only(domain,
                         authenticated_only_qos(test::security_of("intruder")));  // no permissions
  ASSERT_NE(supervisor.reader(), nullptr);
  // Each of the others has a reader of its own, so "nothing" below is the bridge's refusal,
  // not a reader that was never there.
  ASSERT_NE(plain.reader(), nullptr);
  ASSERT_NE(rogue.reader(), nullptr)
      << "the rogue CA's grant lets the intruder create its reader locally";
  ASSERT_NE(auth_only.reader(), nullptr);

  // Samples keep coming (TRANSIENT_LOCAL also gives a late match the last one).
  const auto start = Clock::now();
  uint16_t bits = 0x0100;
  while (supervisor.poll() < 3 && Clock::now() - start < std::chrono::seconds(20)) {
    publisher.axis_status(status(bits++));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  const double first_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  ASSERT_GE(supervisor.poll(), 3) << "the permitted supervisor got no samples within 20 s";
  EXPECT_EQ(supervisor.matched(), 1);

  // As long again and at least 3 s more for the others: discovery had the same chances.
  const auto more = std::max(std::chrono::milliseconds(3000),
                             std::chrono::milliseconds(static_cast<int>(first_ms)));
  const auto until = Clock::now() + more;
  while (Clock::now() < until) {
    publisher.axis_status(status(bits++));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(plain.poll(), 0) << "a participant without security read the bridge";
  EXPECT_EQ(rogue.poll(), 0) << "a participant with permissions of another CA read the bridge";
  EXPECT_EQ(auth_only.poll(), 0)
      << "an authenticated participant without permissions read the bridge";
  EXPECT_EQ(plain.matched() + rogue.matched() + auth_only.matched(), 0);
  std::printf(
      "DDS Security: supervisor matched and had 3 samples after %.0f ms; the other three 0 samples "
      "in "
      "another %lld ms (supervisor %d samples in all)\n",
      first_ms, static_cast<long long>(more.count()), supervisor.poll());
}

TEST(DdsSecurity, ACertificateTheGrantsDoNotNameCannotJoin) {
  // The intruder's valid certificate with the plant's real permissions (signed by the
  // right CA, but no grant names it): refused before Fast DDS sees it, in one line.
  ParticipantOptions options;
  options.domain = test::unique_test_domain();
  options.security = test::security_of("intruder-unsigned");
  try {
    delete_participant(create_participant(options));
    FAIL() << "a participant without a grant was created";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("dds.security.permissions"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("no grant for CN=intruder,O=stepnode,C=DE"),
              std::string::npos)
        << e.what();
  }
  // And Fast DDS refuses the same participant on its own (the check is not stricter than it).
  // Fast DDS 2.9 leaks the identity handle of a participant it refuses (allocated in
  // PKIDH::get_identity_handle, never returned): the sanitizer build is not told of it.
#if defined(__SANITIZE_ADDRESS__)
  __lsan_disable();
#endif
  efd::DomainParticipant* refused =
      efd::DomainParticipantFactory::get_instance()->create_participant(
          options.domain, secured_qos(options.security));
#if defined(__SANITIZE_ADDRESS__)
  __lsan_enable();
#endif
  EXPECT_EQ(refused, nullptr);
}

TEST(DdsSecurity, TheBridgeMayNotSubscribe) {
  // Its grant allows publishing only: a reader with its identity is refused locally.
  StatusReader bridge_as_reader(test::unique_test_domain(),
                                secured_qos(test::security_of("stepbridge")));
  ASSERT_NE(bridge_as_reader.participant(), nullptr);
  EXPECT_EQ(bridge_as_reader.reader(), nullptr);
}

}  // namespace
}  // namespace stepnode::bridge::dds
