// The axes of the device and their back end: one motion::AxisCore per axis (the pulse
// engine, position, e-stop guard, and the job that runs) driving the simulated machine, the
// Horner front end on each (motion::Axis: the module's status bits report every job), and
// the clock that turns the node's microseconds into engine ticks. The other front ends (HP
// channels, CiA 402) are built on the cores by their profiles.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "node/deadline.hpp"
#include "node/device_objects.hpp"
#include "node/motion/axis.hpp"
#include "node/sim/machine.hpp"

namespace stepnode::node {

class AxisBank {
 public:
  explicit AxisBank(const DeviceLayout& layout);

  // Every axis up to `now_us` (CLOCK_MONOTONIC or virtual): the steps due are taken.
  void advance(uint64_t now_us);
  // Power-up / NMT reset node: every axis back to its power-up state.
  void power_up(uint64_t now_us);
  // The master was lost (or can no longer reach the node): every moving axis ramps down,
  // %I8 latches.
  void master_lost(uint64_t now_us);
  // When an axis next needs an advance (absolute us; kNoDeadline: every axis idle). A
  // moving axis: its next step, but at most once per step wake period (the poll period,
  // or half the step port's horizon if longer: the planner has queued the steps up to
  // the horizon at the last advance, so the port never runs dry; README "Running a node"
  // says why horizon 0 keeps the poll period). A job's deadline between steps (FIND
  // HOME's dwell) and the end of a ramp that ends between steps: exactly then. A job
  // waiting for an input: nothing (the input comes with a frame).
  uint64_t next_deadline_us(uint64_t now_us);

  unsigned count() const { return static_cast<unsigned>(axes_.size()); }
  motion::AxisCore& core(unsigned n) { return *cores_.at(n); }
  motion::Axis& axis(unsigned n) { return *axes_.at(n); }
  sim::Machine& machine() { return machine_; }
  // The time of the latest advance (the time a command written now acts at).
  uint64_t now_us() const { return now_us_; }
  motion::Tick now() const { return ticks(now_us_); }
  motion::Tick ticks(uint64_t now_us) const;
  // The node clock's microsecond of a tick, to the nearest (so micros(ticks(us)) == us).
  // The first node microsecond at which ticks() reaches t (a deadline is never early).
  uint64_t micros_at_or_after(motion::Tick t) const;
  uint64_t micros(motion::Tick t) const {
    uint64_t u = static_cast<uint64_t>(t);
    return epoch_us_ + u / 3072 * 625 + (u % 3072 * 625 + 1536) / 3072;
  }

  // Every axis event (status change, error, move done), to every listener in order.
  using EventListener = std::function<void(unsigned axis, const motion::AxisEvent& event)>;
  void listen(EventListener listener) { listeners_.push_back(std::move(listener)); }

 private:
  uint64_t core_deadline_us(motion::AxisCore& core, uint64_t now_us) const;

  sim::Machine machine_;
  std::vector<std::unique_ptr<motion::AxisCore>> cores_;
  std::vector<std::unique_ptr<motion::Axis>> axes_;
  std::vector<EventListener> listeners_;
  uint64_t epoch_us_ = 0;
  bool epoch_set_ = false;
  uint64_t now_us_ = 0;
  uint64_t step_wake_us_ = kPollUs;  // the shortest sleep while an axis moves
};

}  // namespace stepnode::node
