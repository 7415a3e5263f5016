// `stepctl hp "WORDS" --node N --axis CH`: runs the plan of hp_words.hpp on the bus, prints
// the answers of queries, and explains a refusal with the channel's error number or
// PROFILE conflict as the manual words it.
#pragma once
#include <string>

#include "tools/stepctl/master_bus.hpp"

namespace stepnode::tools {

// Returns the exit status (0, or 1 when the node refused). Throws std::invalid_argument
// for words that are not the manual's (exit 2).
int run_hp_command(MasterBus& bus, int node, unsigned channel, const std::string& words, int wait_timeout_s);

}  // namespace stepnode::tools
