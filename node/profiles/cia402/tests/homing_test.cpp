// CiA 402 homing mode on the simulated machine, in virtual time: each method this drive
// performs ends on the position the standard's figure gives for it (CiA 402-2 "Homing
// mode": methods 1, 2, 3..6, 17, 18, 19..22, 33, 34, 35, 37; 7..14 and 23..30 are in
// homing_window_test.cpp), with the homing status bits
// as the standard's table codes them (6041h bits 13/12/10: 0/0/1 not started or
// interrupted, 0/0/0 in progress, 0/1/1 completed, 1/0/x error) and the home offset 607Ch.
//
// The machine: the index pulse is the encoder marker, active 4 steps wide once per 2000
// steps from position 0 ([0, 4) + 2000 k); a rising edge seen moving up is at 0 + 2000 k,
// moving down at 3 + 2000 k. The limit switches are active at or beyond their position.
#include <gtest/gtest.h>

#include <algorithm>
#include <optional>

#include "node/profiles/cia402/tests/drive_harness.hpp"

namespace stepnode::cia402 {
namespace {

constexpr uint16_t kInProgressMask = (1u << 13) | (1u << 12) | (1u << 10);
constexpr uint16_t kNotStarted = 1u << 10, kInProgress = 0, kCompleted = (1u << 12) | (1u << 10);
constexpr uint16_t kError = 1u << 13;

class Homing : public DriveAxis {
 protected:
  uint16_t homing_bits() const { return drive.statusword() & kInProgressMask; }
  // Enable, mode 6, method `m`, start (bit 4), and run until done (or `seconds`).
  void home(int8_t m, double seconds = 20) {
    Parameters& p = drive.parameters();
    p.homing_method = m;
    p.homing_switch_speed = 2000;
    p.homing_zero_speed = 200;
    p.homing_acceleration = 20'000;
    drive.set_mode(Mode::Homing, now);
    cw(0x06);
    cw(0x07);
    cw(0x0F);
    ASSERT_EQ(homing_bits(), kNotStarted);
    cw(0x1F);
    if (auto plan = homing_plan(m, false); plan && !plan->empty()) {
      EXPECT_EQ(homing_bits(), kInProgress);  // bit 10 cleared at the start edge
    }
    for (int i = 0; i < seconds * 10 && homing_bits() == kInProgress; ++i) run_s(0.1);
  }
  // Method `m`, mode 6, the master's enable sequence and the start edge (bit 4), nothing
  // run yet.
  void start(int8_t m) {
    drive.parameters().homing_method = m;
    drive.set_mode(Mode::Homing, now);
    cw(0x06);
    cw(0x07);
    cw(0x0F);
    cw(0x1F);
  }
  void limits(std::optional<int64_t> low, std::optional<int64_t> high) {
    motor.config().lower_limit = low;
    motor.config().upper_limit = high;
    core.advance_to(now);  // the core learns of the inputs' edges at its next advance
  }
  void home_switch(int64_t from, int64_t to) {
    motor.config().home = sim::Cam{from, to - from};
    core.advance_to(now);
  }
  // A fresh machine at mechanical position `at`, the drive powered up.
  void reset(int64_t at = 0) {
    motor = RecordingMachine{};
    motor.displace(at);
    core.power_up(now);
    core.set_position(static_cast<int32_t>(at));
    drive.power_up(now, drive.mode());
  }
};

TEST_F(Homing, Method17NegativeLimitSwitch) {
  limits(-500, std::nullopt);  // active at -500 and below: it goes off at -499
  home(17);
  EXPECT_EQ(homing_bits(), kCompleted);
  EXPECT_EQ(motor.position(), -499);
  EXPECT_EQ(drive.position_actual(), 0);  // the home position is the home offset
}

TEST_F(Homing, Method18PositiveLimitSwitch) {
  limits(std::nullopt, 700);
  home(18);
  EXPECT_EQ(homing_bits(), kCompleted);
  EXPECT_EQ(motor.position(), 699);
}

TEST_F(Homing, Method1NegativeLimitSwitchAndIndexPulse) {
  limits(-500, std::nullopt);
  home(1);
  EXPECT_EQ(homing_bits(), kCompleted);
  EXPECT_EQ(motor.position(), 0);  // the first index pulse after the switch, moving up
}

TEST_F(Homing, Method2PositiveLimitSwitchAndIndexPulse) {
  limits(std::nullopt, 2500);
  home(2);
  EXPECT_EQ(homing_bits(), kCompleted);
  EXPECT_EQ(motor.position(), 2003);  // moving down from 2499: the pulse at 2000..2003
}

TEST_F(Homing, Methods19To22HomeTheSwitchEdgeFromTheSideTheStandardSays) {
  struct Case {
    int8_t method;
    int64_t from, to;  // the switch's active range
    int64_t home;
  };
  // 19/20: a positive home switch (active from 300 up); 21/22: a negative one (up to -300).
  for (const Case c : {Case{19, 300, 1'000'000, 299}, Case{20, 300, 1'000'000, 300},
                       Case{21, -1'000'000, -299, -299}, Case{22, -1'000'000, -299, -300}}) {
    SCOPED_TRACE(c.method);
    reset();
    home_switch(c.from, c.to);
    home(c.method);
    EXPECT_EQ(homing_bits(), kCompleted);
    EXPECT_EQ(motor.position(), c.home);
    // Started on the switch, the same edge is found.
    reset(c.from > 0 ? c.from + 2000 : c.to - 2000);
    home_switch(c.from, c.to);
    home(c.method);
    EXPECT_EQ(homing_bits(), kCompleted);
    EXPECT_EQ(motor.position(), c.home);
  }
}

TEST_F(Homing, Methods3To6AddTheIndexPulseBeyondTheEdge) {
  struct Case {
    int8_t method;
    int64_t from, to;
    int64_t home;
  };
  for (const Case c : {Case{3, 300, 1'000'000, 3}, Case{4, 300, 1'000'000, 2000},
                       Case{5, -1'000'000, -299, 0}, Case{6, -1'000'000, -299, -1997}}) {
    SCOPED_TRACE(c.method);
    reset();
    home_switch(c.from, c.to);
    home(c.method);
    EXPECT_EQ(homing_bits(), kCompleted);
    EXPECT_EQ(motor.position(), c.home);
  }
}

TEST_F(Homing, Methods33And34AreTheNextIndexPulse) {
  home(33);
  EXPECT_EQ(motor.position(), -1997);
  reset();
  home(34);
  EXPECT_EQ(motor.position(), 2000);
}

TEST_F(Homing, Methods35And37TakeTheCurrentPositionWithTheHomeOffset) {
  reset(1234);
  drive.parameters().home_offset = -50;
  home(37);
  EXPECT_EQ(homing_bits(), kCompleted);
  EXPECT_EQ(drive.position_actual(), -50);
  EXPECT_EQ(motor.position(), 1234);  // nothing moved
}

TEST_F(Homing, ALimitSwitchTheMethodDoesNotLookForIsAHomingError) {
  limits(std::nullopt, 800);  // no home switch: method 19 runs into the positive limit
  home(19);
  EXPECT_EQ(homing_bits(), kError | (1u << 10));  // error, velocity 0
  EXPECT_LE(motor.position(), 800);
}

TEST_F(Homing, AMethodThisDriveDoesNotPerformIsAHomingError) {
  home(15);  // reserved
  EXPECT_EQ(homing_bits() & kError, kError);
  EXPECT_EQ(motor.position(), 0);
}

TEST_F(Homing, HaltInterruptsTheHoming) {
  limits(-100'000, std::nullopt);
  drive.parameters().homing_switch_speed = 1000;
  drive.parameters().homing_acceleration = 10'000;
  start(17);
  run_s(0.5);
  EXPECT_EQ(homing_bits(), kInProgress);
  cw(0x011F);  // halt
  run_s(0.5);
  EXPECT_EQ(homing_bits(), kNotStarted);  // 0/0/1: interrupted, standing
}

// ---- stepnode's manufacturer-specific methods on a hard stop (homing.hpp) --------------
// The machine's hard stop: the motor cannot pass the position (sim stall_below/above), its
// encoder (quadrature, 500 lines on 2000 steps per revolution: one count per step) stops
// counting there. The block is found once the encoder has not counted in the direction of
// travel for more than 6065h steps and that has lasted 6066h.
class HardStopHoming : public Homing {
 protected:
  static constexpr uint32_t kWindow = 20;     // 6065h, steps
  static constexpr uint16_t kTimeoutMs = 10;  // 6066h
  void SetUp() override {
    drive.parameters().following_error_window = kWindow;
    drive.parameters().following_error_timeout_ms = kTimeoutMs;
  }
  // Steps the motor was given in `direction` that did not move it.
  int64_t lost_steps(int direction) const {
    int64_t given = 0;
    for (const auto& s : motor.steps) given += s.direction == direction ? 1 : -1;
    return given - direction * motor.position();
  }
};

TEST_F(HardStopHoming, MethodMinus17HomesOnTheHardStopBelow) {
  motor.config().stall_below = -500;
  drive.parameters().home_offset = 7;
  home(-17);
  EXPECT_EQ(homing_bits(), kCompleted);
  EXPECT_EQ(motor.position(), -500);
  EXPECT_EQ(drive.position_actual(), 7);  // the home offset, at the block
  // At 2000 steps/s (6099h:1) a step every 0.5 ms: the 21st step without a count exceeds
  // the window, and 10 ms later (20 steps) the block is found on that step.
  EXPECT_EQ(lost_steps(-1), kWindow + 1 + 20);
  // Position actual now measures from the block: a move to 107 ends 100 steps above it.
  drive.set_mode(Mode::ProfilePosition, now);
  drive.parameters().profile_velocity = 2000;
  drive.parameters().acceleration = 20'000;
  drive.parameters().deceleration = 20'000;
  drive.set_target_position(107);
  cw(0x0F);
  cw(0x1F);
  run_s(1);
  EXPECT_EQ(motor.position(), -400);
  EXPECT_EQ(drive.position_actual(), 107);
}

TEST_F(HardStopHoming, MethodMinus18HomesOnTheHardStopAbove) {
  motor.config().stall_above = 700;
  home(-18);
  EXPECT_EQ(homing_bits(), kCompleted);
  EXPECT_EQ(motor.position(), 700);
  EXPECT_EQ(drive.position_actual(), 0);
  EXPECT_EQ(lost_steps(+1), kWindow + 1 + 20);
}

TEST_F(HardStopHoming, MethodsMinus1AndMinus2GoBackToTheFirstIndexPulse) {
  motor.config().stall_below = -500;
  home(-1);
  EXPECT_EQ(homing_bits(), kCompleted);
  EXPECT_EQ(motor.position(), 0);  // as method 1: the first pulse moving up, at 0
  reset();
  motor.config().stall_above = 2500;
  home(-2);
  EXPECT_EQ(homing_bits(), kCompleted);
  EXPECT_EQ(motor.position(), 2003);  // as method 2: moving down, the pulse at 2000..2003
}

TEST_F(HardStopHoming, ALimitSwitchBeforeTheHardStopIsAHomingError) {
  motor.config().stall_below = -500;
  limits(-300, std::nullopt);
  home(-17);
  EXPECT_EQ(homing_bits() & kError, kError);
  EXPECT_EQ(motor.position(), -300);
}

TEST_F(HardStopHoming, WithoutAnEncoderOrAFollowingErrorWindowTheMethodIsRefused) {
  auto start_and_wait = [&] {
    start(-17);
    run_s(0.5);
  };
  motor.config().stall_below = -500;
  motor.config().encoder = sim::EncoderKind::None;
  start_and_wait();
  EXPECT_EQ(homing_bits(), kError | kNotStarted);  // error, velocity 0: at the start edge
  EXPECT_EQ(motor.position(), 0);                  // nothing moved
  reset();
  cw(0x0F);  // bit 4 low again
  motor.config().stall_below = -500;
  drive.parameters().following_error_window = UINT32_MAX;  // 6065h off
  start_and_wait();
  EXPECT_EQ(homing_bits(), kError | kNotStarted);
  EXPECT_EQ(motor.position(), 0);
}

TEST_F(HardStopHoming, AnEncoderCountingEveryFourStepsNeedsAWindowAboveFour) {
  // Up/down counting of 500 lines on 2000 steps: one count per 4 steps. A free load counts
  // within every window of 4 steps, so a window of 20 never sees a block before the stop.
  motor.config().encoder = sim::EncoderKind::UpDown;
  motor.config().stall_below = -1000;
  home(-17);
  EXPECT_EQ(homing_bits(), kCompleted);
  EXPECT_EQ(motor.position(), -1000);
}

}  // namespace
}  // namespace stepnode::cia402
