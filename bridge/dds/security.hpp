// DDS Security (OMG DDS Security 1.1, Fast DDS's builtin plugins) for the participants of
// stepbridge and stepwatch: the six files of the [dds.security] table, checked before
// Fast DDS sees them (so a wrong file is one line naming it, not a refused participant),
// and the participant properties that turn on PKI-DH authentication, Access-Permissions
// and AES-GCM-GMAC. README "DDS Security" tells how to make the files.
#pragma once
#include <string>

#include "config/toml_file.hpp"

namespace eprosima::fastdds::dds {
class DomainParticipantQos;
}

namespace stepnode::bridge::dds {

// Absolute paths (or all empty: no security).
struct SecurityFiles {
  std::string identity_ca;           // the CA that signed every participant's certificate
  std::string identity_certificate;  // this participant's certificate (PEM)
  std::string private_key;           // its key (PEM, unencrypted: keep it 0600)
  std::string permissions_ca;        // the CA that signed governance and permissions
  std::string governance;            // signed governance document (S/MIME)
  std::string permissions;           // signed permissions document with this participant's grant
  bool enabled() const { return !identity_ca.empty(); }
};

// The [dds.security] table of a config file, when it has one (else all empty). Every key
// is required; relative paths are relative to the file's directory (a config under
// /etc/stepnode names its certificates beside it whatever the working directory is).
// Unknown keys under [dds] or [dds.security] refuse the file. Throws config::UsageError.
SecurityFiles load_security_table(const config::TomlFile& file);

// Reads each file and checks what Fast DDS would refuse later without saying which file:
// certificates are PEM, the identity certificate is signed by the identity CA and valid
// now, the key belongs to it, both documents are S/MIME signed by the permissions CA, and
// the permissions grant something to this certificate's subject. Throws
// std::invalid_argument: "dds.security.KEY PATH: what is wrong".
void check_security_files(const SecurityFiles& files);

// Sets the dds.sec.* properties (file:// URIs) on `qos`, replacing any of the same name
// an XML profile set.
void add_security_properties(const SecurityFiles& files,
                             eprosima::fastdds::dds::DomainParticipantQos& qos);

}  // namespace stepnode::bridge::dds
