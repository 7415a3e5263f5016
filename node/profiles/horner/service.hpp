// The Horner profile (SPM30 / STP100 register set) in the node: command bits and words
// written over SDO or RPDO act on the axes at once; status, positions and velocity are
// published back into the objects (and so into the TPDOs); an axis error raises EMCY
// 0xFF00 + axis number until cleared. The objects are node/profiles/horner/objects.*.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "node/axis_bank.hpp"
#include "node/emcy.hpp"
#include "node/profile.hpp"
#include "node/profiles/horner/refused_words.hpp"
#include "od/dictionary.hpp"

namespace stepnode::node {

class HornerService final : public Profile {
 public:
  HornerService(od::Dictionary& dictionary, AxisBank& axes, EmcyProducer& emcy);

  // The configuration objects (0x2n09) into the axes, before they power up.
  void configure(uint64_t now_us) override;
  // The words as stored, refused RPDO words forgotten.
  void power_up(uint64_t now_us) override;
  void publish() override;
  // No timed work of its own: the register front ends run in the axes' advance (AxisBank
  // reports their deadlines) and the words act when written.
  uint64_t next_advance_us(uint64_t) override { return kNoDeadline; }

 private:
  void install_hooks();
  void load_words(unsigned a);
  void load_config(unsigned a);
  void publish(unsigned a);
  void on_axis_event(unsigned a, const motion::AxisEvent& event);

  od::Dictionary& dictionary_;
  AxisBank& axes_;
  EmcyProducer& emcy_;
  std::vector<std::unique_ptr<RefusedWords>> refused_words_;  // RPDO words the dictionary refused
};

}  // namespace stepnode::node
