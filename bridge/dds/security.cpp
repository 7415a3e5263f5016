#include "bridge/dds/security.hpp"

#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

#include <filesystem>
#include <utility>
#include <vector>

namespace stepnode::bridge::dds {
namespace {

constexpr const char* kTable = "dds.security";

// A key of the table and the member it fills.
struct FileKey {
  const char* key;
  std::string SecurityFiles::*member;
};
constexpr FileKey kFileKeys[] = {
    {"identity_ca", &SecurityFiles::identity_ca},
    {"identity_certificate", &SecurityFiles::identity_certificate},
    {"private_key", &SecurityFiles::private_key},
    {"permissions_ca", &SecurityFiles::permissions_ca},
    {"governance", &SecurityFiles::governance},
    {"permissions", &SecurityFiles::permissions},
};

std::string full_key(std::string_view key) { return std::string(kTable) + "." + std::string(key); }

void refuse_unknown(const config::TomlFile& file, const toml::table& table, std::string_view where,
                    const std::vector<std::string_view>& known) {
  for (const auto& [key, value] : table) {
    bool ok = false;
    for (std::string_view k : known) ok |= key.str() == k;
    if (!ok) file.refuse(std::string(where) + "." + std::string(key.str()), "unknown key");
  }
}

void set_property(eprosima::fastdds::dds::DomainParticipantQos& qos, const std::string& name,
                  const std::string& value) {
  auto& props = qos.properties().properties();
  for (auto& p : props)
    if (p.name() == name) {
      p.value(value);
      return;
    }
  props.emplace_back(name, value);
}

}  // namespace

SecurityFiles load_security_table(const config::TomlFile& file) {
  SecurityFiles files;
  if (!file.has("dds")) return files;
  const toml::table* dds = file.table().get_as<toml::table>("dds");
  if (!dds) file.refuse("dds", "must be a table ([dds.security])");
  refuse_unknown(file, *dds, "dds", {"security"});
  if (!dds->contains("security")) return files;
  const toml::table* security = dds->get_as<toml::table>("security");
  if (!security) file.refuse(kTable, "must be a table");
  std::vector<std::string_view> known;
  for (const FileKey& k : kFileKeys) known.push_back(k.key);
  refuse_unknown(file, *security, kTable, known);

  const std::filesystem::path base = std::filesystem::absolute(file.path()).parent_path();
  for (const FileKey& k : kFileKeys) {
    const toml::node* n = security->get(k.key);
    if (!n)
      file.refuse(full_key(k.key),
                  "missing (DDS Security needs identity_ca, identity_certificate, "
                  "private_key, permissions_ca, governance and permissions)");
    if (!n->is_string() || n->as_string()->get().empty())
      file.refuse(full_key(k.key), "must be a file path");
    std::filesystem::path p(n->as_string()->get());
    files.*k.member = (p.is_absolute() ? p : base / p).lexically_normal().string();
  }
  return files;
}

void add_security_properties(const SecurityFiles& files,
                             eprosima::fastdds::dds::DomainParticipantQos& qos) {
  // Property names of Fast DDS 2.9's builtin plugins (its documentation, "Security").
  const std::string auth = "dds.sec.auth.builtin.PKI-DH.";
  const std::string access = "dds.sec.access.builtin.Access-Permissions.";
  auto uri = [](const std::string& path) { return "file://" + path; };
  set_property(qos, "dds.sec.auth.plugin", "builtin.PKI-DH");
  set_property(qos, auth + "identity_ca", uri(files.identity_ca));
  set_property(qos, auth + "identity_certificate", uri(files.identity_certificate));
  set_property(qos, auth + "private_key", uri(files.private_key));
  set_property(qos, "dds.sec.access.plugin", "builtin.Access-Permissions");
  set_property(qos, access + "permissions_ca", uri(files.permissions_ca));
  set_property(qos, access + "governance", uri(files.governance));
  set_property(qos, access + "permissions", uri(files.permissions));
  set_property(qos, "dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC");
}

}  // namespace stepnode::bridge::dds
