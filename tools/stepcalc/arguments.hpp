// stepcalc's positional arguments (TOTAL AQ3 AQ4 AQ5 AQ6 AQ7) as text -> an STPCALC input.
#pragma once
#include <string>
#include <vector>

#include "node/motion/stpcalc.hpp"

namespace stepnode::tools {

// TOTAL is 0..16777215 or "-" (a move without destination, B1.2.1); the AQ words are
// integers. Throws std::invalid_argument naming the input and its legal range (SPM30 3.4,
// B1.2). The ranges that depend on other registers are checked by motion::stpcalc().
motion::StpcalcInput parse_input(const std::string& total, const std::vector<std::string>& aq);

}  // namespace stepnode::tools
