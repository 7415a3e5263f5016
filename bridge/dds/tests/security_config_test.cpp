// The [dds.security] table and the checks of its files: every wrong file is refused with
// one line that names the key and the file, before Fast DDS reads it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bridge/config.hpp"
#include "bridge/dds/security.hpp"
#include "bridge/dds/tests/security_pki.hpp"

namespace stepnode::bridge::dds {
namespace {
namespace fs = std::filesystem;

fs::path write_file(const std::string& name, const std::string& text) {
  const fs::path dir =
      fs::temp_directory_path() / ("stepnode-sec-config-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const fs::path path = dir / name;
  std::ofstream(path) << text;
  return path;
}

const char* kTable =
    "[dds.security]\n"
    "identity_ca = \"ca/identity.pem\"\n"
    "identity_certificate = \"/etc/stepnode/bridge.pem\"\n"
    "private_key = \"bridge.key\"\n"
    "permissions_ca = \"ca/permissions.pem\"\n"
    "governance = \"governance.p7s\"\n"
    "permissions = \"permissions.p7s\"\n";

std::string load_error(const std::string& text) {
  try {
    load_security_table(config::TomlFile(write_file("bad.toml", text).string()));
  } catch (const config::UsageError& e) {
    return e.what();
  }
  return "";
}

std::string check_error(const SecurityFiles& files) {
  try {
    check_security_files(files);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(SecurityConfig, RelativePathsAreRelativeToTheConfigFile) {
  const fs::path file = write_file("sec.toml", kTable);
  const fs::path dir = file.parent_path();
  SecurityFiles f = load_security_table(config::TomlFile(file.string()));
  EXPECT_TRUE(f.enabled());
  EXPECT_EQ(f.identity_ca, (dir / "ca/identity.pem").string());
  EXPECT_EQ(f.identity_certificate, "/etc/stepnode/bridge.pem");
  EXPECT_EQ(f.private_key, (dir / "bridge.key").string());
  EXPECT_EQ(f.permissions_ca, (dir / "ca/permissions.pem").string());
  EXPECT_EQ(f.governance, (dir / "governance.p7s").string());
  EXPECT_EQ(f.permissions, (dir / "permissions.p7s").string());
}

TEST(SecurityConfig, NoTableNoSecurity) {
  EXPECT_FALSE(
      load_security_table(config::TomlFile(write_file("none.toml", "iface = \"can0\"\n").string()))
          .enabled());
}

TEST(SecurityConfig, EveryKeyIsRequiredAndNoOtherAllowed) {
  std::string text = kTable;
  text.erase(text.find("permissions = "));
  EXPECT_NE(load_error(text).find(": dds.security.permissions: missing"), std::string::npos)
      << load_error(text);
  EXPECT_NE(load_error(std::string(kTable) + "password = \"x\"\n")
                .find("dds.security.password: unknown key"),
            std::string::npos);
  EXPECT_NE(load_error("[dds]\nsecurty = 1\n").find("dds.securty: unknown key"), std::string::npos);
  EXPECT_NE(load_error("dds = 1\n").find("dds: must be a table"), std::string::npos);
  EXPECT_NE(load_error("[dds.security]\nidentity_ca = 5\n")
                .find("dds.security.identity_ca: must be a file path"),
            std::string::npos);
}

TEST(SecurityConfig, TheBridgeConfigCarriesTheTable) {
  const std::string path =
      write_file("bridge.toml", std::string("iface = \"vcan0\"\n") + kTable).string();
  std::vector<std::string> args{"stepbridge", "--config", path};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  bool exit_now = false;
  int exit_code = 0;
  BridgeConfig cfg =
      parse_bridge_command_line(static_cast<int>(argv.size()), argv.data(), exit_now, exit_code);
  EXPECT_TRUE(cfg.dds_security.enabled());
  EXPECT_EQ(cfg.dds_security.identity_certificate, "/etc/stepnode/bridge.pem");
}

TEST(SecurityCheck, TheScriptsFilesPass) {
  for (const char* participant : {"stepbridge", "supervisor"})
    EXPECT_EQ(check_error(test::security_of(participant)), "") << participant;
}

TEST(SecurityCheck, EachWrongFileIsNamed) {
  const fs::path pki = test::security_pki_dir();
  const SecurityFiles good = test::security_of("stepbridge");
  SecurityFiles f = good;
  f.governance = (pki / "missing.p7s").string();
  EXPECT_EQ(check_error(f), "dds.security.governance " + f.governance + ": cannot read file");

  f = good;
  f.identity_ca = (pki / "governance.p7s").string();
  EXPECT_EQ(check_error(f),
            "dds.security.identity_ca " + f.identity_ca + ": not a PEM X.509 certificate");

  f = good;  // a CA that did not sign the bridge's certificate
  f.identity_ca = (pki / "intruder/rogue_ca.pem").string();
  EXPECT_NE(check_error(f).find("dds.security.identity_certificate " + f.identity_certificate +
                                ": not accepted by identity_ca " + f.identity_ca),
            std::string::npos)
      << check_error(f);

  f = good;  // another participant's key
  f.private_key = (pki / "supervisor/key.pem").string();
  EXPECT_EQ(check_error(f), "dds.security.private_key " + f.private_key +
                                ": is not the key of identity_certificate " +
                                f.identity_certificate);

  f = good;  // a certificate where a signed document belongs
  f.governance = (pki / "identity_ca.pem").string();
  EXPECT_NE(check_error(f).find("dds.security.governance " + f.governance +
                                ": not an S/MIME signed document"),
            std::string::npos)
      << check_error(f);

  f = good;  // a document signed by the rogue CA
  f.permissions = (pki / "intruder/permissions.p7s").string();
  EXPECT_EQ(check_error(f), "dds.security.permissions " + f.permissions +
                                ": signature not accepted by permissions_ca " + f.permissions_ca);
}

}  // namespace
}  // namespace stepnode::bridge::dds
