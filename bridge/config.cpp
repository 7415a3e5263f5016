#include "bridge/config.hpp"

#include <CLI/CLI.hpp>
#include <toml++/toml.h>

#include <filesystem>
#include <sstream>

namespace stepnode::bridge {
namespace {

constexpr uint32_t kMaxDomain = 232;

void check(const BridgeConfig& cfg) {
  if (cfg.iface.empty()) throw UsageError("no CAN interface: give --iface IFACE (or iface in the config file)");
  if (cfg.domain > kMaxDomain) throw UsageError("domain " + std::to_string(cfg.domain) + ": must be 0..232");
  if (cfg.tick_ms < 1 || cfg.tick_ms > 1000) throw UsageError("tick_ms " + std::to_string(cfg.tick_ms) + ": must be 1..1000");
  static const char* levels[] = {"trace", "debug", "info", "warn", "warning", "error", "critical", "off"};
  bool level_ok = false;
  for (const char* l : levels) level_ok |= cfg.log_level == l;
  if (!level_ok) throw UsageError("log level \"" + cfg.log_level + "\": must be trace, debug, info, warn, error, critical or off");
}

// Applies the file's keys that the command line did not set.
void load_config_file(const std::string& path, BridgeConfig& cfg, const CLI::App& app) {
  toml::table t;
  try {
    t = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    std::ostringstream msg;
    msg << "config " << path << ": " << e.description();
    if (e.source().begin) msg << " (line " << e.source().begin.line << ")";
    throw UsageError(msg.str());
  }
  auto bad = [&](const std::string& key, const std::string& rule) {
    throw UsageError("config " + path + ": " + key + ": " + rule);
  };
  auto given = [&](const char* option) { return app.count(option) > 0; };
  auto string_key = [&](const char* key, const char* option, std::string& into) {
    if (auto v = t[key]) {
      if (!v.is_string()) bad(key, "must be a string");
      if (!given(option)) into = *v.value<std::string>();
    }
  };
  auto uint_key = [&](const char* key, const char* option, int64_t min, int64_t max, uint32_t& into) {
    if (auto v = t[key]) {
      auto n = v.value<int64_t>();
      if (!v.is_integer() || !n || *n < min || *n > max)
        bad(key, "must be an integer " + std::to_string(min) + ".." + std::to_string(max));
      if (!option || !given(option)) into = static_cast<uint32_t>(*n);
    }
  };
  string_key("iface", "--iface", cfg.iface);
  uint_key("domain", "--domain", 0, kMaxDomain, cfg.domain);
  if (auto v = t["ros2"]) {
    if (!v.is_boolean()) bad("ros2", "must be true or false");
    if (!given("--ros2")) cfg.ros2 = *v.value<bool>();
  }
  string_key("ros2_prefix", "--ros2-prefix", cfg.ros2_prefix);
  string_key("profiles", "--profiles", cfg.profiles);
  string_key("log_level", "--log-level", cfg.log_level);
  uint_key("tick_ms", "--tick-ms", 1, 1000, cfg.tick_ms);
  uint_key("heartbeat_timeout_ms", nullptr, 0, 3'600'000, cfg.heartbeat_timeout_ms);  // 0: from the heartbeats
  // An SDO answer takes at least a frame time or two: below 10 ms every read would fail.
  uint_key("sdo_timeout_ms", nullptr, 10, 60'000, cfg.sdo_timeout_ms);
  for (const auto& [key, value] : t) {
    static const char* known[] = {"iface", "domain", "ros2", "ros2_prefix", "profiles", "log_level",
                                  "tick_ms", "heartbeat_timeout_ms", "sdo_timeout_ms"};
    bool ok = false;
    for (const char* k : known) ok |= key.str() == k;
    if (!ok) bad(std::string(key.str()), "unknown key");
  }
}

}  // namespace

BridgeConfig parse_bridge_command_line(int argc, char** argv, bool& exit_now, int& exit_code) {
  BridgeConfig cfg;
  exit_now = false;
  CLI::App app{"stepbridge: republishes a CANopen bus's stepnode axes and node health on DDS (eProsima Fast DDS)"};
  std::string config_file;
  app.add_option("--iface", cfg.iface, "SocketCAN interface, e.g. can0 or vcan0");
  app.add_option("--domain", cfg.domain, "DDS domain id 0..232 (default 0)");
  app.add_option("--config", config_file, "TOML config file with the same keys as the options");
  app.add_flag("--ros2", cfg.ros2, "ROS 2 names: topics rt/<prefix>/axis_status ..., types stepnode::msg::dds_::AxisStatus_ ...");
  app.add_option("--ros2-prefix", cfg.ros2_prefix, "topic prefix in ROS 2 mode (default stepnode)");
  app.add_option("--profiles", cfg.profiles, "Fast DDS XML profiles file (loaded before FASTRTPS_DEFAULT_PROFILES_FILE)");
  app.add_option("--log-level", cfg.log_level, "trace, debug, info, warn, error, off");
  app.add_option("--tick-ms", cfg.tick_ms, "observer timer period in ms (1..1000, default 10)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    exit_now = true;
    exit_code = app.exit(e);
    return cfg;
  } catch (const CLI::ParseError& e) {
    throw UsageError(e.what());
  }
  if (!config_file.empty()) {
    if (!std::filesystem::is_regular_file(config_file)) throw UsageError("config " + config_file + ": cannot read file");
    load_config_file(config_file, cfg, app);
  }
  if (app.count("--ros2-prefix") && !cfg.ros2) throw UsageError("--ros2-prefix needs --ros2");
  if (!cfg.profiles.empty() && !std::filesystem::is_regular_file(cfg.profiles))
    throw UsageError("profiles " + cfg.profiles + ": cannot read file");
  check(cfg);
  return cfg;
}

}  // namespace stepnode::bridge
