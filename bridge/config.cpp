#include "bridge/config.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "config/toml_file.hpp"
#include "od/cob_id.hpp"
#include "od/communication_objects.hpp"

namespace stepnode::bridge {
namespace {

constexpr uint32_t kMaxDomain = 232;

void check(const BridgeConfig& cfg) {
  if (cfg.iface.empty())
    throw UsageError("no CAN interface: give --iface IFACE (or iface in the config file)");
  if (cfg.domain > kMaxDomain)
    throw UsageError("domain " + std::to_string(cfg.domain) + ": must be 0..232");
  if (cfg.tick_ms < 1 || cfg.tick_ms > 1000)
    throw UsageError("tick_ms " + std::to_string(cfg.tick_ms) + ": must be 1..1000");
  static const char* levels[] = {"trace",   "debug", "info",     "warn",
                                 "warning", "error", "critical", "off"};
  bool level_ok = false;
  for (const char* l : levels) level_ok |= cfg.log_level == l;
  if (!level_ok)
    throw UsageError("log level \"" + cfg.log_level +
                     "\": must be trace, debug, info, warn, error, critical or off");
}

uint32_t parse_cob_id(const std::string& text, const std::string& what) {
  if (auto id = od::parse_can_id(text)) return *id;
  throw UsageError(what + ": '" + text + "' is not an 11-bit CAN-ID (1..0x7FF)");
}

// A node-ID as written: digits only, 1..127 ("5x" is no node).
uint8_t parse_node(const std::string& text, const std::string& what) {
  if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos ||
      text.size() > 3 || std::stoi(text) < 1 || std::stoi(text) > 127)
    throw UsageError(what + ": node must be 1..127");
  return static_cast<uint8_t>(std::stoi(text));
}

std::string hex(uint32_t cob_id) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%X", cob_id);
  return text;
}

void add_sdo_channel(BridgeConfig& cfg, const NodeSdoChannel& ch, const std::string& what) {
  if (ch.node < 1 || ch.node > 127) throw UsageError(what + ": node must be 1..127");
  if (ch.client_to_server == ch.server_to_client)
    throw UsageError(what + ": the two COB-IDs must differ");
  for (const uint32_t cob_id : {ch.client_to_server, ch.server_to_client}) {
    // CiA 301 7.3.5: no SDO server channel takes them (the NMT, SYNC, TIME and the
    // default channels' and heartbeats' IDs), so the node would refuse it.
    if (od::is_restricted_can_id(cob_id))
      throw UsageError(what + ": " + hex(cob_id) + " is a restricted CAN-ID (CiA 301 7.3.5)");
    // The bridge decodes these as the SYNC and the TIME stamp.
    if (cob_id == od::cob::kSync || cob_id == od::cob::kTimeStamp)
      throw UsageError(what + ": " + hex(cob_id) + " is the " +
                       (cob_id == od::cob::kSync ? "SYNC" : "TIME") + "'s CAN-ID");
  }
  for (const NodeSdoChannel& other : cfg.sdo_channels) {
    if (other.node == ch.node)
      throw UsageError(what + ": node " + std::to_string(ch.node) + " has a channel already");
    // Two channels on one CAN-ID: the answers of one node would be taken for the other's.
    for (const uint32_t cob_id : {ch.client_to_server, ch.server_to_client})
      if (cob_id == other.client_to_server || cob_id == other.server_to_client)
        throw UsageError(what + ": " + hex(cob_id) + " is node " + std::to_string(other.node) +
                         "'s channel already");
  }
  cfg.sdo_channels.push_back(ch);
}

// [sdo_channels] 5 = [0x685, 0x6C5]: node = [client->server, server->client].
void load_sdo_channels(const config::TomlFile& file, BridgeConfig& cfg) {
  const toml::table* channels = file.table().get_as<toml::table>("sdo_channels");
  if (!channels) file.refuse("sdo_channels", "must be a table (node = [rx, tx])");
  for (const auto& [key, value] : *channels) {
    const std::string what = "config " + file.path() + ": sdo_channels." + std::string(key.str());
    const toml::array* ids = value.as_array();
    if (!ids || ids->size() != 2 || !ids->at(0).is_integer() || !ids->at(1).is_integer())
      throw UsageError(what + ": must be [CLIENT_TO_SERVER, SERVER_TO_CLIENT]");
    NodeSdoChannel ch;
    ch.node = parse_node(std::string(key.str()), what);
    auto cob_id = [&](const toml::node& n) {
      const int64_t v = *n.value<int64_t>();
      if (v < 1 || v > 0x7FF)
        throw UsageError(what + ": COB-IDs must be 11-bit CAN-IDs (1..0x7FF)");
      return static_cast<uint32_t>(v);
    };
    ch.client_to_server = cob_id(ids->at(0));
    ch.server_to_client = cob_id(ids->at(1));
    add_sdo_channel(cfg, ch, what);
  }
}

// "host" or "network": true for network time (README "TIME in the bridge's timestamps").
bool timestamps(const std::string& value, const std::string& where) {
  if (value == "host") return false;
  if (value == "network") return true;
  throw UsageError(where + ": timestamps \"" + value + "\": must be host or network");
}

// Applies the file's keys that the command line did not set.
void load_config_file(const std::string& path, BridgeConfig& cfg, const CLI::App& app) {
  const config::TomlFile file(path);
  auto given = [&](const char* option) { return option && app.count(option) > 0; };
  auto string_key = [&](const char* key, const char* option, std::string& into) {
    if (auto v = file.string(key); v && !given(option)) into = *v;
  };
  auto uint_key = [&](const char* key, const char* option, int64_t min, int64_t max,
                      uint32_t& into) {
    if (auto v = file.integer(key, min, max); v && !given(option)) into = static_cast<uint32_t>(*v);
  };
  string_key("iface", "--iface", cfg.iface);
  uint_key("domain", "--domain", 0, kMaxDomain, cfg.domain);
  if (auto v = file.boolean("ros2"); v && !given("--ros2")) cfg.ros2 = *v;
  string_key("ros2_prefix", "--ros2-prefix", cfg.ros2_prefix);
  string_key("profiles", "--profiles", cfg.profiles);
  string_key("log_level", "--log-level", cfg.log_level);
  uint_key("tick_ms", "--tick-ms", 1, 1000, cfg.tick_ms);
  uint_key("heartbeat_timeout_ms", nullptr, 0, 3'600'000,
           cfg.heartbeat_timeout_ms);  // 0: from the heartbeats
  // An SDO answer takes at least a frame time or two: below 10 ms every read would fail.
  uint_key("sdo_timeout_ms", nullptr, 10, 60'000, cfg.sdo_timeout_ms);
  uint_key("sdo_max_outstanding", nullptr, 1, 127, cfg.sdo_max_outstanding);
  uint_key("sdo_rate_per_s", nullptr, 0, 100'000,
           cfg.sdo_rate_per_s);  // 0: as fast as answers come
  if (auto v = file.string("timestamps"); v && !given("--timestamps"))
    cfg.network_time = timestamps(*v, file.path());
  if (file.has("sdo_channels") && !given("--sdo-channel")) load_sdo_channels(file, cfg);
  cfg.dds_security = dds::load_security_table(file);
  file.refuse_unknown_keys({"iface", "domain", "ros2", "ros2_prefix", "profiles", "log_level",
                            "tick_ms", "heartbeat_timeout_ms", "sdo_timeout_ms", "sdo_channels",
                            "dds", "sdo_max_outstanding", "sdo_rate_per_s", "timestamps"});
}

}  // namespace

NodeSdoChannel parse_sdo_channel(const std::string& text) {
  const std::string what = "--sdo-channel " + text;
  const size_t colon = text.find(':'), comma = text.find(',');
  if (colon == std::string::npos || comma == std::string::npos || comma < colon)
    throw UsageError(what + ": give NODE:CLIENT_TO_SERVER,SERVER_TO_CLIENT (e.g. 5:0x685,0x6C5)");
  NodeSdoChannel ch;
  ch.node = parse_node(text.substr(0, colon), what);
  ch.client_to_server = parse_cob_id(text.substr(colon + 1, comma - colon - 1), what);
  ch.server_to_client = parse_cob_id(text.substr(comma + 1), what);
  return ch;
}

BridgeConfig parse_bridge_command_line(int argc, char** argv, bool& exit_now, int& exit_code) {
  BridgeConfig cfg;
  exit_now = false;
  CLI::App app{
      "stepbridge: republishes a CANopen bus's stepnode axes and node health on DDS (eProsima Fast "
      "DDS)"};
  std::string config_file;
  app.add_option("--iface", cfg.iface, "SocketCAN interface, e.g. can0 or vcan0");
  app.add_option("--domain", cfg.domain, "DDS domain id 0..232 (default 0)");
  app.add_option("--config", config_file, "TOML config file with the same keys as the options");
  app.add_flag("--ros2", cfg.ros2,
               "ROS 2 names: topics rt/<prefix>/axis_status ..., types "
               "stepnode::msg::dds_::AxisStatus_ ...");
  app.add_option("--ros2-prefix", cfg.ros2_prefix, "topic prefix in ROS 2 mode (default stepnode)");
  app.add_option("--profiles", cfg.profiles,
                 "Fast DDS XML profiles file (loaded before FASTRTPS_DEFAULT_PROFILES_FILE)");
  app.add_option("--log-level", cfg.log_level, "trace, debug, info, warn, error, off");
  app.add_option("--tick-ms", cfg.tick_ms, "observer timer period in ms (1..1000, default 10)");
  std::string timestamps_option;
  app.add_option(
      "--timestamps", timestamps_option,
      "host (default): samples carry the host's kernel timestamps; network: on the bus's TIME "
      "(COB-ID 0x100) once a TIME frame was seen");
  std::vector<std::string> sdo_channels;
  app.add_option(
      "--sdo-channel", sdo_channels,
      "NODE:RX,TX: read node NODE on its SDO server channel with these COB-IDs (client->server, "
      "server->client, as set in 0x1201..0x1203 sub 1/2); repeatable. Other nodes: the default "
      "channel, when quiet");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    exit_now = true;
    exit_code = app.exit(e);
    return cfg;
  } catch (const CLI::ParseError& e) {
    throw UsageError(e.what());
  }
  if (!timestamps_option.empty()) cfg.network_time = timestamps(timestamps_option, "--timestamps");
  for (const std::string& text : sdo_channels)
    add_sdo_channel(cfg, parse_sdo_channel(text), "--sdo-channel " + text);
  if (!config_file.empty()) load_config_file(config_file, cfg, app);
  if (app.count("--ros2-prefix") && !cfg.ros2) throw UsageError("--ros2-prefix needs --ros2");
  if (!cfg.profiles.empty() && !std::filesystem::is_regular_file(cfg.profiles))
    throw UsageError("profiles " + cfg.profiles + ": cannot read file");
  check(cfg);
  return cfg;
}

}  // namespace stepnode::bridge
