// The simulated machine behind an axis, input by input: switches, limits, the index input and
// the encoder marker are pure functions of the mechanical position (so the step at which any
// input changes is exact); encoder counts per type (SPM30 5.1, STP100 6.2) at positive and
// negative positions; and the faults (stall, missed steps, external displacement).
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "node/sim/machine.hpp"

namespace stepnode::sim {
namespace {

// Moves the machine to `p` with single steps, as an axis would.
void step_to(AxisMachine& m, int64_t p) {
  while (m.position() < p) m.step(+1);
  while (m.position() > p) m.step(-1);
}

TEST(SimMachineModel, CamIsActiveOnItsHalfOpenRange) {
  Cam c{-5, 3};
  EXPECT_FALSE(c.contains(-6));
  EXPECT_TRUE(c.contains(-5));
  EXPECT_TRUE(c.contains(-3));
  EXPECT_FALSE(c.contains(-2));
  Cam one{7, 1};
  EXPECT_TRUE(one.contains(7));
  EXPECT_FALSE(one.contains(6));
  EXPECT_FALSE(one.contains(8));
}

TEST(SimMachineModel, HomeSwitchChangesOnTheExactStepBothWays) {
  AxisMachineConfig c;
  c.home = Cam{100, 40};
  AxisMachine m(c);
  std::vector<int64_t> edges;
  bool was = m.home();
  for (int i = 0; i < 200; ++i) {
    m.step(+1);
    if (m.home() != was) edges.push_back(m.position());
    was = m.home();
  }
  for (int i = 0; i < 200; ++i) {
    m.step(-1);
    if (m.home() != was) edges.push_back(m.position());
    was = m.home();
  }
  // Up: on at 100, off at 140. Down: on at 139, off at 99.
  EXPECT_EQ(edges, (std::vector<int64_t>{100, 140, 139, 99}));
}

TEST(SimMachineModel, LimitsAreActiveAtAndBeyondTheirPositions) {
  AxisMachineConfig c;
  c.lower_limit = -10;
  c.upper_limit = 10;
  AxisMachine m(c);
  EXPECT_FALSE(m.lower_limit() || m.upper_limit());
  step_to(m, 9);
  EXPECT_FALSE(m.upper_limit());
  m.step(+1);
  EXPECT_TRUE(m.upper_limit());
  m.displace(1000);
  EXPECT_TRUE(m.upper_limit());  // still on far past it
  step_to(m, -9);
  EXPECT_FALSE(m.lower_limit());
  m.step(-1);
  EXPECT_TRUE(m.lower_limit());
  EXPECT_FALSE(m.upper_limit());
  m.displace(-1'000'000);
  EXPECT_TRUE(m.lower_limit());
  // Without limit switches configured, never active.
  AxisMachine free_machine{AxisMachineConfig{}};
  free_machine.displace(1LL << 40);
  EXPECT_FALSE(free_machine.upper_limit());
  free_machine.displace(-(1LL << 41));
  EXPECT_FALSE(free_machine.lower_limit());
  EXPECT_FALSE(free_machine.home());
  EXPECT_FALSE(free_machine.index());
}

TEST(SimMachineModel, IndexInputIsItsOwnCam) {
  AxisMachineConfig c;
  c.index = Cam{-3010, 10};
  c.home = Cam{0, 1};
  AxisMachine m(c);
  EXPECT_TRUE(m.home());
  EXPECT_FALSE(m.index());
  step_to(m, -3000);
  EXPECT_FALSE(m.index());
  m.step(-1);
  EXPECT_TRUE(m.index());  // first active step moving down: -3001
  step_to(m, -3010);
  EXPECT_TRUE(m.index());
  m.step(-1);
  EXPECT_FALSE(m.index());
}

TEST(SimMachineModel, MarkerOncePerRevolutionAtItsOffsetIncludingNegativePositions) {
  AxisMachineConfig c;
  c.encoder = EncoderKind::Quadrature;
  c.steps_per_rev = 2000;
  c.marker_offset = 300;
  c.marker_width = 4;
  AxisMachine m(c);
  m.displace(-10'000);
  std::vector<int64_t> starts;
  int active = 0;
  bool was = m.marker();
  while (m.position() < 10'000) {
    m.step(+1);
    if (m.marker()) ++active;
    if (m.marker() && !was) starts.push_back(m.position());
    was = m.marker();
  }
  EXPECT_EQ(starts,
            (std::vector<int64_t>{-9700, -7700, -5700, -3700, -1700, 300, 2300, 4300, 6300, 8300}));
  EXPECT_EQ(active, 10 * 4);  // 4 steps wide each
  // A negative offset is the same marker one revolution earlier.
  c.marker_offset = -1700;
  AxisMachine n(c);
  n.displace(300);
  EXPECT_TRUE(n.marker());
  n.displace(-2000);
  EXPECT_TRUE(n.marker());
}

TEST(SimMachineModel, OnlyAQuadratureEncoderWithMarkerHasAMarker) {
  for (EncoderKind kind :
       {EncoderKind::None, EncoderKind::UpDown, EncoderKind::QuadratureNoMarker}) {
    AxisMachineConfig c;
    c.encoder = kind;
    c.marker_offset = 0;
    AxisMachine m(c);
    bool any = false;
    for (int i = 0; i < 4000; ++i) {
      any = any || m.marker();
      m.step(+1);
    }
    EXPECT_FALSE(any) << static_cast<int>(kind);  // SPM30 5.1: QUAD N/M, U/D, NONE
  }
  AxisMachineConfig c;
  c.steps_per_rev = 0;  // a degenerate revolution has no marker (and no counts)
  AxisMachine m(c);
  EXPECT_FALSE(m.marker());
  EXPECT_EQ(m.encoder_count(), 0);
}

TEST(SimMachineModel, QuadratureCountsFourPerLineAndFloorsNegativePositions) {
  AxisMachineConfig c;
  c.encoder = EncoderKind::Quadrature;
  c.steps_per_rev = 2000;
  c.encoder_lines = 500;  // x4: one count per step
  AxisMachine m(c);
  EXPECT_EQ(m.encoder_counts_per_rev(), 2000);
  for (int64_t p : {-4001, -1, 0, 1, 1999, 2000, 123457}) {
    AxisMachine k(c);
    k.displace(p);
    EXPECT_EQ(k.encoder_count(), p) << p;
  }
  // 2000 steps against 250 lines x4 = 1000 counts: a count every 2 steps, rounded down.
  c.encoder_lines = 250;
  for (auto [p, counts] : std::vector<std::pair<int64_t, int64_t>>{
           {-3, -2}, {-2, -1}, {-1, -1}, {0, 0}, {1, 0}, {3, 1}}) {
    AxisMachine k(c);
    k.displace(p);
    EXPECT_EQ(k.encoder_count(), counts) << p;
  }
  // 200 steps against 1000 lines x4: 20 counts per step.
  c.steps_per_rev = 200;
  c.encoder_lines = 1000;
  AxisMachine fine(c);
  step_to(fine, -7);
  EXPECT_EQ(fine.encoder_count(), -140);
}

TEST(SimMachineModel, UpDownCountsOnePerLineBothWays) {
  AxisMachineConfig c;
  c.encoder = EncoderKind::UpDown;
  c.steps_per_rev = 200;
  c.encoder_lines = 1000;  // SPM30 5.3: 1000 lines on 200 steps: 5 counts per step
  AxisMachine m(c);
  EXPECT_EQ(m.encoder_counts_per_rev(), 1000);
  step_to(m, 37);
  EXPECT_EQ(m.encoder_count(), 185);
  step_to(m, -37);  // counts down as it moves down
  EXPECT_EQ(m.encoder_count(), -185);
  c.encoder = EncoderKind::QuadratureNoMarker;  // counts like quadrature, only no marker
  AxisMachine q(c);
  step_to(q, -37);
  EXPECT_EQ(q.encoder_count(), -740);
  c.encoder = EncoderKind::None;
  AxisMachine none(c);
  step_to(none, 50);
  EXPECT_EQ(none.encoder_count(), 0);
  EXPECT_EQ(none.encoder_counts_per_rev(), 0);
}

TEST(SimMachineModel, StallAtAPositionJamsOnlyTowardIt) {
  AxisMachineConfig c;
  c.stall_above = 3;
  c.stall_below = -2;
  AxisMachine m(c);
  for (int i = 0; i < 10; ++i) m.step(+1);
  EXPECT_EQ(m.position(), 3);  // reaches it, cannot pass
  m.step(-1);
  EXPECT_EQ(m.position(), 2);  // backing away works at once
  for (int i = 0; i < 10; ++i) m.step(-1);
  EXPECT_EQ(m.position(), -2);
  EXPECT_EQ(m.pulses_received(), 21u);  // every pulse arrived at the drive
  m.config().stall_above.reset();       // the jam is cleared
  for (int i = 0; i < 10; ++i) m.step(+1);
  EXPECT_EQ(m.position(), 8);
}

TEST(SimMachineModel, MissedStepsLoseEveryNthPulseInEitherDirection) {
  AxisMachineConfig c;
  c.miss_every = 4;
  AxisMachine m(c);
  for (int i = 0; i < 40; ++i) m.step(+1);
  EXPECT_EQ(m.position(), 30);
  for (int i = 0; i < 40; ++i) m.step(-1);
  EXPECT_EQ(m.position(), 0);
  EXPECT_EQ(m.pulses_received(), 80u);
}

TEST(SimMachineModel, ExternalDisplacementMovesTheInputsWithoutPulses) {
  AxisMachineConfig c;
  c.home = Cam{50, 5};
  c.encoder = EncoderKind::Quadrature;  // 2000 steps, 500 lines: 1:1
  c.stall_above = 10;                   // a jam does not hold back an external force
  AxisMachine m(c);
  m.displace(52);
  EXPECT_EQ(m.position(), 52);
  EXPECT_TRUE(m.home());
  EXPECT_EQ(m.encoder_count(), 52);  // the encoder sees the real motion
  EXPECT_EQ(m.pulses_received(), 0u);
  m.displace(-60);
  EXPECT_EQ(m.encoder_count(), -8);
  EXPECT_FALSE(m.home());
}

TEST(SimMachineModel, StepSinkRecordsPulsesTimesAndDirections) {
  AxisMachine m;
  motion::MotorPort& port = m;  // what an axis drives
  port.step(100, +1);
  port.step(250, +1);
  port.step(400, -1);
  port.step(401, 0);  // any non-negative direction is up
  EXPECT_EQ(m.position(), 2);
  EXPECT_EQ(m.pulses_received(), 4u);
  EXPECT_EQ(m.last_step_time(), 401);
  m.step(-1);  // untimed: at the last step's time
  EXPECT_EQ(m.last_step_time(), 401);
  EXPECT_EQ(port.encoder_count(), 1);  // default: 2000 steps, 500 lines quadrature
}

TEST(SimMachineModel, MachineHoldsItsAxesAndTheSharedEmergencyStop) {
  Machine machine;
  EXPECT_FALSE(machine.emergency_stop());
  machine.axes.resize(3);
  machine.axes[1].step(+1);
  machine.axes[2].displace(-5);
  EXPECT_EQ(machine.axes[0].position(), 0);
  EXPECT_EQ(machine.axes[1].position(), 1);
  EXPECT_EQ(machine.axes[2].position(), -5);
}

}  // namespace
}  // namespace stepnode::sim
