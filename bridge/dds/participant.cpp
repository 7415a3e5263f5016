#include "bridge/dds/participant.hpp"

#include <spdlog/spdlog.h>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

#include <filesystem>
#include <stdexcept>

#if defined(__SANITIZE_ADDRESS__)
// Debian's libfastrtps 2.9 deletes its StatisticsWriterImpl through a pointer of another
// size (ASan: new-delete-type-mismatch inside the library, at every participant's
// creation). Every program that creates a participant links this file, so the sanitizer
// build checks everything else; options given in ASAN_OPTIONS still override this one.
extern "C" const char* __asan_default_options() { return "new_delete_type_mismatch=0"; }
#endif

namespace stepnode::bridge::dds {
namespace efd = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

efd::DomainParticipant* create_participant(const ParticipantOptions& options) {
  if (options.domain > kMaxDomain)
    throw std::invalid_argument("domain " + std::to_string(options.domain) + ": must be 0.." +
                                std::to_string(kMaxDomain));
  auto* factory = efd::DomainParticipantFactory::get_instance();
  if (!options.profiles_file.empty()) {
    if (!std::filesystem::is_regular_file(options.profiles_file))
      throw std::invalid_argument("profiles " + options.profiles_file + ": cannot read file");
    if (factory->load_XML_profiles_file(options.profiles_file) != ReturnCode_t::RETCODE_OK)
      throw std::invalid_argument("profiles " + options.profiles_file +
                                  ": Fast DDS rejected the XML");
  }
  // Loads the environment's default profile file (once per process) and makes its default
  // participant profile the default participant QoS. Must come before the QoS is read.
  factory->load_profiles();

  efd::DomainParticipantQos qos = factory->get_default_participant_qos();
  if (factory->get_participant_qos_from_profile(kParticipantProfile, qos) ==
      ReturnCode_t::RETCODE_OK)
    spdlog::debug("participant QoS from XML profile {}", kParticipantProfile);
  if (qos.name().to_string().empty() || qos.name().to_string() == "RTPSParticipant")
    qos.name(options.name);
  if (options.security.enabled()) {
    check_security_files(options.security);  // a wrong file: one line that names it
    add_security_properties(options.security, qos);
  }
  efd::DomainParticipant* participant = factory->create_participant(options.domain, qos);
  // The files passed the checks, so what is left is their content (a governance or a
  // grant Fast DDS cannot parse, or that does not let this participant join the domain).
  if (!participant && options.security.enabled())
    throw std::invalid_argument("dds.security: Fast DDS refused the participant on domain " +
                                std::to_string(options.domain) +
                                " (the governance or permissions content; " +
                                "Fast DDS's log above says which)");
  if (!participant)
    throw std::runtime_error("DDS domain " + std::to_string(options.domain) +
                             ": Fast DDS could not create a participant");
  return participant;
}

void delete_participant(efd::DomainParticipant* participant) {
  if (!participant) return;
  participant->delete_contained_entities();
  efd::DomainParticipantFactory::get_instance()->delete_participant(participant);
}

}  // namespace stepnode::bridge::dds
