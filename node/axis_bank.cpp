#include "node/axis_bank.hpp"

#include <algorithm>

namespace stepnode::node {

AxisBank::AxisBank(const DeviceLayout& layout) {
  machine_.axes.resize(layout.motors());
  // The step port's horizon, in ticks (4.9152 per microsecond, exact).
  const motion::Tick horizon =
      static_cast<motion::Tick>(uint64_t{layout.step_horizon_us} * 3072 / 625);
  for (sim::AxisMachine& m : machine_.axes) m.set_horizon(horizon);
  step_wake_us_ = std::max<uint64_t>(kPollUs, layout.step_horizon_us / 2);
  for (unsigned a = 0; a < layout.axes; ++a) {
    std::vector<motion::MotorPort*> motors{&machine_.axes[a]};
    if (layout.spm30_multiplexed)
      motors = {&machine_.axes[0], &machine_.axes[1], &machine_.axes[2]};
    cores_.push_back(std::make_unique<motion::AxisCore>(motors));
    axes_.push_back(std::make_unique<motion::Axis>(motion::AxisConfig{}, *cores_.back()));
    axes_.back()->on_event = [this, a](const motion::AxisEvent& e) {
      for (const EventListener& l : listeners_) l(a, e);
    };
  }
}

motion::Tick AxisBank::ticks(uint64_t now_us) const {
  // 4.9152 ticks per microsecond = 3072/625, exact in integers.
  uint64_t since = now_us >= epoch_us_ ? now_us - epoch_us_ : 0;
  return static_cast<motion::Tick>(since / 625 * 3072 + since % 625 * 3072 / 625);
}

void AxisBank::advance(uint64_t now_us) {
  if (!epoch_set_) {
    epoch_us_ = now_us;
    epoch_set_ = true;
  }
  now_us_ = now_us;
  for (auto& core : cores_) core->advance_to(ticks(now_us));
}

uint64_t AxisBank::next_deadline_us(uint64_t now_us) {
  uint64_t next = kNoDeadline;
  for (auto& c : cores_) {
    // An idle core waits for a command or an input edge: both come with a frame.
    motion::AxisCore& core = *c;
    if (!core.busy()) continue;
    const std::optional<motion::Tick> step = core.next_step_time();
    next = earliest(next,
                    step ? std::max(micros(*step), now_us + step_wake_us_) : poll_deadline(now_us));
  }
  return next;
}

void AxisBank::power_up(uint64_t now_us) {
  advance(now_us);
  for (auto& core : cores_) core->power_up(ticks(now_us));
  for (auto& axis : axes_) axis->power_up(ticks(now_us));
}

void AxisBank::master_lost(uint64_t now_us) {
  advance(now_us);
  for (auto& axis : axes_) axis->master_lost(ticks(now_us));
}

}  // namespace stepnode::node
