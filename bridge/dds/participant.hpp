// Creating a DomainParticipant the way every stepnode DDS process does: XML profiles are
// loaded first (an explicit --profiles file, then FASTRTPS_DEFAULT_PROFILES_FILE /
// ./DEFAULT_FASTRTPS_PROFILES.xml), and only then is the default participant QoS read:
// Fast DDS ignores profiles loaded after that. A participant profile named
// "stepnode_participant" is used when present (else the default profile, else built-in).
// With SecurityFiles (the [dds.security] table), the DDS Security properties are added to
// whichever QoS that gives, after the files were checked (security.hpp).
#pragma once
#include <fastdds/dds/domain/DomainParticipant.hpp>

#include <cstdint>
#include <string>

#include "bridge/dds/security.hpp"

namespace stepnode::bridge::dds {

constexpr uint32_t kMaxDomain = 232;  // UDP port formula of the RTPS spec (PB 7400, DG 250)
constexpr const char* kParticipantProfile = "stepnode_participant";

struct ParticipantOptions {
  uint32_t domain = 0;
  std::string profiles_file;  // empty: only the environment's default file
  std::string name = "stepnode";
  SecurityFiles security;  // empty: no DDS Security (unless an XML profile sets it)
};

// Throws std::runtime_error naming the file or the domain when Fast DDS refuses, and
// std::invalid_argument for a bad profiles file or DDS Security file (bad input).
eprosima::fastdds::dds::DomainParticipant* create_participant(const ParticipantOptions& options);
// Deletes every entity the participant contains, then the participant.
void delete_participant(eprosima::fastdds::dds::DomainParticipant* participant);

}  // namespace stepnode::bridge::dds
