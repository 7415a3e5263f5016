// One Horner axis on a simulated machine, driven as a PLC drives the module: command bits
// written (a command is the bit going on and off in one tick), time advanced in virtual
// ticks, the status bits and the motor's position read. Shared by the axis tests.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <vector>

#include "node/motion/axis.hpp"
#include "node/sim/machine.hpp"
#include "node/sim/tests/estop_switch.hpp"

namespace stepnode::motion::harness {

constexpr Tick ms(double v) { return static_cast<Tick>(v * kClockHz / 1000.0); }

class AxisHarness : public ::testing::Test {
 protected:
  // No encoder, no switches unless a test adds them.
  static sim::AxisMachineConfig plain() {
    sim::AxisMachineConfig m;
    m.encoder = sim::EncoderKind::None;
    return m;
  }
  // A new axis at power-up (%I8 on: `clear()` before a command acts), driving the first
  // `ports` of `machines` simulated motors (an SPM30 multiplexed axis drives three); the
  // e-stop input is wired to every motor.
  void build(AxisConfig c = {}, sim::AxisMachineConfig m = plain(), unsigned ports = 1,
             unsigned machines = 0) {
    motors.assign(std::max(ports, machines), sim::AxisMachine(m));
    std::vector<sim::AxisMachine*> wired;
    std::vector<MotorPort*> driven;
    for (auto& motor : motors) wired.push_back(&motor);
    for (unsigned i = 0; i < ports; ++i) driven.push_back(&motors[i]);
    estop.wire(wired);
    axis = std::make_unique<Axis>(c, driven);
    axis->on_event = [this](const AxisEvent& e) { events.push_back(e); };
    now = 0;
    held = 0;
    events.clear();
  }
  void SetUp() override { build(); }

  void write(uint16_t bits) { axis->write_commands(bits, now); }
  void issue(uint16_t bits) {
    write(static_cast<uint16_t>(held | bits));
    write(held);
  }
  void hold(uint16_t bits) {
    held = bits;
    write(held);
  }
  void at(Tick t) {
    now = std::max(now, t);
    axis->advance_to(now);
  }
  void wait(double milliseconds) { at(now + ms(milliseconds)); }
  void clear() { issue(command::kClearErrors); }
  void set_position(int32_t p) {
    axis->words().destination = p;
    issue(command::kSetPosition);
  }
  void move_rel(int32_t d) {
    axis->words().destination = d;
    issue(command::kMoveRelative);
  }
  void move_abs(int32_t d) {
    axis->words().destination = d;
    issue(command::kMoveAbsolute);
  }
  bool has(uint16_t bits) const { return (axis->status() & bits) == bits; }
  bool any(uint16_t bits) const { return (axis->status() & bits) != 0; }
  uint16_t errors() const { return axis->status() & status::kErrors; }
  int64_t mech() const { return motors[0].position(); }
  // Step by step until the axis stands still (or `limit` ms pass); `check` after each step.
  template <class F>
  void walk(F check, double limit = 600000) {
    Tick end = now + ms(limit);
    while (now < end && any(status::kMoving)) {
      auto next = axis->next_step_time();
      at(next ? std::min(*next, end) : std::min(now + ms(0.1), end));
      check();
    }
  }
  // Every step until the axis stands still (or `limit` ms pass): the time of each.
  std::vector<Tick> walk_steps(double limit = 120000) {
    std::vector<Tick> steps;
    Tick end = now + ms(limit);
    int64_t last = mech();
    while (now < end && any(status::kMoving)) {
      auto next = axis->next_step_time();
      at(next ? std::min(*next, end) : std::min(now + ms(0.1), end));
      if (mech() != last) steps.push_back(now);
      last = mech();
    }
    return steps;
  }

  std::vector<sim::AxisMachine> motors;
  sim::EStopSwitch estop;
  std::unique_ptr<Axis> axis;
  std::vector<AxisEvent> events;
  Tick now = 0;
  uint16_t held = 0;
};

}  // namespace stepnode::motion::harness
