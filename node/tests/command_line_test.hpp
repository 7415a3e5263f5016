// The node's command line as a test gives it: `parse` (the arguments after the program
// name), `error_of` (a UsageError expected: its one-line message) and `config` (a TOML file
// in a temporary directory). The config and multi-node tests share it.
#pragma once
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "node/config.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {

class CommandLineTest : public ::testing::Test {
 protected:
  NodeConfig parse(std::vector<std::string> args) {
    std::vector<char*> argv;
    std::string prog = "stepnode";
    argv.push_back(prog.data());
    args.insert(args.begin(), base_args.begin(), base_args.end());
    for (auto& a : args) argv.push_back(a.data());
    return parse_command_line(static_cast<int>(argv.size()), argv.data(), exit_now, exit_code);
  }
  // Parses and expects a UsageError; returns its message.
  std::string error_of(std::vector<std::string> args) {
    try {
      parse(std::move(args));
    } catch (const UsageError& e) {
      std::string msg = e.what();
      EXPECT_EQ(msg.find('\n'), std::string::npos) << "not one line: " << msg;
      EXPECT_FALSE(msg.empty());
      return msg;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "not a UsageError: " << e.what();
      return {};
    }
    ADD_FAILURE() << "no error";
    return {};
  }
  std::string config(const std::string& text) {
    std::filesystem::path p = dir.path / ("c" + std::to_string(++files) + ".toml");
    std::ofstream(p) << text;
    return p.string();
  }
  static bool has(const std::string& msg, const std::string& part) {
    return msg.find(part) != std::string::npos;
  }

  std::vector<std::string> base_args;  // given before every test's own arguments
  TempDir dir;
  int files = 0;
  bool exit_now = false;
  int exit_code = -1;
};

}  // namespace stepnode::node::test
