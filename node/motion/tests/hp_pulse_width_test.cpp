// The HP 44714A's pulse widths at its outputs (issue 11 item 12): each pulse leaves the step
// port with its width (PROFILE FREQ's pwidth, 3-8; the WIDTH-mode width SUSTAIN ramps to,
// 3-25..3-28), the simulated drive records it, and the channel shows the width now.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "node/motion/tests/hp_channel_fixture.hpp"

namespace stepnode::motion::hp {
namespace {

double seconds(Tick t) { return static_cast<double>(t) / static_cast<double>(kClockHz); }
uint32_t us_to_ns(double us) { return static_cast<uint32_t>(std::llround(us)) * 1000u; }

class HpPulseWidth : public HpChannel, public ::testing::WithParamInterface<Tick> {
 protected:
  void SetUp() override {
    HpChannel::SetUp();
    motor->set_horizon(GetParam());  // at its time, or queued ahead of it
    motor->trace_pulses_into(&train);
  }
  std::vector<sim::TracedPulse> train;
};

// 3-28's example, PROFILE WIDTH 1E-3 10E-3 5E-3 20E-3 and SUSTAIN 2E-3: 50 pulses a second,
// the width from the minimum (1 ms) up at 5 ms/s to 2 ms. Each pulse's width is the ramp's
// at its time, to appendix A's 1 us; then a SUSTAIN 1.5E-3 given during the train ramps it
// down from there (pulses queued ahead of the change get the new ramp too).
TEST_P(HpPulseWidth, Hp3_25To3_28_WidthModePulsesCarryTheRampedWidth) {
  ASSERT_EQ(ch->profile(width(1e-3, 10e-3, 5e-3, 20e-3), now), Conflict::None);
  const Tick start = now;
  ASSERT_EQ(ch->sustain(2e-3, true, now), Error::None);
  wait(500);
  ASSERT_GE(train.size(), 24u);
  for (const sim::TracedPulse& p : train) {
    const double t = seconds(p.time - start);
    EXPECT_EQ(p.width_ns, us_to_ns(std::min(2e-3, 1e-3 + 5e-3 * t) * 1e6))
        << "pulse at " << t << " s";
  }
  EXPECT_EQ(motor->last_pulse_width_ns(), 2'000'000u);
  EXPECT_DOUBLE_EQ(ch->current_width(), 2e-3);

  train.clear();
  const Tick change = now;
  ASSERT_EQ(ch->sustain(1.5e-3, true, now), Error::None);
  wait(300);
  ASSERT_GE(train.size(), 14u);
  for (const sim::TracedPulse& p : train) {
    const double t = seconds(p.time - change);
    EXPECT_EQ(p.width_ns, us_to_ns(std::max(1.5e-3, 2e-3 - 5e-3 * t) * 1e6))
        << "pulse at " << t << " s";
  }
  EXPECT_EQ(motor->last_pulse_width_ns(), 1'500'000u);
  EXPECT_DOUBLE_EQ(ch->current_width(), 1.5e-3);
  // HALT SGL: no pulse train, no width.
  ch->halt_sgl(now);
  EXPECT_EQ(ch->current_width(), 0);
}

// 3-8: "pwidth: pulse width of all pulses generated", in a MOVE and a SUSTAIN alike.
TEST_P(HpPulseWidth, Hp3_8_FreqModePulsesAllHaveThePwidth) {
  ASSERT_EQ(ch->profile(freq(100, 800, 200, 25e-6), now), Conflict::None);
  ASSERT_EQ(ch->move(20, false, true, now), Error::None);
  wait(100);
  EXPECT_DOUBLE_EQ(ch->current_width(), 25e-6);
  wait(2000);
  ASSERT_EQ(done(), 0);
  ASSERT_EQ(train.size(), 20u);
  for (const sim::TracedPulse& p : train) EXPECT_EQ(p.width_ns, 25'000u);
  EXPECT_EQ(ch->current_width(), 0);  // no pulses now
  ASSERT_EQ(ch->profile(freq(100, 500, 200, 1.5e-3), now), Conflict::None);
  ASSERT_EQ(ch->sustain(-300, true, now), Error::None);
  wait(500);
  EXPECT_EQ(motor->last_pulse_width_ns(), 1'500'000u);
  EXPECT_DOUBLE_EQ(ch->current_width(), 1.5e-3);
}

INSTANTIATE_TEST_SUITE_P(Horizons, HpPulseWidth, ::testing::Values(Tick{0}, ms(1), ms(100)));

// A step given without output signals (a Horner or CiA 402 job) has no width of the HP's.
TEST_F(HpChannel, Hp3_25_AStepWithoutAPulseWidthRecordsNone) {
  std::vector<sim::TracedPulse> train;
  motor->trace_pulses_into(&train);
  ASSERT_EQ(ch->profile(freq(100, 800, 200, 25e-6), now), Conflict::None);
  ASSERT_EQ(ch->move(3, false, true, now), Error::None);
  wait(1000);
  EXPECT_EQ(motor->last_pulse_width_ns(), 25'000u);
  motor->step(now, +1);
  EXPECT_EQ(motor->last_pulse_width_ns(), 0u);
  ASSERT_EQ(train.size(), 4u);
  EXPECT_EQ(train.back().width_ns, 0u);
}

}  // namespace
}  // namespace stepnode::motion::hp
