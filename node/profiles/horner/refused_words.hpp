// Command words that arrived in an RPDO with a value the dictionary refused.
//
// Over SDO a master writing DESTINATION = 8,388,608 gets a range abort and knows. A PDO has
// no answer, and the module keeps whatever the PLC put in its registers: the next command
// finds a word no move can be made of and is an Illegal Move (SPM30 3.4, B1.2). So a
// refused RPDO value is remembered here and shown to the axis in place of the stored one
// until a valid value for that word is written (by SDO or PDO) or the node powers up.
#pragma once
#include <cstdint>
#include <map>

#include "node/motion/axis_registers.hpp"
#include "od/dictionary.hpp"

namespace stepnode::node {

class RefusedWords {
 public:
  // Hooks the word entries of axis `a` (0-based): destination, profile, indexed move.
  RefusedWords(od::Dictionary& dictionary, unsigned a);

  // The axis' words with every refused value in place of the stored one.
  void overlay(motion::CommandWords& words) const;
  void clear() { refused_.clear(); }
  bool empty() const { return refused_.empty(); }

 private:
  void watch(od::Entry& entry);

  unsigned axis_;
  std::map<uint32_t, uint64_t> refused_;  // (index << 8 | sub) -> raw little-endian value
};

}  // namespace stepnode::node
