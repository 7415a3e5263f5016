// The axis every CiA 402 drive test runs on, in virtual time: a simulated motor that records
// each step it receives (time, direction), the e-stop switch wired to it, the motion core
// and the drive on it. The drive, PP/PV, homing and cyclic tests derive their fixtures from
// DriveAxis and add what their mode needs.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "node/profiles/cia402/drive.hpp"
#include "node/sim/machine.hpp"
#include "node/sim/tests/estop_switch.hpp"

// In the profile's namespace, so the tests name the drive and the harness alike.
namespace stepnode::cia402 {

using motion::kClockHz;
using motion::Tick;

constexpr Tick ms(int64_t n) { return n * kClockHz / 1000; }

// The statusword's state bits (6041h state coding, mask 0x6F).
constexpr uint16_t kStateMask = 0x006F;
constexpr uint16_t kSwitchOnDisabled = 0x0040, kReadyToSwitchOn = 0x0021, kSwitchedOn = 0x0023,
                   kOperationEnabled = 0x0027, kQuickStopActive = 0x0007, kFault = 0x0008;
// Bits 10..13 (6041h): target reached, internal limit active, the two mode-specific ones.
constexpr uint16_t kTargetReached = 1u << 10, kInternalLimit = 1u << 11, kBit12 = 1u << 12,
                   kBit13 = 1u << 13;

// A simulated motor that keeps every step pulse it received.
struct RecordingMachine : sim::AxisMachine {
  using sim::AxisMachine::AxisMachine;
  std::vector<sim::TracedStep> steps;
  void step(Tick time, int direction) override {
    steps.push_back({time, direction});
    sim::AxisMachine::step(time, direction);
  }
};

class DriveAxis : public ::testing::Test {
 protected:
  RecordingMachine motor;
  sim::EStopSwitch estop{{&motor}};
  motion::AxisCore core{{&motor}};
  Drive drive{core};
  Tick now = 0;

  uint16_t state() const { return drive.statusword() & kStateMask; }
  void cw(uint16_t value) { drive.controlword(value, now); }
  // Time passes in steps of 1 ms, the drive advanced at each (as the node's timer does).
  void run(Tick dt) {
    const Tick end = now + dt;
    while (now < end) drive.advance(now = std::min(end, now + ms(1)));
  }
  void run_s(double seconds) { run(static_cast<Tick>(seconds * kClockHz)); }
  // 6081h, 6083h, 6084h.
  void set_profile(uint32_t v, uint32_t acc, uint32_t dec) {
    drive.parameters().profile_velocity = v;
    drive.parameters().acceleration = acc;
    drive.parameters().deceleration = dec;
  }
  // The master's start sequence: shutdown, switch on, enable operation.
  void enable() {
    cw(0x06);
    cw(0x07);
    cw(0x0F);
    ASSERT_EQ(state(), kOperationEnabled);
  }
};

}  // namespace stepnode::cia402
