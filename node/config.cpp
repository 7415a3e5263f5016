#include "node/config.hpp"

#include <CLI/CLI.hpp>

#include <charconv>
#include <cstdlib>
#include <map>
#include <optional>

#include "config/toml_file.hpp"
#include "node/node_id_list.hpp"
#include "od/pdo_mapping.hpp"

namespace stepnode::node {
namespace {

constexpr int64_t kMaxBootListenMs = 60'000;

std::filesystem::path default_state_dir() {
  if (const char* s = std::getenv("STATE_DIRECTORY")) return s;  // systemd StateDirectory=
  if (const char* s = std::getenv("XDG_STATE_HOME")) return std::filesystem::path(s) / "stepnode";
  if (const char* h = std::getenv("HOME"))
    return std::filesystem::path(h) / ".local/state/stepnode";
  return "/var/lib/stepnode";
}

// What the command line gave, which the file's keys do not override.
struct GivenOnCommandLine {
  bool iface = false;
  bool node_id = false;
  bool state_dir = false;
  bool tick_us = false;
  bool log_level = false;
};

// node_id: 1..127, "none" (255, CiA 305's invalid node-ID): the node waits for an LSS
// master; or a list "1-32" / "1,5,10-12": that many nodes in the process. Returns true when
// the file has the key.
bool load_node_id(const config::TomlFile& file, NodeConfig& cfg, bool id_given) {
  const toml::node* v = file.table().get("node_id");
  if (!v) return false;
  const char* rule = "must be an integer 1..127, \"none\" (255), or a list such as \"1-32\"";
  const auto text = v->value_exact<std::string>();
  int64_t id = v->value_exact<int64_t>().value_or(-1);  // -1: not an integer
  std::vector<uint8_t> ids;
  if (text && *text != "none") {
    try {
      ids = parse_node_id_list(*text);
    } catch (const std::invalid_argument&) {
      file.refuse("node_id", rule);
    }
    if (ids.size() == 1) file.refuse("node_id", rule);  // one id is an integer, not text
    id = ids.front();
  }
  const bool none = text == "none" || id == lss::kUnconfigured;
  if (!none && (id < 1 || id > 127)) file.refuse("node_id", rule);
  if (!id_given) {
    cfg.options.device.node_id = none ? lss::kUnconfigured : static_cast<uint8_t>(id);
    cfg.options.node_id_origin = none ? NodeIdOrigin::None : NodeIdOrigin::ConfigFile;
    cfg.node_ids = ids;
  }
  return true;
}

// profiles: the profiles the device has, any of "horner", "hp", "user", "cia402" (default:
// the first three).
void load_profiles(const config::TomlFile& file, DeviceLayout& layout) {
  if (!file.has("profiles")) return;
  const char* rule = "must be a list of \"horner\", \"hp\", \"user\", \"cia402\"";
  const toml::array* list = file.table().get_as<toml::array>("profiles");
  if (!list) file.refuse("profiles", rule);
  layout.horner = layout.hp = layout.user = layout.cia402 = false;
  for (const auto& item : *list) {
    auto name = item.value_exact<std::string>();
    if (name && *name == "horner") layout.horner = true;
    else if (name && *name == "hp") layout.hp = true;
    else if (name && *name == "user") layout.user = true;
    else if (name && *name == "cia402") layout.cia402 = true;
    else file.refuse("profiles", rule);
  }
}

// A REAL64 as text that reads back as the same double (std::to_string keeps 6 decimals:
// a PSCALE of 2.5e-6 became 3e-6).
std::string shortest_text(double d) {
  char text[32];
  const auto [end, ec] = std::to_chars(text, text + sizeof text, d);
  return std::string(text, end);
}

// [defaults]: "1017" = 500 or "1016:1" = 0x000101F4, kept as text for the object's type.
void load_object_defaults(const config::TomlFile& file, NodeConfig& cfg) {
  const toml::table* defaults = file.table().get_as<toml::table>("defaults");
  if (!defaults) return;
  for (const auto& [key, value] : *defaults) {
    std::string text;
    if (auto i = value.value<int64_t>()) text = std::to_string(*i);
    else if (auto s = value.value<std::string>()) text = *s;
    else if (auto d = value.value<double>()) text = shortest_text(*d);
    else file.refuse("defaults." + std::string(key.str()), "must be an integer, number or string");
    cfg.object_defaults.emplace_back(std::string(key.str()), text);
  }
}

// Returns true when the file set the node id.
bool load_config_file(const std::string& path, NodeConfig& cfg, GivenOnCommandLine given) {
  const config::TomlFile file(path);
  if (auto iface = file.string("iface"); iface && !given.iface) cfg.iface = *iface;
  const bool id_set = load_node_id(file, cfg, given.node_id);
  if (auto dir = file.string("state_dir"); dir && !given.state_dir) {
    cfg.options.state_dir = *dir;
    cfg.state_dir_given = true;
  }
  if (auto us = file.integer("tick_us", 100, 10'000'000); us && !given.tick_us)
    cfg.tick_us = static_cast<uint64_t>(*us);
  if (auto us = file.integer("step_horizon_us", 0, 1'000'000))
    cfg.options.layout.step_horizon_us = static_cast<uint32_t>(*us);
  const auto axes = file.integer("axes", 1, static_cast<int64_t>(kMaxAxes));
  if (axes) cfg.options.layout.axes = static_cast<unsigned>(*axes);
  if (auto on = file.boolean("spm30_multiplexed")) {
    // SPM30 3-axis models: one register set and %Q1..%Q3 select one of three motors.
    cfg.options.layout.spm30_multiplexed = *on;
    if (*on && axes && *axes != 1)
      file.refuse("axes",
                  "must be 1 (or left out) with spm30_multiplexed = true: the one "
                  "register set selects one of its three motors");
    if (*on) cfg.options.layout.axes = 1;
  }
  load_profiles(file, cfg.options.layout);
  if (auto n = file.integer("serial_number", 0, 0xFFFFFFFFll))
    cfg.options.device.serial_number = static_cast<uint32_t>(*n);
  if (auto level = file.string("log_level"); level && !given.log_level) cfg.log_level = *level;
  if (auto on = file.boolean("apply_bit_timing")) cfg.apply_bit_timing = *on;
  // boot_listen_ms: listen for another device with the node-ID before the boot-up.
  if (auto ms = file.integer("boot_listen_ms", 0, kMaxBootListenMs))
    cfg.options.boot_listen_us = static_cast<uint64_t>(*ms) * 1000;
  // self_start: the default of 0x1F80 NMT startup (CiA 302-2 bit 2: 0 = enter operational
  // by itself after boot-up); [defaults] "1F80" and a stored value go over it.
  if (auto on = file.boolean("self_start"))
    cfg.object_defaults.emplace_back("1F80", *on ? "0" : "4");
  load_object_defaults(file, cfg);
  // A misspelt key ("nodeid", "[defualts]") would otherwise run the node on defaults.
  file.refuse_unknown_keys({"iface", "node_id", "state_dir", "tick_us", "step_horizon_us", "axes",
                            "spm30_multiplexed", "profiles", "serial_number", "log_level",
                            "apply_bit_timing", "boot_listen_ms", "self_start", "defaults"});
  return id_set;
}

// --serial-number: an UNSIGNED32, decimal or 0x hex.
uint32_t parse_serial_number(const std::string& text) {
  unsigned long long n = 0;
  size_t used = 0;
  try {
    n = std::stoull(text, &used, 0);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || n > 0xFFFFFFFFull || text[0] == '-')
    throw UsageError("--serial-number " + text + ": must be an integer 0..4294967295 (or 0x...)");
  return static_cast<uint32_t>(n);
}

// --node-id: one id, none (255), or a list of ids and ranges (node/node_id_list.hpp).
void apply_node_id_argument(const std::string& text, NodeConfig& cfg) {
  if (text == "none" || text == "255") {
    // The command line gives none: an id stored over LSS, else the config file's, applies.
    if (cfg.options.node_id_origin == NodeIdOrigin::CommandLine) {
      cfg.options.device.node_id = lss::kUnconfigured;
      cfg.options.node_id_origin = NodeIdOrigin::None;
      cfg.node_ids.clear();
    }
    return;
  }
  std::vector<uint8_t> ids;
  try {
    ids = parse_node_id_list(text);
  } catch (const std::invalid_argument& e) {
    throw UsageError("--node-id " + text + ": " + e.what() +
                     "; must be 1..127, none (255), or a list such as 1-32 or 1,5,10-12");
  }
  cfg.options.device.node_id = ids.front();
  cfg.options.node_id_origin = NodeIdOrigin::CommandLine;
  if (ids.size() == 1) ids.clear();
  cfg.node_ids = ids;
}

// Node k of a set has serial number + k (its own LSS address): all must fit UNSIGNED32.
void check_serial_numbers(const NodeConfig& cfg) {
  if (cfg.node_ids.empty()) return;
  const uint64_t last = uint64_t{cfg.options.device.serial_number} + cfg.node_ids.size() - 1;
  if (last > 0xFFFFFFFFull)
    throw UsageError("--serial-number " + std::to_string(cfg.options.device.serial_number) +
                     ": the " + std::to_string(cfg.node_ids.size()) +
                     " nodes get serial numbers up to " + std::to_string(last) +
                     ", above 4294967295");
}

void apply_boot_listen_argument(int64_t ms, NodeConfig& cfg) {
  if (ms < 0 || ms > kMaxBootListenMs)
    throw UsageError("--boot-listen-ms " + std::to_string(ms) + ": must be 0..60000");
  cfg.options.boot_listen_us = static_cast<uint64_t>(ms) * 1000;
}

}  // namespace

NodeConfig parse_command_line(int argc, char** argv, bool& exit_now, int& exit_code) {
  NodeConfig cfg;
  exit_now = false;
  CLI::App app{"stepnode: a CANopen (CiA 301) stepper-motion node on a SocketCAN interface"};
  std::string config_file;
  std::string state_dir;
  std::string node_id;
  std::string serial_number;
  int64_t boot_listen_ms = 0;
  int64_t tick_us = 0;
  bool apply_bit_timing = false;
  app.add_option("--iface", cfg.iface, "SocketCAN interface, e.g. can0 or vcan0");
  app.add_option("--node-id", node_id,
                 "CANopen node id, 1..127, or none (255): no id, the node waits for an LSS master "
                 "(an id an LSS master stored is used then, else the config file's); or a "
                 "list such as 1-32 or 1,5,10-12: one node per id in this process");
  app.add_option(
      "--serial-number", serial_number,
      "serial number in the identity object 0x1018 sub 4 (the LSS address), e.g. 7 or 0x1A2B");
  app.add_option("--config", config_file, "TOML config file (see README)");
  app.add_option("--state-dir", state_dir, "where stored parameters (0x1010) are kept");
  app.add_option("--tick-us", tick_us,
                 "the longest the node sleeps between its deadlines, in microseconds "
                 "(100..10000000, default 1000000)");
  app.add_option("--log-level", cfg.log_level, "trace, debug, info, warn, error, off");
  app.add_option("--boot-listen-ms", boot_listen_ms,
                 "listen this long for another device with the node-ID before the boot-up; "
                 "one heard: no boot-up, the node waits for LSS (0..60000, default 0: boot at "
                 "once, yield within 2 s)");
  app.add_flag("--print-eds", cfg.print_eds, "print the device's EDS (CiA 306) and exit");
  app.add_flag("--apply-bit-timing", apply_bit_timing,
               "set the interface's bit rate to the LSS bit timing (at start and on LSS activate "
               "bit timing; needs CAP_NET_ADMIN)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    exit_now = true;
    exit_code = app.exit(e);
    return cfg;
  } catch (const CLI::ParseError& e) {
    throw UsageError(e.what());
  }
  bool id_known = app.count("--node-id") > 0;
  if (!config_file.empty()) {
    // "--node-id none" gives no id: the config file's applies (after one stored over LSS).
    const bool id_given = id_known && node_id != "none" && node_id != "255";
    id_known |= load_config_file(config_file, cfg,
                                 {!cfg.iface.empty(), id_given, !state_dir.empty(),
                                  app.count("--tick-us") > 0, app.count("--log-level") > 0});
  }
  if (app.count("--node-id")) apply_node_id_argument(node_id, cfg);
  if (app.count("--serial-number"))
    cfg.options.device.serial_number = parse_serial_number(serial_number);
  check_serial_numbers(cfg);
  if (apply_bit_timing) cfg.apply_bit_timing = true;  // over the file's
  if (app.count("--boot-listen-ms")) apply_boot_listen_argument(boot_listen_ms, cfg);
  if (!state_dir.empty()) {
    cfg.options.state_dir = state_dir;
    cfg.state_dir_given = true;
  }
  // Only where none was given: "." given is the current directory.
  if (!cfg.state_dir_given) cfg.options.state_dir = default_state_dir();
  if (app.count("--tick-us")) {
    if (tick_us < 100 || tick_us > 10'000'000)
      throw UsageError("--tick-us " + std::to_string(tick_us) + ": must be 100..10000000");
    cfg.tick_us = static_cast<uint64_t>(tick_us);
  }
  static const char* levels[] = {"trace", "debug", "info", "warn", "error", "critical", "off"};
  if (std::find(std::begin(levels), std::end(levels), cfg.log_level) == std::end(levels))
    throw UsageError("--log-level " + cfg.log_level +
                     ": must be one of trace, debug, info, warn, error, critical, off");
  if (cfg.print_eds) return cfg;
  if (cfg.iface.empty()) throw UsageError("--iface is required (e.g. --iface vcan0)");
  if (!id_known)
    throw UsageError("--node-id is required (1..127, or none for a node an LSS master configures)");
  return cfg;
}

}  // namespace stepnode::node
