// First checks of the axis state machine; the full rule-by-rule suite is axis_*_test.cpp.
#include <gtest/gtest.h>

#include "node/motion/axis.hpp"
#include "node/sim/machine.hpp"

namespace stepnode::motion {
namespace {

TEST(AxisSmoke, ClearSetPositionMoveRelativeAndAbsolute) {
  sim::AxisMachine m;
  Axis axis({}, {&m});
  EXPECT_EQ(axis.status() & status::kPowerUp, status::kPowerUp);  // SPM30 3.1
  axis.write_commands(command::kMoveRelative, 0);                 // refused: error latched
  EXPECT_FALSE(axis.status() & status::kMoving);
  axis.write_commands(0, 10);
  axis.write_commands(command::kClearErrors, 20);
  EXPECT_EQ(axis.status() & status::kErrors, 0);
  axis.words().destination = 1000;
  axis.write_commands(0, 30);
  axis.write_commands(command::kMoveRelative, 40);
  EXPECT_TRUE(axis.status() & status::kMoving);
  EXPECT_TRUE(axis.status() & status::kAccelerating);
  axis.advance_to(40 + 10 * kClockHz);
  EXPECT_FALSE(axis.status() & status::kMoving);
  EXPECT_EQ(axis.motor_position(), 1000);
  EXPECT_EQ(m.position(), 1000);
  // Absolute needs a valid position: Illegal Move (SPM30 3.3.1).
  axis.write_commands(0, 11 * kClockHz);
  axis.write_commands(command::kMoveAbsolute, 11 * kClockHz + 1);
  EXPECT_TRUE(axis.status() & status::kIllegalMove);
  axis.write_commands(0, 12 * kClockHz);
  axis.write_commands(command::kClearErrors, 12 * kClockHz + 1);
  axis.words().destination = 50;
  axis.write_commands(0, 13 * kClockHz);
  axis.write_commands(command::kSetPosition, 13 * kClockHz + 1);
  EXPECT_TRUE(axis.status() & status::kPositionValid);
  axis.words().destination = -250;
  axis.write_commands(0, 14 * kClockHz);
  axis.write_commands(command::kMoveAbsolute, 14 * kClockHz + 1);
  axis.advance_to(30 * kClockHz);
  EXPECT_EQ(axis.motor_position(), -250);
  EXPECT_EQ(m.position(), 1000 - 300);
}

TEST(AxisSmoke, FindHomeNormalMethodStopsPreciselyAtHome) {
  sim::AxisMachineConfig cfg;
  cfg.home = sim::Cam{5000, 40};
  sim::AxisMachine m(cfg);
  Axis axis({}, {&m});
  axis.write_commands(command::kClearErrors, 0);
  axis.words().destination = 123;
  axis.write_commands(0, 1);
  axis.write_commands(command::kFindHomeUp, 2);
  axis.advance_to(60 * kClockHz);
  EXPECT_FALSE(axis.status() & status::kMoving);
  EXPECT_TRUE(axis.status() & status::kPositionValid);
  EXPECT_TRUE(axis.status() & status::kAtHome);
  EXPECT_EQ(axis.motor_position(), 123);
  // Approached from below at base velocity: stops on the first step of the cam.
  EXPECT_EQ(m.position(), 5000);
}

// SPM30 JOG: releasing the bit decelerates to base and stops; the ramp may end between
// steps, and the axis must still come to rest (a regression: it stayed "decelerating").
TEST(AxisSmoke, JogReleaseEndsInStandstill) {
  sim::AxisMachine m;
  Axis axis({}, {&m});
  axis.write_commands(command::kClearErrors, 0);
  axis.write_commands(0, 1);
  axis.write_commands(command::kJogDown, 10);
  axis.advance_to(kClockHz);
  EXPECT_EQ(axis.phase(), MotionPhase::Running);
  axis.write_commands(0, kClockHz);
  EXPECT_TRUE(axis.status() & status::kDecelerating);
  axis.advance_to(3 * kClockHz);
  EXPECT_EQ(axis.phase(), MotionPhase::Idle);
  EXPECT_FALSE(axis.status() & status::kMoving);
  EXPECT_EQ(m.position(), axis.motor_position());
  EXPECT_LT(axis.motor_position(), -500);
}

}  // namespace
}  // namespace stepnode::motion
