// `stepctl drive ...`: CiA 402 device control and the profile modes over SDO, on axis n's
// objects (index + 0x800 * (n - 1)): status in the standard's words, enable / disable /
// quick-stop / fault-reset through the controlword steps of drive_words.hpp, checked in
// 6041h, and profile position (pp), profile velocity (pv) and homing (home) with a live
// progress line.
#pragma once
#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <string>

#include "tools/stepctl/master_bus.hpp"
#include "tools/stepctl/object_catalog.hpp"

namespace stepnode::tools {

struct DriveArgs {
  std::string verb;  // status, enable, disable, quick-stop, fault-reset, pp, pv, home
  int node = -1;
  int axis = 1;  // 1..8
  bool quiet = false;
  bool no_wait = false;
  int wait_s = 120;  // motion (and stop ramps): give up after this many s
  // pp TARGET (6064h position units) / pv VELOCITY (velocity units)
  int64_t target = 0;
  bool relative = false, immediate = false;
  std::optional<int64_t> velocity, acceleration, deceleration;  // 6081h, 6083h, 6084h
  // home: 6098h, 6099h:1, 6099h:2, 609Ah (--acceleration), 607Ch
  std::optional<int> method;
  std::optional<int64_t> switch_speed, zero_speed, home_offset;
};

// Adds `drive` and its subcommands to `app`; the parsed words go to `args` (drive_options.cpp).
CLI::App* add_drive_command(CLI::App& app, DriveArgs& args);

// Returns the exit status (0, or 1 for a status with a fault). Throws std::runtime_error when
// the node refused or the drive did not do what it was told (exit 1), std::invalid_argument
// for what this node cannot be asked (exit 2: homing on a node without it).
int run_drive_command(MasterBus& bus, const ObjectCatalog& catalog, const DriveArgs& args);

}  // namespace stepnode::tools
