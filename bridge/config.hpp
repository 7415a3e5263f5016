// stepbridge's settings: command line (CLI11) over a TOML config file with the same keys.
#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "bridge/dds/security.hpp"
#include "bridge/observer/bus_observer.hpp"
#include "config/toml_file.hpp"

namespace stepnode::bridge {

struct BridgeConfig {
  std::string iface;
  uint32_t domain = 0;
  bool ros2 = false;
  std::string ros2_prefix = "stepnode";
  std::string profiles;  // Fast DDS XML profiles file
  std::string log_level = "info";
  uint32_t tick_ms = 10;              // observer timers (SDO timeouts, heartbeat loss, health)
  uint32_t heartbeat_timeout_ms = 0;  // 0: 3 x the node's heartbeat interval, min 1000
  uint32_t sdo_timeout_ms = 500;
  // SDO server channels of the bridge's own, one per node (--sdo-channel NODE:RX,TX or the
  // [sdo_channels] table); other nodes are read on their default channel, when it is quiet.
  std::vector<NodeSdoChannel> sdo_channels;
  // The bridge's SDO reads on the whole bus (issue 13): in flight at once, starts a second.
  uint32_t sdo_max_outstanding = 8;
  uint32_t sdo_rate_per_s = 1000;
  // timestamps = "network": samples stamped on the bus's TIME (COB-ID 0x100) once one was
  // seen; "host" (default): the host clock's kernel timestamps.
  bool network_time = false;
  // [dds.security]: the DDS Security files (README "DDS Security"); only in the config file.
  dds::SecurityFiles dds_security;
};

// "5:0x685,0x6C5": node 5's channel, client->server and server->client COB-IDs. Throws
// UsageError naming the rule.
NodeSdoChannel parse_sdo_channel(const std::string& text);

// Bad input: the message is the one line printed before exiting with status 2.
using config::UsageError;

// Parses the command line and the --config file (the command line wins). `exit_now` is set
// for --help (exit_code 0). Throws UsageError.
BridgeConfig parse_bridge_command_line(int argc, char** argv, bool& exit_now, int& exit_code);

}  // namespace stepnode::bridge
