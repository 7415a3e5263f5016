#include "node/sim/machine.hpp"

#include <algorithm>
#include <limits>

namespace stepnode::sim {
namespace {

int64_t floor_div(int64_t a, int64_t b) {
  int64_t q = a / b;
  return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

int64_t floor_mod(int64_t a, int64_t b) { return a - floor_div(a, b) * b; }

}  // namespace

AxisMachine::AxisMachine(AxisMachineConfig config) : config_(config) {
  reported_ = sensed();
  find_steady_range();
  changed_ = false;
  update_faulty();
}

void AxisMachine::queue_pulse(motion::Tick time, const motion::OutputPulse& p) {
  steps_.push(time, motion::direction_of(p));
  if (p.width_ns) widths_.push_back({time, p.width_ns});
}

void AxisMachine::flush(motion::Tick until) {
  while (steps_.due(until)) {
    motion::StepQueue::Entry e = steps_.pop();
    uint32_t width = 0;
    if (!widths_.empty() && widths_.front().time == e.time) {
      width = widths_.front().width_ns;
      widths_.pop_front();
    }
    move(e.time, e.direction, width);
  }
  clock_ = std::max(clock_, until);
}

void AxisMachine::cancel_after(motion::Tick after) {
  steps_.cancel_after(after);
  while (!widths_.empty() && widths_.back().time > after) widths_.pop_back();
}

void AxisMachine::update_faulty() {
  faulty_ = config_open_ || !powered_ || config_.miss_every || config_.move_every ||
            config_.stall_above || config_.stall_below;
}

void AxisMachine::move_with_faults(motion::Tick time, int direction) {
  if (config_open_) {  // config() was called: look at the faults again from this step on
    config_open_ = false;
    update_faulty();
  }
  if (!powered_) return;  // no torque: the pulse is lost
  if (config_.miss_every && pulses_ % config_.miss_every == 0) return;  // lost pulse
  if (config_.move_every && pulses_ % config_.move_every != 0) return;  // slipping
  int64_t next = position_ + direction;
  if (config_.stall_above && next > *config_.stall_above) return;  // jammed
  if (config_.stall_below && next < *config_.stall_below) return;
  position_ = next;
  if (position_ < steady_low_ || position_ > steady_high_) [[unlikely]]
    sense(time);
}

// Out of line: the hot path of move() stays as small as it was without a trace.
__attribute__((noinline)) void AxisMachine::record(motion::Tick time, int direction,
                                                   uint32_t width_ns) {
  const int d = direction >= 0 ? +1 : -1;
  if (trace_) trace_->push_back({time, d});
  if (pulse_trace_) pulse_trace_->push_back({time, d, width_ns});
}

motion::InputLevels AxisMachine::sensed() const {
  using motion::Input;
  motion::InputLevels l;
  l.set(Input::Home, home());
  l.set(Input::LowerLimit, lower_limit());
  l.set(Input::UpperLimit, upper_limit());
  l.set(Input::Index, index());
  l.set(Input::Marker, marker());
  l.set(Input::EmergencyStop, estop_);
  l.set(Input::Halt, halt_high_);
  return l;
}

void AxisMachine::sense(motion::Tick time) {
  const motion::InputLevels now = sensed();
  const uint8_t changed = now.active ^ reported_.active;
  for (uint8_t bit = 1; bit != 0 && bit <= changed; bit = static_cast<uint8_t>(bit << 1))
    if (changed & bit) {
      const auto input = static_cast<motion::Input>(bit);
      edges_.push_back({time, input, now.is(input)});
      edges_waiting_ = true;
    }
  reported_ = now;
  find_steady_range();
}

void AxisMachine::find_steady_range() {
  // The positions around the present one at which no switch of the position changes:
  // within them a step needs no look at the inputs.
  int64_t low = std::numeric_limits<int64_t>::min(), high = std::numeric_limits<int64_t>::max();
  const int64_t p = position_;
  auto cam = [&](const std::optional<Cam>& c) {
    if (!c) return;
    if (c->contains(p)) {
      low = std::max(low, c->position);
      high = std::min(high, c->position + c->width - 1);
    } else if (p < c->position) {
      high = std::min(high, c->position - 1);
    } else {
      low = std::max(low, c->position + c->width);
    }
  };
  cam(config_.home);
  cam(config_.index);
  if (config_.lower_limit) {
    if (p <= *config_.lower_limit) high = std::min(high, *config_.lower_limit);
    else low = std::max(low, *config_.lower_limit + 1);
  }
  if (config_.upper_limit) {
    if (p >= *config_.upper_limit) low = std::max(low, *config_.upper_limit);
    else high = std::min(high, *config_.upper_limit - 1);
  }
  const int64_t rev = config_.steps_per_rev;
  if (config_.encoder == EncoderKind::Quadrature && rev > 0 && config_.marker_width > 0 &&
      config_.marker_width < rev) {
    const int64_t into = floor_mod(p - config_.marker_offset, rev), begin = p - into;
    if (into < config_.marker_width) {
      low = std::max(low, begin);
      high = std::min(high, begin + config_.marker_width - 1);
    } else {
      low = std::max(low, begin + config_.marker_width);
      high = std::min(high, begin + rev - 1);
    }
  }
  steady_low_ = low;
  steady_high_ = high;
}

bool AxisMachine::next_edge(motion::InputEdge& edge) {
  if (changed_) {  // a change from outside: look at every input now
    changed_ = false;
    sense(clock_);
  }
  if (edges_.empty()) {
    edges_waiting_ = false;
    return false;
  }
  edge = edges_.front();
  edges_.pop_front();
  return true;
}

int64_t AxisMachine::encoder_counts_per_rev() const {
  switch (config_.encoder) {
    case EncoderKind::None: return 0;
    case EncoderKind::UpDown: return config_.encoder_lines;
    default: return config_.encoder_lines * 4;
  }
}

int64_t AxisMachine::encoder_count() const {
  int64_t per_rev = encoder_counts_per_rev();
  if (per_rev == 0 || config_.steps_per_rev <= 0) return 0;
  return floor_div(position_ * per_rev, config_.steps_per_rev);
}

bool AxisMachine::marker() const {
  if (config_.encoder != EncoderKind::Quadrature || config_.steps_per_rev <= 0) return false;
  return floor_mod(position_ - config_.marker_offset, config_.steps_per_rev) < config_.marker_width;
}

}  // namespace stepnode::sim
