#include "node/sim/machine.hpp"

namespace stepnode::sim {
namespace {

int64_t floor_div(int64_t a, int64_t b) {
  int64_t q = a / b;
  return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

int64_t floor_mod(int64_t a, int64_t b) { return a - floor_div(a, b) * b; }

}  // namespace

void AxisMachine::step(motion::Tick time, int direction) {
  ++pulses_;
  last_step_time_ = time;
  if (trace_) [[unlikely]] record(time, direction);
  if (!powered_) return;  // no torque: the pulse is lost
  if (config_.miss_every && pulses_ % config_.miss_every == 0) return;  // lost pulse
  if (config_.move_every && pulses_ % config_.move_every != 0) return;  // slipping
  int64_t next = position_ + (direction >= 0 ? 1 : -1);
  if (config_.stall_above && next > *config_.stall_above) return;  // jammed
  if (config_.stall_below && next < *config_.stall_below) return;
  position_ = next;
}

// Out of line: the hot path of step() stays as small as it was without a trace.
__attribute__((noinline)) void AxisMachine::record(motion::Tick time, int direction) {
  trace_->push_back({time, direction >= 0 ? +1 : -1});
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
