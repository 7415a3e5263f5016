// The node process's settings: command line, optional TOML config file, and defaults for
// dictionary objects. The command line wins over the file.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "config/toml_file.hpp"
#include "node/canopen_node.hpp"

namespace stepnode::node {

struct NodeConfig {
  std::string iface;
  NodeOptions options;  // of the one node, or the first of node_ids
  // --node-id 1-32 (or a config's node_id = "1-32"): every node of the process, ascending
  // (node/node_id_list.hpp gives each its options). Empty: the one node of `options`.
  std::vector<uint8_t> node_ids;
  uint64_t tick_us =
      1'000'000;  // the longest the node sleeps (issue 13: it wakes for its deadlines)
  std::string log_level = "info";
  bool state_dir_given = false;  // options.state_dir from --state-dir or state_dir, not the default
  // Object defaults from the config's [defaults] table: "1017" or "1016:1" -> value text.
  std::vector<std::pair<std::string, std::string>> object_defaults;
  bool print_eds = false;
  // The node sets its interface's bit rate itself (CAP_NET_ADMIN): to the bit timing an LSS
  // master stored, at start, and at an LSS activate bit timing (README, "LSS").
  bool apply_bit_timing = false;
};

// Bad input (an argument, the config file): the process prints "stepnode: <message>" and
// exits with status 2.
using config::UsageError;

// Parses argv (and the config file it names). For --help, sets exit_now and exit_code
// (the text is printed). Throws UsageError with one clear line on bad input.
NodeConfig parse_command_line(int argc, char** argv, bool& exit_now, int& exit_code);

// `text` as one printable line (control bytes as \xNN): the messages stderr gets.
using config::one_line;

// A PDO mapping record the configuration set to something the mapping procedure refuses
// (e.g. "1A00:1" = 0x99990020 names an object this device does not have).
struct RefusedMapping {
  uint16_t index = 0;
  od::SdoAbort reason = od::SdoAbort::None;
};

// Applies object_defaults to the dictionary's default values. Throws UsageError naming the
// object when one does not exist, is not writable or does not fit its type: the file is
// wrong on its face. A mapping record whose entries each fit but which, as a whole, the
// device cannot use keeps its built-in default and is returned: the node starts and says
// so (EMCY 0x6100), as it does for such a stored mapping.
std::vector<RefusedMapping> apply_object_defaults(
    od::Dictionary& od, const std::vector<std::pair<std::string, std::string>>& defaults);

}  // namespace stepnode::node
