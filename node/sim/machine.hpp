// The simulated machine behind the step outputs: per axis a motor that follows steps
// (unless a fault says otherwise), switches and an encoder that are pure functions of the
// mechanical position, so the engine knows the exact step at which any input changes.
#pragma once
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "node/motion/encoder_kind.hpp"
#include "node/motion/motor_port.hpp"
#include "node/motion/step_queue.hpp"

namespace stepnode::sim {

// A switch active while the mechanical position is inside [position, position + width).
struct Cam {
  int64_t position = 0;
  int64_t width = 1;
  bool contains(int64_t p) const { return p >= position && p < position + width; }
};

using EncoderKind = motion::EncoderKind;

struct AxisMachineConfig {
  std::optional<Cam> home;             // home switch
  std::optional<Cam> index;            // index input (indexed moves)
  std::optional<int64_t> lower_limit;  // active at or below this position
  std::optional<int64_t> upper_limit;  // active at or above this position
  int64_t steps_per_rev = 2000;        // motor steps (or microsteps) per revolution
  int64_t encoder_lines = 500;         // encoder lines per revolution
  EncoderKind encoder = EncoderKind::Quadrature;
  int64_t marker_offset = 0;  // marker once per revolution, at this offset...
  int64_t marker_width = 4;   // ...and this many steps wide
  // Faults.
  std::optional<int64_t> stall_below, stall_above;  // the motor cannot pass these positions
  uint32_t miss_every = 0;                          // every n-th step is lost (0 = none)
  uint32_t move_every = 0;  // a slipping motor: only every n-th step moves it
};

// One step pulse as the drive received it: its tick and direction (+1 / -1).
struct TracedStep {
  motion::Tick time;
  int direction;
  bool operator==(const TracedStep&) const = default;
};

// One pulse as the drive received it, with its width in ns (0: given without one).
struct TracedPulse {
  motion::Tick time;
  int direction;
  uint32_t width_ns;
  bool operator==(const TracedPulse&) const = default;
};

class AxisMachine : public motion::MotorPort {
 public:
  explicit AxisMachine(AxisMachineConfig config = {});

  // --- The step port (motion::StepPort) --------------------------------------------
  // Steps are queued up to `horizon` ticks ahead of their time (0, the default: each is
  // given as it falls due) and move the motor when the core flushes them.
  motion::Tick horizon() const override { return horizon_; }
  void set_horizon(motion::Tick ticks) { horizon_ = ticks; }
  void queue(motion::Tick time, int direction) override { steps_.push(time, direction); }
  // A pulse given as output signals: the drive follows the direction the outputs say, and
  // the machine records the pulse's width (HP 44714A WIDTH mode, 3-25..3-27).
  void queue_pulse(motion::Tick time, const motion::OutputPulse& p) override;
  void flush(motion::Tick until) override;
  void cancel_after(motion::Tick after) override;
  std::optional<int64_t> position_at(motion::Tick time) const override {
    return steps_.position_at(time);
  }
  std::size_t queued() const { return steps_.queued(); }

  // One step pulse from the drive at its time (+1 up, -1 down). The motor follows unless
  // stalled or the pulse is one of the missed ones.
  void step(motion::Tick time, int direction) override {
    const int d = direction >= 0 ? +1 : -1;
    steps_.went_out(time, d);
    move(time, d);
  }
  void step(int direction) { step(clock_, direction); }
  // External force: the load moved without steps.
  void displace(int64_t steps) {
    position_ += steps;
    changed_ = edges_waiting_ = true;
  }
  // Motor power (the drive's standby input): an unpowered motor holds no torque, so a
  // pulse it receives moves nothing (HP 44714A STANDBY ON, 3-13).
  void set_powered(bool powered) {
    powered_ = powered;
    update_faulty();
  }
  bool powered() const { return powered_; }

  // --- The inputs (motion::InputPort) ----------------------------------------------
  // Edges carry the tick of the step that moved the load across a switch's edge; a change
  // made from outside (a switch moved, the load displaced, the e-stop pressed) carries the
  // back end's clock, the latest flush or step.
  motion::InputLevels levels() override { return sensed(); }
  bool next_edge(motion::InputEdge& edge) override;
  int64_t position() const { return position_; }
  bool home() const { return config_.home && config_.home->contains(position_); }
  bool index() const { return config_.index && config_.index->contains(position_); }
  bool lower_limit() const { return config_.lower_limit && position_ <= *config_.lower_limit; }
  bool upper_limit() const { return config_.upper_limit && position_ >= *config_.upper_limit; }
  bool marker() const;
  // The e-stop input (the machine's, shared by its axes: Machine::set_emergency_stop) and
  // the HALT switch input's level (HIGH: open, pulled up).
  void set_emergency_stop(bool active) {
    estop_ = active;
    changed_ = edges_waiting_ = true;
  }
  bool emergency_stop() const { return estop_; }
  void set_halt_input(bool high) {
    halt_high_ = high;
    changed_ = edges_waiting_ = true;
  }
  bool halt_input_high() const { return halt_high_; }
  // Encoder counts as the input hardware sees them: every edge of A and B for quadrature
  // (4 per line; the module decides how many it counts), 1 per line for up/down; 0 without.
  int64_t encoder_count() const override;
  bool has_encoder() const override {
    return encoder_counts_per_rev() > 0 && config_.steps_per_rev > 0;
  }
  int64_t encoder_counts_per_rev() const;
  uint64_t pulses_received() const { return pulses_; }
  // The width of the last pulse received (ns): 0 for a step given without one (a step
  // sink, a Horner or CiA 402 job).
  uint32_t last_pulse_width_ns() const { return last_width_ns_; }
  // Appends every step pulse received from now on to `trace` (nullptr: stop). The golden
  // step-train test records the engine's output through this.
  void trace_into(std::vector<TracedStep>* trace) {
    trace_ = trace;
    tracing_ = trace_ || pulse_trace_;
  }
  // The same with each pulse's width (the outputs as a scope would see them).
  void trace_pulses_into(std::vector<TracedPulse>* trace) {
    pulse_trace_ = trace;
    tracing_ = trace_ || pulse_trace_;
  }
  motion::Tick last_step_time() const { return last_step_time_; }

  // The configuration; changing it through here is a change of the inputs from outside.
  // The switches are looked at again at the next input read, the faults at the next step:
  // the reference is for the change made now, not to keep.
  AxisMachineConfig& config() {
    changed_ = edges_waiting_ = true;
    faulty_ = config_open_ = true;
    return config_;
  }
  const AxisMachineConfig& config() const { return config_; }

 private:
  AxisMachineConfig config_;
  int64_t position_ = 0;
  uint64_t pulses_ = 0;
  motion::Tick last_step_time_ = 0;
  motion::Tick clock_ = 0;  // the back end's time: the latest step or flush
  motion::Tick horizon_ = 0;
  bool powered_ = true;
  bool estop_ = false;
  bool halt_high_ = true;
  motion::StepQueue steps_;
  std::vector<TracedStep>* trace_ = nullptr;
  std::vector<TracedPulse>* pulse_trace_ = nullptr;
  bool tracing_ = false;  // either trace: one test per step
  // A fault that can keep a pulse from moving the motor (no power, a missed or slipping
  // pulse, a stall), or a configuration not looked at since config(): one test per step.
  bool faulty_ = false;
  bool config_open_ = false;
  // The widths of the queued pulses that have one, in time order (a step without a width
  // costs nothing here), and the width of the last pulse that went out.
  struct QueuedWidth {
    motion::Tick time;
    uint32_t width_ns;
  };
  std::deque<QueuedWidth> widths_;
  uint32_t last_width_ns_ = 0;
  // The inputs: the levels last reported, the positions between which none of the
  // position's switches changes (so a step costs two comparisons), the edges not read.
  motion::InputLevels reported_;
  int64_t steady_low_ = 0, steady_high_ = -1;
  bool changed_ = true;
  std::deque<motion::InputEdge> edges_;

  // A pulse that reached the drive (direction +1 / -1); steps come in time order, each
  // after the last flush. Inline: it is every step's path.
  void move(motion::Tick time, int direction, uint32_t width_ns = 0) {
    ++pulses_;
    last_step_time_ = clock_ = time;
    last_width_ns_ = width_ns;
    if (tracing_) [[unlikely]]
      record(time, direction, width_ns);
    if (faulty_) [[unlikely]]
      return move_with_faults(time, direction);
    position_ += direction;
    if (position_ < steady_low_ || position_ > steady_high_) [[unlikely]]
      sense(time);
  }
  void move_with_faults(motion::Tick time, int direction);
  void update_faulty();
  void record(motion::Tick time, int direction, uint32_t width_ns);
  motion::InputLevels sensed() const;
  void sense(motion::Tick time);
  void find_steady_range();
};

// The whole machine: the axes and the inputs they share.
struct Machine {
  std::vector<AxisMachine> axes;
  // The e-stop input: one switch, wired to every axis.
  void set_emergency_stop(bool active) {
    emergency_stop_ = active;
    for (AxisMachine& a : axes) a.set_emergency_stop(active);
  }
  bool emergency_stop() const { return emergency_stop_; }

 private:
  bool emergency_stop_ = false;
};

}  // namespace stepnode::sim
