// `stepctl hp "..."`: the HP 44714A manual's command words (chapter 3 and the Command
// Summary) translated into writes and reads of the node's HP channel objects (0x2n10..).
// Pure: words in, a plan of object accesses out; hp_command.cpp runs the plan on the bus.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "od/data_type.hpp"
#include "od/value_codec.hpp"

namespace stepnode::tools {

struct HpAccess {
  enum Kind { Write, Read, WaitWhileRunning } kind = Write;
  uint16_t index = 0;
  uint8_t sub = 0;
  od::Bytes data;                               // Write
  od::DataType type = od::DataType::Unsigned8;  // Read: how to print it
  std::string label;                            // Read: what the answer is ("POS?")
};

// One command ("MOVE 20 NOWAIT") or several separated by ';'. `channel` is the HP channel
// (0 = the node's axis 1). Throws std::invalid_argument naming the word and the rule.
std::vector<HpAccess> plan_hp_words(const std::string& text, unsigned channel);

// The manual's text for an error number (3-3) and a conflict row (3-9, 3-26), and for a
// DONE? code (3-19).
std::string hp_error_text(unsigned number);
std::string hp_conflict_text(unsigned row);
std::string hp_done_text(int code);

}  // namespace stepnode::tools
