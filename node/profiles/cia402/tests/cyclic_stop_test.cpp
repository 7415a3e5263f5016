// The stops of the cyclic modes (CSP 8, CSV 9) against the option codes of CiA 402-2, as
// in the profile modes: quick stop 605Ah 1/5 slow down on the slow-down ramp (6084h), 2/6
// on the quick stop ramp (6085h), 5..8 staying in Quick stop active; halt 605Dh 1 (6084h)
// and 2 (6085h); disable operation 605Ch 1 (6084h); fault reaction 605Eh 1 (6084h) and 2
// (6085h); a mode change ramps down with 6084h before 6061h shows the new mode. Only the
// options that stop at once (605Ah 3, 4, 7, 8; 605Dh and 605Eh 3, 4; 605Ch 0) stop the
// pulses at once. The axis runs at 5,000 steps/s with 6084h = 20,000 and 6085h = 10,000
// steps/s^2: a ramp over v^2/2a = 625 steps (0.25 s) or 1,250 steps (0.5 s).
#include <gtest/gtest.h>

#include <cstdint>
#include <ostream>
#include <string>
#include <tuple>

#include "node/profiles/cia402/tests/drive_harness.hpp"

namespace stepnode::cia402 {
namespace {

constexpr double kSlowDownSteps = 625, kQuickStopSteps = 1250;

class CyclicStop : public DriveAxis {
 protected:
  // Operation enabled in `m`, running at 5,000 steps/s after 100 SYNCs at 1 kHz (CSP: 5
  // steps a cycle); `at` is where the stop begins.
  void run_up(Mode m, const Options& options = {}) {
    drive.parameters().max_velocity = 1'000'000;
    drive.parameters().deceleration = 20'000;
    drive.parameters().quick_stop_deceleration = 10'000;
    drive.set_options(options);
    drive.set_mode(m, now);
    enable();
    for (int k = 1; k <= 100; ++k) sync(ms(k), 5 * k);
    ASSERT_NEAR(drive.velocity_actual(), 5000, 1);
    at = motor.position();
  }
  // A SYNC at `t` carrying a set-point (CSP) or the velocity (CSV): the RPDO is applied,
  // then the SYNC acts.
  void sync(Tick t, int32_t target) {
    drive.advance(now = t);
    drive.set_target_position(target);
    drive.set_target_velocity(velocity, now);
    drive.sync(t, t);
  }
  // The master goes on sending its SYNCs for `n` ms (the trajectory on as before).
  void syncs_for(int n) {
    const int first = static_cast<int>(now / ms(1)) + 1;
    for (int k = first; k < first + n; ++k) sync(ms(k), 5 * k);
  }
  int64_t stop_steps() const { return motor.position() - at; }
  int64_t at = 0;
  int32_t velocity = 5000;  // CSV's 60FFh in every SYNC
};

TEST_F(CyclicStop, CsvQuickStopRampsDownWith6085h) {
  run_up(Mode::CyclicSyncVelocity);  // 605Ah left at its default 2
  cw(0x0B);
  EXPECT_EQ(state(), kQuickStopActive) << "quick stop active during the ramp";
  run(ms(100));
  EXPECT_TRUE(core.moving()) << "0.1 s into a 0.5 s quick stop ramp the axis still moves";
  EXPECT_EQ(state(), kQuickStopActive);
  run(ms(1000));
  EXPECT_FALSE(core.moving());
  EXPECT_NEAR(static_cast<double>(stop_steps()), kQuickStopSteps, 25);
  EXPECT_EQ(state(), kSwitchOnDisabled);
}

TEST_F(CyclicStop, CspQuickStopRampsDownWith6085hWhileTheSyncsGoOn) {
  run_up(Mode::CyclicSyncPosition);
  cw(0x0B);
  syncs_for(100);  // the master's SYNCs do not restart the trajectory
  EXPECT_TRUE(core.moving()) << "0.1 s into a 0.5 s quick stop ramp the axis still moves";
  syncs_for(1000);
  EXPECT_FALSE(core.moving());
  EXPECT_NEAR(static_cast<double>(stop_steps()), kQuickStopSteps, 25);
  EXPECT_EQ(state(), kSwitchOnDisabled);
}

// 605Ah 1 and 5 ramp with 6084h, 2 and 6 with 6085h; 5..8 stay in Quick stop active.
const char* name(Mode m) { return m == Mode::CyclicSyncVelocity ? "Csv" : "Csp"; }

struct QuickStopRow {
  int16_t option;
  double steps;
  uint16_t after;
};
void PrintTo(const QuickStopRow& row, std::ostream* os) { *os << "605Ah " << row.option; }
class QuickStopOption : public CyclicStop,
                        public ::testing::WithParamInterface<std::tuple<QuickStopRow, Mode>> {};

TEST_P(QuickStopOption, RampsWithItsDeceleration) {
  const auto& [row, mode] = GetParam();
  run_up(mode, Options{.quick_stop = row.option});
  cw(0x0B);
  syncs_for(150);
  EXPECT_TRUE(core.moving());
  EXPECT_EQ(state(), kQuickStopActive);
  syncs_for(1000);
  EXPECT_NEAR(static_cast<double>(stop_steps()), row.steps, 25);
  EXPECT_EQ(state(), row.after);
}

INSTANTIATE_TEST_SUITE_P(
    CyclicModes, QuickStopOption,
    ::testing::Combine(::testing::Values(QuickStopRow{1, kSlowDownSteps, kSwitchOnDisabled},
                                         QuickStopRow{2, kQuickStopSteps, kSwitchOnDisabled},
                                         QuickStopRow{5, kSlowDownSteps, kQuickStopActive},
                                         QuickStopRow{6, kQuickStopSteps, kQuickStopActive}),
                       ::testing::Values(Mode::CyclicSyncVelocity, Mode::CyclicSyncPosition)),
    [](const auto& info) {
      return "Option" + std::to_string(std::get<0>(info.param).option) +
             name(std::get<1>(info.param));
    });

TEST_F(CyclicStop, CsvHaltRampsDownWith6084hAndTheReleaseFollowsAgain) {
  run_up(Mode::CyclicSyncVelocity);  // 605Dh left at its default 1
  cw(0x010F);                        // halt
  syncs_for(100);
  EXPECT_TRUE(core.moving()) << "0.1 s into a 0.25 s halt ramp the axis still moves";
  EXPECT_EQ(state(), kOperationEnabled);
  syncs_for(1000);
  EXPECT_FALSE(core.moving());
  EXPECT_NEAR(static_cast<double>(stop_steps()), kSlowDownSteps, 25);
  cw(0x0F);  // released: the next SYNC's velocity
  syncs_for(10);
  EXPECT_NEAR(drive.velocity_actual(), 5000, 1);
}

TEST_F(CyclicStop, CspHaltWithOption2RampsWith6085hWithoutAFollowingError) {
  run_up(Mode::CyclicSyncPosition, Options{.halt = 2});
  drive.parameters().following_error_window = 20;
  drive.parameters().following_error_timeout_ms = 5;
  cw(0x010F);
  syncs_for(100);
  EXPECT_TRUE(core.moving());
  // The drive's own ramp is the demand now (6062h), not the master's set-points.
  EXPECT_EQ(drive.following_error(), 0);
  syncs_for(1000);
  EXPECT_FALSE(core.moving());
  EXPECT_NEAR(static_cast<double>(stop_steps()), kQuickStopSteps, 25);
  EXPECT_EQ(state(), kOperationEnabled);
  EXPECT_EQ(drive.error_code(), 0);
  cw(0x0F);  // released: the set-points are followed again from where the axis stands
  const int32_t target = drive.position_actual() + 50;
  for (int k = 1; k <= 3; ++k) sync(now + ms(1), target);
  drive.advance(now += ms(1));
  EXPECT_EQ(drive.position_actual(), target);
}

TEST_F(CyclicStop, CsvDisableOperationRampsWith6084hThenSwitchedOn) {
  run_up(Mode::CyclicSyncVelocity);  // 605Ch left at its default 1
  cw(0x07);                          // disable operation
  syncs_for(100);
  EXPECT_TRUE(core.moving());
  EXPECT_EQ(state(), kOperationEnabled) << "transition 5 once the ramp has ended";
  syncs_for(1000);
  EXPECT_NEAR(static_cast<double>(stop_steps()), kSlowDownSteps, 25);
  EXPECT_EQ(state(), kSwitchedOn);
}

TEST_F(CyclicStop, CspFaultReactionRampsWith6085h) {
  run_up(Mode::CyclicSyncPosition);  // 605Eh left at its default 2
  drive.fault(0x5530, now);
  syncs_for(100);
  EXPECT_TRUE(core.moving());
  EXPECT_EQ(drive.statusword() & 0x4F, 0x0F) << "fault reaction active during the ramp";
  syncs_for(1000);
  EXPECT_NEAR(static_cast<double>(stop_steps()), kQuickStopSteps, 25);
  EXPECT_EQ(state(), kFault);
}

TEST_F(CyclicStop, CsvFaultReactionOption1RampsWith6084h) {
  run_up(Mode::CyclicSyncVelocity, Options{.fault_reaction = 1});
  drive.fault(0x5530, now);
  syncs_for(1100);
  EXPECT_NEAR(static_cast<double>(stop_steps()), kSlowDownSteps, 25);
  EXPECT_EQ(state(), kFault);
}

TEST_F(CyclicStop, AModeChangeOutOfCsvRampsDownWith6084hFirst) {
  run_up(Mode::CyclicSyncVelocity);
  velocity = 0;  // 60FFh 0 from here: PV's target once it takes over
  drive.set_mode(Mode::ProfileVelocity, now);
  syncs_for(100);  // SYNCs of the old mode do not restart it
  EXPECT_TRUE(core.moving());
  EXPECT_EQ(drive.mode_display(), Mode::CyclicSyncVelocity) << "6061h once the ramp has ended";
  syncs_for(1000);
  EXPECT_NEAR(static_cast<double>(stop_steps()), kSlowDownSteps, 25);
  EXPECT_EQ(drive.mode_display(), Mode::ProfileVelocity);
}

TEST_F(CyclicStop, AModeChangeOutOfCspRampsDownWith6084hFirst) {
  run_up(Mode::CyclicSyncPosition);
  drive.set_mode(Mode::ProfilePosition, now);
  syncs_for(100);
  EXPECT_TRUE(core.moving());
  syncs_for(1000);
  EXPECT_NEAR(static_cast<double>(stop_steps()), kSlowDownSteps, 25);
  EXPECT_EQ(drive.mode_display(), Mode::ProfilePosition);
}

// "Current limit", "voltage limit" (605Ah 3, 4, 7, 8; 605Dh and 605Eh 3, 4) and "disable
// drive function" (605Ch 0, disable voltage) stop the pulses at once, in CSV and CSP.
constexpr int32_t kAFault = -1;
struct AtOnceRow {
  const char* what;  // the test's name
  Options options;
  int32_t controlword;  // kAFault: a fault (603Fh 5530h) instead
};
void PrintTo(const AtOnceRow& row, std::ostream* os) { *os << row.what; }
class StopAtOnce : public CyclicStop,
                   public ::testing::WithParamInterface<std::tuple<AtOnceRow, Mode>> {};

TEST_P(StopAtOnce, StopsThePulsesAtOnce) {
  const auto& [row, mode] = GetParam();
  run_up(mode, row.options);
  if (row.controlword == kAFault) drive.fault(0x5530, now);
  else cw(static_cast<uint16_t>(row.controlword));
  EXPECT_FALSE(core.moving());
  syncs_for(100);
  EXPECT_EQ(stop_steps(), 0);
}

INSTANTIATE_TEST_SUITE_P(
    CyclicModes, StopAtOnce,
    ::testing::Combine(
        ::testing::Values(AtOnceRow{"QuickStop3", {.quick_stop = 3}, 0x0B},
                          AtOnceRow{"QuickStop4", {.quick_stop = 4}, 0x0B},
                          AtOnceRow{"QuickStop7", {.quick_stop = 7}, 0x0B},
                          AtOnceRow{"QuickStop8", {.quick_stop = 8}, 0x0B},
                          AtOnceRow{"Halt3", {.halt = 3}, 0x010F},
                          AtOnceRow{"Halt4", {.halt = 4}, 0x010F},
                          AtOnceRow{"FaultReaction3", {.fault_reaction = 3}, kAFault},
                          AtOnceRow{"FaultReaction4", {.fault_reaction = 4}, kAFault},
                          AtOnceRow{"DisableOperation0", {.disable_operation = 0}, 0x07},
                          AtOnceRow{"DisableVoltage", {}, 0x00}),
        ::testing::Values(Mode::CyclicSyncVelocity, Mode::CyclicSyncPosition)),
    [](const auto& info) {
      return std::get<0>(info.param).what + std::string(name(std::get<1>(info.param)));
    });

}  // namespace
}  // namespace stepnode::cia402
