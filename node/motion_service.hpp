// Connects the axes and the simulated machine to the object dictionary: command bits and
// words written over SDO or RPDO act on the axes at once; status, positions and velocity
// are published back into the dictionary (and so into the TPDOs) after every advance.
// Axis errors raise an EMCY (manufacturer code 0xFF00 + axis number) until cleared.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "node/emcy.hpp"
#include "node/motion/axis.hpp"
#include "node/refused_words.hpp"
#include "node/sim/machine.hpp"
#include "node/device_objects.hpp"
#include "od/dictionary.hpp"

namespace stepnode::node {

class MotionService {
 public:
  MotionService(od::Dictionary& dictionary, const DeviceLayout& layout, EmcyProducer& emcy);

  // Brings every axis up to `now_us` (CLOCK_MONOTONIC or virtual) and publishes.
  void advance(uint64_t now_us);
  // The same without publishing, for a caller that acts on the axes and then advances.
  void advance_axes(uint64_t now_us);
  // Power-up / NMT reset node: axes back to the power-up state, settings reloaded.
  void power_up(uint64_t now_us);
  // Heartbeat consumer timeout: every moving axis ramps down, %I8 latches.
  void master_lost(uint64_t now_us);

  motion::Axis& axis(unsigned n) { return *axes_.at(n); }
  sim::Machine& machine() { return machine_; }
  motion::Tick ticks(uint64_t now_us) const;
  // The node clock's microsecond of a tick, to the nearest (so micros(ticks(us)) == us).
  uint64_t micros(motion::Tick t) const {
    uint64_t u = static_cast<uint64_t>(t);
    return epoch_us_ + u / 3072 * 625 + (u % 3072 * 625 + 1536) / 3072;
  }

 private:
  void install_hooks();
  void load_words(unsigned a);
  void load_config(unsigned a);
  void load_machine(unsigned motor);
  void publish(unsigned a);
  void publish_motor(unsigned motor);
  void on_axis_event(unsigned a, const motion::AxisEvent& event);

  od::Dictionary& dictionary_;
  EmcyProducer& emcy_;
  unsigned count_;   // axes (register blocks)
  unsigned motors_;  // simulated motors (3 behind one axis in SPM30 multiplexed mode)
  sim::Machine machine_;
  std::vector<std::unique_ptr<motion::Axis>> axes_;
  std::vector<std::unique_ptr<RefusedWords>> refused_words_;  // RPDO words the dictionary refused
  uint64_t epoch_us_ = 0;
  bool epoch_set_ = false;
  uint64_t now_us_ = 0;
};

}  // namespace stepnode::node
