// stepctl's axis commands: drive one axis of a stepnode node by name (clear, home, move,
// jog, stop, estop, status) through its register objects, with a live progress line.
#pragma once
#include <string>
#include <vector>

#include "tools/stepctl/master_bus.hpp"

namespace stepnode::tools {

// words: e.g. {"move", "abs", "1000"}, {"home", "up"}, {"jog", "down"}, {"status"}.
// Returns the exit status. Throws std::invalid_argument for bad words (exit 2).
int run_axis_command(MasterBus& bus, int node, int axis, const std::vector<std::string>& words,
                     double jog_seconds, bool quiet);

// "power-up/watchdog error, position valid, at home" for a status word.
std::string status_words(uint16_t status);

}  // namespace stepnode::tools
