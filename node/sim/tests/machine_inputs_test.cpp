// The simulated machine: inputs are pure functions of the mechanical position, encoder
// counts per kind (SPM30 5.1: quadrature x4, up/down, quadrature without marker), faults.
#include <gtest/gtest.h>

#include "node/sim/machine.hpp"

namespace stepnode::sim {
namespace {

TEST(SimMachine, SwitchesAreFunctionsOfPosition) {
  AxisMachineConfig c;
  c.home = Cam{100, 3};
  c.lower_limit = -50;
  c.upper_limit = 50'000;
  c.index = Cam{-10, 2};
  AxisMachine m(c);
  m.displace(99);
  EXPECT_FALSE(m.home());
  m.step(+1);
  EXPECT_TRUE(m.home());  // exactly the step onto the cam
  m.displace(2);
  EXPECT_TRUE(m.home());
  m.step(+1);
  EXPECT_FALSE(m.home());
  m.displace(-113);
  EXPECT_TRUE(m.index());
  m.displace(-40);
  EXPECT_TRUE(m.lower_limit());
  EXPECT_FALSE(m.upper_limit());
}

TEST(SimMachine, EncoderKindsAndMarker) {
  AxisMachineConfig c;
  c.steps_per_rev = 200;
  c.encoder_lines = 1000;  // SPM30 5.3: 1000 lines, 200 steps: MLT 1 / DIV 5 per line
  c.marker_offset = 0;
  c.marker_width = 1;
  for (EncoderKind kind : {EncoderKind::Quadrature, EncoderKind::UpDown,
                           EncoderKind::QuadratureNoMarker, EncoderKind::None}) {
    c.encoder = kind;
    AxisMachine m(c);
    m.displace(-200);  // one revolution down
    int64_t per_rev = kind == EncoderKind::UpDown ? 1000 : kind == EncoderKind::None ? 0 : 4000;
    EXPECT_EQ(m.encoder_count(), -per_rev) << int(kind);
    EXPECT_EQ(m.encoder_counts_per_rev(), per_rev);
    // Only a quadrature encoder with a marker has one (SPM30 5.1 QUAD vs QUAD N/M).
    EXPECT_EQ(m.marker(), kind == EncoderKind::Quadrature) << int(kind);
    m.step(+1);
    EXPECT_FALSE(m.marker());
  }
}

TEST(SimMachine, FaultsJamLoseAndRecordTheStepSink) {
  AxisMachineConfig c;
  c.stall_above = 5;
  c.miss_every = 3;
  AxisMachine m(c);
  for (int i = 0; i < 12; ++i) m.step(motion::Tick{i * 10}, +1);
  EXPECT_EQ(m.pulses_received(), 12u);
  EXPECT_EQ(m.position(), 5);  // 8 followed, but jammed at 5
  EXPECT_EQ(m.last_step_time(), 110);
}

}  // namespace
}  // namespace stepnode::sim
