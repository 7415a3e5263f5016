// The test PKI of tools/dds-security-certs, made once per test process in a temporary
// directory (with --with-intruder), and the [dds.security] table of each participant.
#pragma once
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "bridge/dds/security.hpp"

namespace stepnode::bridge::dds::test {

// Removed when the test process ends.
struct SecurityPki {
  std::filesystem::path dir;
  SecurityPki()
      : dir(std::filesystem::temp_directory_path() /
            ("stepnode-dds-pki-" + std::to_string(getpid()))) {
    std::filesystem::remove_all(dir);
    const std::string log = dir.string() + ".log";
    const std::string cmd = std::string(STEPNODE_SOURCE_DIR) + "/tools/dds-security-certs " +
                            dir.string() + " --with-intruder --days 2 > " + log + " 2>&1";
    if (std::system(cmd.c_str()) != 0)
      throw std::runtime_error("tools/dds-security-certs failed: see " + log);
    std::filesystem::remove(log);
  }
  ~SecurityPki() { std::filesystem::remove_all(dir); }
};

inline const std::filesystem::path& security_pki_dir() {
  static const SecurityPki pki;
  return pki.dir;
}

// "stepbridge", "supervisor", "intruder" (its rogue permissions CA), "intruder-unsigned".
inline SecurityFiles security_of(const std::string& participant) {
  return load_security_table(
      config::TomlFile((security_pki_dir() / (participant + ".toml")).string()));
}

}  // namespace stepnode::bridge::dds::test
