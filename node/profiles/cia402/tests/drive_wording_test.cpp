// Points of CiA 402-2's wording a standard master relies on (found in a review against the
// standard, 2026-12-06): PP's halt bit 8 "0 = positioning shall be executed or continued",
// HM's bit 4 "1 = start or continue homing" (so 1 -> 0 interrupts it), 6060h 0 "no mode
// change", and 6041h bit 10 once a quick stop with 605Ah 5..8 has stopped the axis.
#include <gtest/gtest.h>

#include "node/profiles/cia402/tests/drive_harness.hpp"

namespace stepnode::cia402 {
namespace {

class DriveWording : public DriveAxis {
 protected:
  bool reached() const { return (drive.statusword() & kTargetReached) != 0; }
  // Enabled, 1,000 steps/s at 10,000 steps/s², a PP set-point to `target` (handshake done).
  void pp_move_to(int32_t target) {
    enable();
    set_profile(1000, 10'000, 10'000);
    set_point(target);
  }
  void set_point(int32_t target) {
    drive.set_target_position(target);
    cw(0x1F);
    cw(0x0F);
  }
};

TEST_F(DriveWording, PpHaltReleasedGoesOnToTheTarget) {
  pp_move_to(2000);
  run(ms(500));
  cw(0x010F);  // halt
  run(ms(300));
  EXPECT_FALSE(core.moving());
  EXPECT_TRUE(reached()) << "halted: bit 10 once the velocity is 0";
  const int64_t stopped_at = motor.position();
  EXPECT_LT(stopped_at, 2000);
  cw(0x0F);  // released
  run(ms(10));
  EXPECT_TRUE(core.moving());
  EXPECT_FALSE(reached()) << "the target is not reached";
  run(ms(3000));
  EXPECT_EQ(motor.position(), 2000);
  EXPECT_TRUE(reached());
}

TEST_F(DriveWording, PpHaltReleasedDuringItsRampGoesOnAfterIt) {
  pp_move_to(2000);
  run(ms(500));
  cw(0x010F);
  run(ms(20));  // the halt's ramp (100 ms) still runs
  ASSERT_TRUE(core.moving());
  cw(0x0F);
  run(ms(4000));
  EXPECT_EQ(motor.position(), 2000);
  EXPECT_TRUE(reached());
}

TEST_F(DriveWording, PpHaltKeepsTheBufferedSetPointToo) {
  pp_move_to(1000);
  set_point(-500);  // buffered: runs after the first
  run(ms(300));
  cw(0x010F);
  run(ms(300));
  cw(0x0F);
  run(ms(6000));
  EXPECT_EQ(motor.position(), -500);
}

TEST_F(DriveWording, HomingBit4TakenBackInterruptsTheHoming) {
  motor.config().lower_limit = -50'000;  // method 17 searches far
  core.advance_to(now);
  Parameters& p = drive.parameters();
  p.homing_method = 17;
  p.homing_switch_speed = 2000;
  p.homing_acceleration = 20'000;
  drive.set_mode(Mode::Homing, now);
  enable();
  cw(0x1F);
  run(ms(300));
  ASSERT_TRUE(core.moving());
  EXPECT_EQ(drive.statusword() & 0x3400, 0x0000) << "13/12/10 = 0/0/0: in progress";
  cw(0x0F);  // bit 4 back to 0
  run(ms(300));
  EXPECT_FALSE(core.moving());
  EXPECT_EQ(drive.statusword() & 0x3400, 0x0400) << "13/12/10 = 0/0/1: interrupted";
  const int64_t at = motor.position();
  run(ms(1000));
  EXPECT_EQ(motor.position(), at);
  cw(0x1F);  // a new start edge starts it again
  run(ms(100));
  EXPECT_TRUE(core.moving());
}

TEST_F(DriveWording, ModesOfOperationZeroChangesNoMode) {
  pp_move_to(1000);
  run(ms(300));
  drive.set_mode(Mode::None, now);  // a master's RPDO1 with 6060h left 0
  run(ms(2000));
  EXPECT_EQ(motor.position(), 1000);
  EXPECT_EQ(drive.mode_display(), Mode::ProfilePosition);
}

TEST_F(DriveWording, NoModeAtPowerUpUntilTheMasterAssignsOne) {
  drive.power_up(now, Mode::None);
  EXPECT_EQ(drive.mode_display(), Mode::None);
  drive.set_mode(Mode::ProfileVelocity, now);
  EXPECT_EQ(drive.mode_display(), Mode::ProfileVelocity);
}

TEST_F(DriveWording, PvQuickStopOptionSixShowsTargetReachedOnceStopped) {
  Options o;
  o.quick_stop = 6;  // quick stop ramp, stay in Quick stop active
  drive.set_options(o);
  set_profile(1000, 10'000, 10'000);
  drive.set_mode(Mode::ProfileVelocity, now);
  enable();
  drive.set_target_velocity(1000, now);
  run(ms(300));
  cw(0x0B);
  EXPECT_FALSE(reached()) << "still ramping down";
  run(ms(300));
  EXPECT_EQ(state(), kQuickStopActive);
  EXPECT_FALSE(core.moving());
  EXPECT_TRUE(reached());
}

}  // namespace
}  // namespace stepnode::cia402
