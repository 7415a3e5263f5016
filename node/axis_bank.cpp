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
      motors = {machine_.axes.data(), &machine_.axes[1], &machine_.axes[2]};  // SPM30: 3 motors
    cores_.push_back(std::make_unique<motion::AxisCore>(motors));
    axes_.push_back(std::make_unique<motion::Axis>(motion::AxisConfig{}, *cores_.back()));
    axes_.back()->on_event = [this, a](const motion::AxisEvent& e) {
      for (const EventListener& l : listeners_) l(a, e);
    };
  }
}

uint64_t AxisBank::micros_at_or_after(motion::Tick t) const {
  // The first microsecond whose ticks() reaches t: ceil(t * 625 / 3072).
  const uint64_t u = t > 0 ? static_cast<uint64_t>(t) : 0;
  return epoch_us_ + u / 3072 * 625 + (u % 3072 * 625 + 3071) / 3072;
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
    // An idle core waits for a command or an input edge: both come with a frame (a write
    // of the simulated machine's switches advances the axes at once).
    motion::AxisCore& core = *c;
    if (core.busy()) next = earliest(next, core_deadline_us(core, now_us));
  }
  return next;
}

uint64_t AxisBank::core_deadline_us(motion::AxisCore& core, uint64_t now_us) const {
  const auto at = [&](motion::Tick t) { return std::max(micros_at_or_after(t), now_us + 1); };
  uint64_t next = kNoDeadline;
  // A time between steps at which the job changes course (FIND HOME's dwell): exact.
  if (const motion::FrontEnd* owner = core.owner())
    if (const std::optional<motion::Tick> d = owner->deadline()) next = at(*d);
  if (const std::optional<motion::Tick> step = core.next_step_time())
    return earliest(next, std::max(at(*step), now_us + step_wake_us_));
  if (core.moving()) {
    // No step left, but the ramp ends between steps (a stop at base velocity): the core
    // goes idle, and the owner learns of it, at the end the generator computes.
    motion::StepGenerator ahead = core.generator();
    motion::Step none;
    ahead.next(none);
    return earliest(next, at(ahead.marks().end));
  }
  // A job waiting for an input (a move toward an active limit): the input changes with a
  // frame, which advances the axes. A job whose motion ended without its owner told (a wait
  // ended in a frame) is over at the next advance: the conservative poll, as before.
  return core.waiting() ? next : earliest(next, poll_deadline(now_us));
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
