// `stepctl hp "WORDS" --node N --axis CH`: runs the plan of hp_words.hpp on the bus, prints
// the answers of queries, and explains a refusal with the channel's error number or
// PROFILE conflict as the manual words it.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "tools/stepctl/hp_words.hpp"
#include "tools/stepctl/master_bus.hpp"

namespace stepnode::tools {

// Returns the exit status (0, or 1 when the node refused). Throws std::invalid_argument
// for words that are not the manual's (exit 2).
int run_hp_command(MasterBus& bus, int node, unsigned channel, const std::string& words,
                   int wait_timeout_s);
// The same for a plan already made; `idle` (if given) runs after each access and every
// 20 ms while a command without NOWAIT completes (a program's interrupts are looked at there).
int run_hp_plan(MasterBus& bus, int node, unsigned channel, const std::vector<HpAccess>& plan,
                int wait_timeout_s, const std::function<void()>& idle);

// `stepctl hp --program FILE` (hp_program.hpp): the listing checked first (exit 2 before
// anything is sent), then run. Returns 0, or 1 when the node refused a command.
int run_hp_program(MasterBus& bus, int node, unsigned channel, const std::string& listing,
                   int wait_timeout_s);
// The check alone (before the bus is opened): throws std::invalid_argument naming the line.
void check_hp_program(const std::string& listing, unsigned channel);

}  // namespace stepnode::tools
