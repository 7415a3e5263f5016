// The simulated machine behind the step outputs: per axis a motor that follows steps
// (unless a fault says otherwise), switches and an encoder that are pure functions of the
// mechanical position, so the engine knows the exact step at which any input changes.
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include "node/motion/encoder_kind.hpp"
#include "node/motion/motor_port.hpp"

namespace stepnode::sim {

// A switch active while the mechanical position is inside [position, position + width).
struct Cam {
  int64_t position = 0;
  int64_t width = 1;
  bool contains(int64_t p) const { return p >= position && p < position + width; }
};

using EncoderKind = motion::EncoderKind;

struct AxisMachineConfig {
  std::optional<Cam> home;               // home switch
  std::optional<Cam> index;              // index input (indexed moves)
  std::optional<int64_t> lower_limit;    // active at or below this position
  std::optional<int64_t> upper_limit;    // active at or above this position
  int64_t steps_per_rev = 2000;          // motor steps (or microsteps) per revolution
  int64_t encoder_lines = 500;           // encoder lines per revolution
  EncoderKind encoder = EncoderKind::Quadrature;
  int64_t marker_offset = 0;             // marker once per revolution, at this offset...
  int64_t marker_width = 4;              // ...and this many steps wide
  // Faults.
  std::optional<int64_t> stall_below, stall_above;  // the motor cannot pass these positions
  uint32_t miss_every = 0;               // every n-th step is lost (0 = none)
  uint32_t move_every = 0;               // a slipping motor: only every n-th step moves it
};

// One step pulse as the drive received it: its tick and direction (+1 / -1).
struct TracedStep {
  motion::Tick time;
  int direction;
  bool operator==(const TracedStep&) const = default;
};

class AxisMachine : public motion::MotorPort {
 public:
  explicit AxisMachine(AxisMachineConfig config = {}) : config_(config) {}

  // One step pulse from the drive (+1 up, -1 down). The motor follows unless stalled or
  // the pulse is one of the missed ones.
  void step(motion::Tick time, int direction) override;
  void step(int direction) { step(last_step_time_, direction); }
  // External force: the load moved without steps.
  void displace(int64_t steps) { position_ += steps; }
  // Motor power (the drive's standby input): an unpowered motor holds no torque, so a
  // pulse it receives moves nothing (HP 44714A STANDBY ON, 3-13).
  void set_powered(bool powered) { powered_ = powered; }
  bool powered() const { return powered_; }

  int64_t position() const { return position_; }
  bool home() const override { return config_.home && config_.home->contains(position_); }
  bool index() const override { return config_.index && config_.index->contains(position_); }
  bool lower_limit() const override { return config_.lower_limit && position_ <= *config_.lower_limit; }
  bool upper_limit() const override { return config_.upper_limit && position_ >= *config_.upper_limit; }
  bool marker() const override;
  // Encoder counts as the input hardware sees them: every edge of A and B for quadrature
  // (4 per line; the module decides how many it counts), 1 per line for up/down; 0 without.
  int64_t encoder_count() const override;
  int64_t encoder_counts_per_rev() const;
  uint64_t pulses_received() const { return pulses_; }
  // Appends every step pulse received from now on to `trace` (nullptr: stop). The golden
  // step-train test records the engine's output through this.
  void trace_into(std::vector<TracedStep>* trace) { trace_ = trace; }
  motion::Tick last_step_time() const { return last_step_time_; }

  AxisMachineConfig& config() { return config_; }
  const AxisMachineConfig& config() const { return config_; }

 private:
  AxisMachineConfig config_;
  int64_t position_ = 0;
  uint64_t pulses_ = 0;
  motion::Tick last_step_time_ = 0;
  bool powered_ = true;
  std::vector<TracedStep>* trace_ = nullptr;
  void record(motion::Tick time, int direction);
};

// The whole machine: the axes and the inputs they share.
struct Machine {
  std::vector<AxisMachine> axes;
  bool emergency_stop = false;  // the e-stop input is active
};

}  // namespace stepnode::sim
