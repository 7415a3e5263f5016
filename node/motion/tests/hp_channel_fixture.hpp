// The HP channel test fixture: one channel on a simulated motor (no encoder), in virtual
// time, with its interrupts recorded. Shared by the HP channel tests.
#pragma once
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "node/motion/axis.hpp"
#include "node/motion/hp_channel.hpp"
#include "node/sim/machine.hpp"
#include "node/sim/tests/estop_switch.hpp"

namespace stepnode::motion::hp {

inline constexpr Tick ms(double v) {
  return static_cast<Tick>(std::llround(v * kClockHz / 1000.0));
}
inline double to_ms(Tick t) { return static_cast<double>(t) * 1000.0 / kClockHz; }

inline Profile freq(double min, double max, double slope, double pwidth) {
  return Profile{ProfileMode::Freq, min, max, slope, pwidth};
}
inline Profile width(double min, double max, double slope, double period) {
  return Profile{ProfileMode::Width, min, max, slope, period};
}

class HpChannel : public ::testing::Test {
 protected:
  void SetUp() override { build(); }
  void build(sim::AxisMachineConfig m = plain()) {
    motor = std::make_unique<sim::AxisMachine>(m);
    estop.wire({motor.get()});
    axis = std::make_unique<Axis>(AxisConfig{}, std::vector<MotorPort*>{motor.get()});
    ch = std::make_unique<Channel>(axis->core());
    ch->on_interrupt = [this](uint8_t e, Tick t) { interrupts.push_back({e, t}); };
    now = 0;
  }
  static sim::AxisMachineConfig plain() {
    sim::AxisMachineConfig m;
    m.encoder = sim::EncoderKind::None;
    return m;
  }
  void wait(double milliseconds, double step_ms = 1) {
    Tick end = now + ms(milliseconds);
    while (now < end) {
      now = std::min(end, now + ms(step_ms));
      ch->advance_to(now);
    }
  }
  int64_t position() const { return motor->position(); }
  int done() const { return static_cast<int>(ch->done()); }

  struct Intr {
    uint8_t event;
    Tick at;
  };
  sim::EStopSwitch estop;
  std::unique_ptr<sim::AxisMachine> motor;
  std::unique_ptr<Axis> axis;
  std::unique_ptr<Channel> ch;
  std::vector<Intr> interrupts;
  Tick now = 0;
};

}  // namespace stepnode::motion::hp
