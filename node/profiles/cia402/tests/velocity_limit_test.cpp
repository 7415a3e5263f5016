// The software position limits 607Dh in the velocity modes (CiA 402-2: "These parameters
// define the absolute position limits for the position demand value and the position
// actual value"): in CSV (9) and PV (3) the axis does not run past them. A motion toward a
// limit begins its stop in time to end on or before it with the quick stop deceleration
// 6085h (statusword bit 11, internal limit active); a motion toward a limit the axis could
// not stop before does not start; one away from it does. A cyclic mode's own stop ramp
// (CSP's quick stop) ends on or before the limits too.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>

#include "node/profiles/cia402/tests/drive_harness.hpp"

namespace stepnode::cia402 {
namespace {

class VelocityLimit : public DriveAxis {
 protected:
  void SetUp() override {
    Parameters& p = drive.parameters();
    p.max_velocity = 1'000'000;
    p.quick_stop_deceleration = 10'000;  // 2,000 steps/s stop in 0.2 s over 200 steps
    p.min_position_limit = -1000;
    p.max_position_limit = 1000;
  }
  // `n` SYNCs at 1 kHz carrying CSV's `velocity`; the furthest position reached in them.
  int32_t csv_for(int n, int32_t velocity) {
    int32_t furthest = drive.position_actual();
    for (int k = 0; k < n; ++k) {
      drive.advance(now += ms(1));
      drive.set_target_velocity(velocity, now);
      drive.sync(now, now);
      const int32_t p = drive.position_actual();
      furthest = velocity >= 0 ? std::max(furthest, p) : std::min(furthest, p);
    }
    return furthest;
  }
  // `n` ms of the drive's own motion (PV); the furthest position up reached in them.
  int32_t furthest_up_in(int n) {
    int32_t furthest = drive.position_actual();
    for (int k = 0; k < n; ++k) {
      run(ms(1));
      furthest = std::max(furthest, drive.position_actual());
    }
    return furthest;
  }
  // The steps of the motion's last ramp down: those after the last step that came no later
  // than the cruise's interval (`cruise` ticks, with a tick to spare) after the one before.
  size_t last_ramp_steps(Tick cruise) const {
    size_t i = motor.steps.size();
    while (i >= 2 && motor.steps[i - 1].time - motor.steps[i - 2].time > cruise + 1) --i;
    return motor.steps.size() - i;
  }
};

TEST_F(VelocityLimit, CsvStopsOnOrBeforeEachLimitWithThe6085hRamp) {
  drive.set_mode(Mode::CyclicSyncVelocity, now);
  enable();
  const int32_t furthest = csv_for(2000, 2000);
  EXPECT_EQ(furthest, drive.position_actual()) << "never past it on the way";
  EXPECT_LE(drive.position_actual(), 1000);
  EXPECT_GE(drive.position_actual(), 1000 - 210) << "stopped at the limit";
  EXPECT_FALSE(core.moving());
  // A ramp of v^2/2a = 200 steps over v/a = 0.2 s, not a stop at once.
  EXPECT_NEAR(static_cast<double>(last_ramp_steps(kClockHz / 2000)), 200.0, 10.0);
  EXPECT_TRUE(drive.statusword() & kInternalLimit);
  // Toward the limit: it stays; away from it: it goes, to the other limit.
  const int32_t stood = drive.position_actual();
  csv_for(100, 2000);
  EXPECT_EQ(drive.position_actual(), stood);
  csv_for(100, -2000);  // 99 ms at 2,000 steps/s
  EXPECT_NEAR(drive.position_actual(), stood - 198, 1);
  EXPECT_FALSE(drive.statusword() & kInternalLimit);
  EXPECT_GE(csv_for(2000, -2000), -1000);
  EXPECT_LE(drive.position_actual(), -1000 + 210);
  EXPECT_NEAR(static_cast<double>(last_ramp_steps(kClockHz / 2000)), 200.0, 10.0);
}

// The reviewer's case: 607Dh +-100, CSV at 1,000 steps/s for 1 s (6085h 50,000: 10 steps).
TEST_F(VelocityLimit, CsvNearALimitStaysInsideIt) {
  drive.parameters().quick_stop_deceleration = 50'000;
  drive.parameters().min_position_limit = -100;
  drive.parameters().max_position_limit = 100;
  drive.set_mode(Mode::CyclicSyncVelocity, now);
  enable();
  EXPECT_LE(csv_for(1000, 1000), 100);
  EXPECT_GE(drive.position_actual(), 100 - 15);
}

TEST_F(VelocityLimit, PvStopsOnOrBeforeEachLimitWithThe6085hRamp) {
  set_profile(1000, 20'000, 20'000);
  drive.set_mode(Mode::ProfileVelocity, now);
  enable();
  drive.set_target_velocity(2000, now);
  const int32_t furthest = furthest_up_in(2000);
  EXPECT_EQ(furthest, drive.position_actual());
  EXPECT_LE(drive.position_actual(), 1000);
  EXPECT_GE(drive.position_actual(), 1000 - 210);
  EXPECT_FALSE(core.moving());
  EXPECT_NEAR(static_cast<double>(last_ramp_steps(kClockHz / 2000)), 200.0, 10.0);
  EXPECT_TRUE(drive.statusword() & kInternalLimit);
  // A new target toward the limit leaves it standing; one away from it moves it.
  const int32_t stood = drive.position_actual();
  drive.set_target_velocity(3000, now);
  run(ms(200));
  EXPECT_EQ(drive.position_actual(), stood);
  EXPECT_TRUE(drive.statusword() & kInternalLimit);
  drive.set_target_velocity(0, now);  // nothing asked beyond the limit any more
  EXPECT_FALSE(drive.statusword() & kInternalLimit);
  drive.set_target_velocity(-2000, now);
  run(ms(2000));
  EXPECT_GE(drive.position_actual(), -1000);
  EXPECT_LE(drive.position_actual(), -1000 + 210);
}

// Too close to the limit to reach the target velocity: the ramp up turns where the 6085h
// stop still ends before it.
TEST_F(VelocityLimit, PvStartedCloseToALimitStopsBeforeIt) {
  drive.parameters().quick_stop_deceleration = 50'000;
  drive.parameters().max_position_limit = 100;
  set_profile(1000, 10'000, 10'000);
  drive.set_mode(Mode::ProfileVelocity, now);
  enable();
  drive.set_target_velocity(5000, now);
  run(ms(1000));
  EXPECT_LE(drive.position_actual(), 100);
  EXPECT_GE(drive.position_actual(), 70);
  EXPECT_FALSE(core.moving());
}

// 6086h = 3: the jerk-limited quick stop is longer than v^2/2a; it still ends before.
TEST_F(VelocityLimit, PvWithTheJerkLimitedRampStopsBeforeTheLimit) {
  set_profile(1000, 20'000, 20'000);
  drive.parameters().motion_profile_type = kJerkLimitedRamp;
  std::fill(std::begin(drive.parameters().jerk), std::end(drive.parameters().jerk), 200'000);
  drive.set_mode(Mode::ProfileVelocity, now);
  enable();
  drive.set_target_velocity(2000, now);
  const int32_t furthest = furthest_up_in(2000);
  EXPECT_LE(furthest, 1000);
  EXPECT_GE(drive.position_actual(), 1000 - 300);
  EXPECT_FALSE(core.moving());
}

// CSP's set-points stay inside 607Dh; its quick stop ramp (6085h from 5,000 steps/s: 1,250
// steps) must not carry the axis past the limit either.
TEST_F(VelocityLimit, ACspQuickStopRampEndsOnOrBeforeTheLimit) {
  drive.parameters().max_position_limit = 700;
  drive.set_mode(Mode::CyclicSyncPosition, now);
  enable();
  for (int k = 1; k <= 100; ++k) {
    drive.advance(now = ms(k));
    drive.set_target_position(5 * k);
    drive.sync(now, now);
  }
  cw(0x0B);
  run(ms(1000));
  EXPECT_LE(drive.position_actual(), 700);
  EXPECT_EQ(state(), kSwitchOnDisabled);
}

}  // namespace
}  // namespace stepnode::cia402
