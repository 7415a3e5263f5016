// The cyclic modes in virtual time (CiA 402-2 CSP, CSV, IP): a set-point every SYNC, and the
// step times against the ideal trajectory of the drive's linear interpolation (the set-point
// of SYNC k reached at SYNC k+1, at a constant rate in between): each step within one tick
// of the instant the ideal trajectory reaches it. SYNC jitter, a missed SYNC, the velocity
// mode and the following error.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <vector>

#include "node/profiles/cia402/tests/drive_harness.hpp"

namespace stepnode::cia402 {
namespace {

class Cyclic : public DriveAxis {
 protected:
  void enable(Mode m) {
    drive.parameters().max_velocity = 1'000'000;
    drive.set_mode(m, now);
    DriveAxis::enable();
  }
  // A SYNC at `t` carrying `target` (CSP): the RPDO is applied, then the SYNC acts.
  void sync_to(Tick t, int32_t target) {
    drive.advance(now = t);
    drive.set_target_position(target);
    drive.sync(t, t);
  }
};

// The master's trajectory: up at 5 steps a cycle, then back down at 3, at 1 kHz SYNC.
std::vector<int32_t> master_trajectory() {
  std::vector<int32_t> p;
  int32_t x = 0;
  for (int k = 0; k < 200; ++k) p.push_back(x += 5);
  for (int k = 0; k < 200; ++k) p.push_back(x -= 3);
  return p;
}

// Every step against the ideal: the step to position x falls when the interpolated
// trajectory (from the position at SYNC k to set-point k over one cycle) reaches x.
void expect_on_trajectory(const std::vector<sim::TracedStep>& steps,
                          const std::vector<int32_t>& targets, Tick cycle, Tick first) {
  size_t s = 0;
  int64_t pos = 0;
  Tick worst = 0;
  for (size_t k = 0; k < targets.size(); ++k) {
    const Tick start = first + static_cast<Tick>(k) * cycle;
    const int64_t from = pos, n = std::llabs(targets[k] - from);
    for (int64_t i = 1; i <= n; ++i, ++s) {
      ASSERT_LT(s, steps.size());
      const double ideal =
          static_cast<double>(start) + static_cast<double>(i) * static_cast<double>(cycle) / n;
      worst =
          std::max<Tick>(worst, std::llabs(steps[s].time - static_cast<Tick>(std::llround(ideal))));
      pos += steps[s].direction;
    }
    ASSERT_EQ(pos, targets[k]) << "after cycle " << k;
  }
  EXPECT_EQ(s, steps.size());
  EXPECT_LE(worst, 1) << "ticks off the ideal trajectory";
}

TEST_F(Cyclic, CspAt1kHzFollowsTheLinearInterpolationToATick) {
  enable(Mode::CyclicSyncPosition);
  const Tick cycle = kClockHz / 1000;
  const std::vector<int32_t> targets = master_trajectory();
  for (size_t k = 0; k < targets.size(); ++k) {
    sync_to(cycle * static_cast<Tick>(k + 1), targets[k]);
    EXPECT_TRUE(drive.statusword() & (1u << 12));  // the drive follows
  }
  drive.advance(now += 2 * cycle);
  expect_on_trajectory(motor.steps, targets, cycle, cycle);
}

TEST_F(Cyclic, CspAt100HzToo) {
  enable(Mode::CyclicSyncPosition);
  const Tick cycle = kClockHz / 100;
  drive.parameters().interpolation_period =
      cycle;  // 60C2h: the first cycle, before SYNCs are timed
  std::vector<int32_t> targets;
  for (int k = 1; k <= 100; ++k)
    targets.push_back(static_cast<int32_t>(std::lround(2000 * std::sin(k * 0.05))));
  for (size_t k = 0; k < targets.size(); ++k) sync_to(cycle * static_cast<Tick>(k + 1), targets[k]);
  drive.advance(now += 2 * cycle);
  expect_on_trajectory(motor.steps, targets, cycle, cycle);
}

TEST_F(Cyclic, SyncJitterNeitherLosesNorJumps) {
  enable(Mode::CyclicSyncPosition);
  const Tick cycle = kClockHz / 1000;
  std::mt19937 rng(7);
  std::uniform_int_distribution<Tick> jitter(-cycle / 20, cycle / 20);  // +-50 us
  const std::vector<int32_t> targets = master_trajectory();
  for (size_t k = 0; k < targets.size(); ++k) {
    const Tick t = cycle * static_cast<Tick>(k + 1) + jitter(rng);
    sync_to(t, targets[k]);
    // At each SYNC the axis is within one cycle's motion of the last set-point.
    if (k > 0) {
      EXPECT_LE(std::llabs(int64_t{drive.position_actual()} - targets[k - 1]), 5);
    }
  }
  drive.advance(now += 3 * cycle);
  EXPECT_EQ(drive.position_actual(), targets.back());
  EXPECT_EQ(motor.position(), targets.back());
  // No step closer than a quarter of the fastest rate's interval (no catching up in a burst).
  for (size_t i = 1; i < motor.steps.size(); ++i)
    EXPECT_GE(motor.steps[i].time - motor.steps[i - 1].time, cycle / 5 / 4) << i;
}

TEST_F(Cyclic, AMissedSyncHoldsTheLastSetPoint) {
  enable(Mode::CyclicSyncPosition);
  const Tick cycle = kClockHz / 1000;
  for (int k = 1; k <= 10; ++k) sync_to(cycle * k, 10 * k);
  drive.advance(now = 12 * cycle);          // SYNC 11 does not come
  EXPECT_EQ(drive.position_actual(), 100);  // no extrapolation
  drive.advance(now = 13 * cycle);
  EXPECT_EQ(drive.position_actual(), 100);
  sync_to(13 * cycle, 130);  // the master goes on: one cycle to the new set-point
  drive.advance(now = 14 * cycle);
  EXPECT_EQ(drive.position_actual(), 130);
}

// One lost SYNC (a 2 ms gap in a 1 ms stream, 60C2h = 1 ms) is an odd interval, not a
// longer cycle (it was averaged in: a cycle of 1.25 ms, each set-point reached late): the
// set-point of every SYNC after it is reached one 1 ms period later.
TEST_F(Cyclic, OneLostSyncDoesNotStretchTheInterpolationPeriod) {
  enable(Mode::CyclicSyncPosition);
  for (int k = 1; k <= 10; ++k) sync_to(ms(k), 10 * k);
  // SYNC 11 is lost; the master's trajectory goes on at 10 steps a cycle.
  for (int k = 12; k <= 20; ++k) {
    sync_to(ms(k), 10 * k);
    drive.advance(now = ms(k + 1));  // up to the next SYNC, before it is handled
    EXPECT_EQ(drive.position_actual(), 10 * k)
        << "the set-point of the SYNC at " << k << " ms, one 1 ms period later";
  }
}

// Two SYNCs read out of a queued socket microseconds apart must not become the cycle (the
// axis would be capped at a few steps a SYNC for good), and a period other than 60C2h's is
// taken after three SYNCs that agree.
TEST_F(Cyclic, ASyncBurstIsNotTheCycleAndANewPeriodIsTaken) {
  enable(Mode::CyclicSyncPosition);
  const Tick cycle = kClockHz / 100;  // 10 ms SYNC; 60C2h left at its 1 ms
  sync_to(cycle, 0);
  sync_to(cycle + 50, 0);  // the burst
  for (int k = 2; k <= 101; ++k) sync_to(cycle * k, 20 * (k - 1));
  drive.advance(now += cycle);
  EXPECT_EQ(drive.position_actual(), 2000);
  // At the steady period each segment is spread over the whole cycle: 20 steps in 10 ms.
  const size_t n = motor.steps.size();
  EXPECT_NEAR(static_cast<double>(motor.steps[n - 1].time - motor.steps[n - 20].time),
              19.0 * cycle / 20, cycle / 20);
}

TEST_F(Cyclic, CsvChangesTheVelocityAtEachSyncWithoutLosingAStep) {
  enable(Mode::CyclicSyncVelocity);
  const Tick cycle = kClockHz / 1000;
  double ideal = 0;  // steps of the ideal piecewise-constant velocity
  for (int k = 1; k <= 500; ++k) {
    const int32_t v = 300 + 7 * k;  // steps/s, a new one each cycle
    drive.advance(now = cycle * k);
    drive.set_target_velocity(v, now);
    drive.sync(now, now);
    ideal += v / 1000.0;
    EXPECT_EQ(drive.velocity_actual(), v);
  }
  drive.advance(now += cycle);
  drive.set_target_velocity(0, now);
  drive.sync(now, now);
  EXPECT_NEAR(motor.position(), ideal, 1.0);
}

TEST_F(Cyclic, ALaggingAxisReportsAFollowingErrorAndFaults) {
  enable(Mode::CyclicSyncPosition);
  drive.parameters().max_velocity = 1000;  // steps/s: the master asks for 5000
  drive.parameters().following_error_window = 20;
  drive.parameters().following_error_timeout_ms = 5;
  const Tick cycle = kClockHz / 1000;
  for (int k = 1; k <= 40; ++k) sync_to(cycle * k, 5 * k);
  EXPECT_EQ(drive.statusword() & 0x4F, 0x08);  // fault
  EXPECT_EQ(drive.error_code(), 0x8611);
}

TEST_F(Cyclic, InterpolatedPositionRunsOnlyWithBit4) {
  enable(Mode::InterpolatedPosition);
  const Tick cycle = kClockHz / 1000;
  drive.set_ip_set_point(50);
  for (int k = 1; k <= 3; ++k) {
    drive.advance(now = k * cycle);
    drive.sync(now, now);
  }
  EXPECT_EQ(drive.position_actual(), 0);  // interpolation not enabled
  drive.controlword(0x1F, now);           // enable ip
  EXPECT_TRUE(drive.statusword() & (1u << 12));
  drive.advance(now = 4 * cycle);
  drive.sync(now, now);
  drive.advance(now = 5 * cycle);
  EXPECT_EQ(drive.position_actual(), 50);
  EXPECT_TRUE(drive.statusword() & (1u << 10));  // at the set-point
}

}  // namespace
}  // namespace stepnode::cia402
