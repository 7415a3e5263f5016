// `stepctl lss ...`: an LSS master (CiA 305 V3.0) on COB-IDs 0x7E5 (master -> slaves) and
// 0x7E4 (slaves -> master). Every request is 8 bytes, the command specifier first, 32-bit
// values little-endian in bytes 1..4, unused bytes 0. Services:
//   switch global waiting|configuration          0x04, no answer
//   switch selective VENDOR PRODUCT REVISION SERIAL   0x40..0x43 -> 0x44
//   configure node-id N | configure bit-timing KBIT   0x11 / 0x13 -> error code
//   activate-bit-timing [--delay MS]             0x15, no answer
//   store                                        0x17 -> error code
//   inquire identity | inquire node-id           0x5A..0x5D / 0x5E
//   fast-scan [--assign FIRST [--store]]         0x51 -> 0x4F, bit by bit (CiA 305 fast scan)
#pragma once
#include <CLI/CLI.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "tools/stepctl/master_bus.hpp"

namespace stepnode::tools {

struct LssArgs {
  std::vector<std::string>
      words;                  // the service and its arguments, e.g. {"configure", "node-id", "6"}
  int delay_ms = 0;           // activate bit timing: the switch delay
  std::optional<int> assign;  // fast scan: give the slaves found node-IDs from this one up
  bool store = false;         // fast scan with --assign: store each configuration
  int scan_timeout_ms = 100;  // fast scan: silence that means "no slave matches"
};

// Adds `lss` to `app` (its words parsed into `args`).
CLI::App* add_lss_command(CLI::App& app, LssArgs& args);

// CiA 305 table 1 (bit timing table 0): the index of a bit rate in kbit/s; none for a rate
// the table does not have.
std::optional<uint8_t> lss_bit_timing_index(unsigned kbit);

// Runs the service. Throws std::invalid_argument for words that are not a service (exit 2)
// and std::runtime_error when no slave answered or the slave refused (exit 1).
int run_lss_command(MasterBus& bus, const LssArgs& args, int timeout_ms);

}  // namespace stepnode::tools
