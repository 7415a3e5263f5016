// `stepcalc cia402 DISTANCE ...`: the command line of the CiA 402 calculator.
#pragma once

namespace stepnode::tools {

// argv[0] is "cia402". Returns the exit status (2: bad input, one line; 1: a plot that
// could not be written).
int run_cia402(int argc, char** argv);

}  // namespace stepnode::tools
