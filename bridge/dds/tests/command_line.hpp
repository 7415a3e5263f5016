// The bridge's command line as a test gives it: the arguments after the program name.
#pragma once
#include <string>
#include <vector>

#include "bridge/config.hpp"

namespace stepnode::bridge::test {

inline BridgeConfig parse_command_line(std::vector<std::string> args) {
  args.insert(args.begin(), "stepbridge");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  bool exit_now = false;
  int exit_code = 0;
  return parse_bridge_command_line(static_cast<int>(argv.size()), argv.data(), exit_now, exit_code);
}

}  // namespace stepnode::bridge::test
