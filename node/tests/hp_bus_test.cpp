// The HP 44714A manual's example programs replayed through the bus objects of a node in
// virtual time (every command an SDO write, every query an SDO read, the interrupt as TPDO
// 4 and EMCY): Figure 3-3 "Sending Pulses To a Motor", the interrupt example (3-16), the
// PSCALE round-off examples (3-10), the PROFILE conflicts and error numbers as aborts, and
// TRIG SYS on a SYNC frame (with what changed while the MOVE waited for it).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "node/profiles/hp44714a/objects.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

using namespace hp44714a::obj;

class HpBus : public NodeHarness {
 protected:
  void SetUp() override { build(1); }
  void build(unsigned axes) {
    make(axes);
    nmt(0x01);  // operational: TPDOs go out
  }

  int done(unsigned a = 0) { return static_cast<int8_t>(*sdo_read(index(a, kDone), 0)); }
  int error(unsigned a = 0) { return static_cast<int>(*sdo_read(index(a, kError), 0)); }
  int32_t mechanical(unsigned a = 0) {
    return static_cast<int32_t>(*sdo_read(static_cast<uint16_t>(0x5003 + 0x100 * a), 0));
  }

  // The manual's words as object writes.
  uint32_t profile(uint8_t mode, double min, double max, double slope, double last,
                   unsigned a = 0) {
    uint16_t p = index(a, kProfile);
    EXPECT_EQ(put_int<uint8_t>(p, hp44714a::profile_sub::kMode, mode), 0u);
    EXPECT_EQ(put(p, hp44714a::profile_sub::kMin, min), 0u);
    EXPECT_EQ(put(p, hp44714a::profile_sub::kMax, max), 0u);
    EXPECT_EQ(put(p, hp44714a::profile_sub::kSlope, slope), 0u);
    EXPECT_EQ(put(p, hp44714a::profile_sub::kLast, last), 0u);
    return put_int<uint8_t>(p, hp44714a::profile_sub::kApply, 1);
  }
  uint32_t move(double d, bool abs = false, bool nowait = false, unsigned a = 0) {
    EXPECT_EQ(put_int<uint8_t>(index(a, kMove), hp44714a::move_sub::kNowait, nowait ? 1 : 0), 0u);
    return put(index(a, kMove), abs ? hp44714a::move_sub::kAbsolute : hp44714a::move_sub::kRelative,
               d);
  }
  uint32_t sustain(double v, bool nowait = false, unsigned a = 0) {
    EXPECT_EQ(put_int<uint8_t>(index(a, kMove), hp44714a::move_sub::kNowait, nowait ? 1 : 0), 0u);
    return put(index(a, kSustain), 0, v);
  }
  uint32_t trig(uint8_t mode, unsigned a = 0) { return sdo_write(index(a, kTrig), 0, mode, 1); }
  // HP-IB "WAIT n" / the operator's PAUSE: virtual time passes.
  void wait_s(double s) { advance_us(static_cast<uint64_t>(s * 1e6)); }
};

constexpr uint32_t kDeviceState = 0x08000022, kIncompatible = 0x06040043;
constexpr uint32_t kTpdo4 = 0x480 + 5;

TEST_F(HpBus, Figure3_3SendingPulsesToAMotor) {
  // 30 STANDBY AUTO LO / 40 PULSE SS HI HI / 50 PROFILE FREQ 100 800 200 25E-6 / 60 PSCALE 0.1
  uint16_t out = index(0, kOutput);
  ASSERT_EQ(sdo_write(out, hp44714a::output_sub::kStandbyMode, 2, 1), 0u);
  ASSERT_EQ(sdo_write(out, hp44714a::output_sub::kStandbySense, 0, 1), 0u);
  ASSERT_EQ(sdo_write(out, hp44714a::output_sub::kPulseMode, 1, 1), 0u);
  ASSERT_EQ(sdo_write(out, hp44714a::output_sub::kPstpSense, 1, 1), 0u);
  ASSERT_EQ(sdo_write(out, hp44714a::output_sub::kNdirSense, 1, 1), 0u);
  ASSERT_EQ(profile(0, 100, 800, 200, 25e-6), 0u);
  ASSERT_EQ(put(index(0, kPscale), 0, 0.1), 0u);
  EXPECT_EQ(*sdo_read(out, hp44714a::output_sub::kStbyLevel), 0u);  // LO sense: low = power removed

  // 70 MOVE 20 (auto triggered): 200 pulses; 90 MOVE -30: 300 pulses back.
  ASSERT_EQ(move(20), 0u);
  EXPECT_EQ(*sdo_read(out, hp44714a::output_sub::kStbyLevel), 1u);  // motor power on
  wait_s(3);
  EXPECT_EQ(done(), 0);
  EXPECT_EQ(mechanical(), 200);
  EXPECT_NEAR(get(index(0, kPosition)), 20.0, 1e-9);
  ASSERT_EQ(move(-30), 0u);
  wait_s(4);
  EXPECT_EQ(mechanical(), -100);
  EXPECT_NEAR(get(index(0, kPosition)), -10.0, 1e-9);
  // SS mode: the negative pulses went to NDIR.
  EXPECT_EQ(*sdo_read(out, hp44714a::output_sub::kPstpPulses), 200u);
  EXPECT_EQ(*sdo_read(out, hp44714a::output_sub::kNdirPulses), 300u);

  // 70 DELAY 5 / 80 TRIG HOLD / 90 MOVE 20 NOWAIT / 100 TRIG
  ASSERT_EQ(sdo_write(index(0, kDelay), 0, 5000, 2), 0u);
  ASSERT_EQ(trig(0), 0u);
  ASSERT_EQ(move(20, false, true), 0u);
  wait_s(1);
  EXPECT_EQ(done(), -3);
  EXPECT_EQ(mechanical(), -100);
  ASSERT_EQ(trig(2), 0u);
  EXPECT_EQ(*sdo_read(index(0, kTrig), 0), 0u);  // back to HOLD
  wait_s(4.9);
  EXPECT_EQ(done(), -2);  // the delay runs
  EXPECT_EQ(mechanical(), -100);
  wait_s(3);
  EXPECT_EQ(mechanical(), 100);
  EXPECT_EQ(static_cast<int32_t>(
                *sdo_read(index(0, kTiming), hp44714a::timing_sub::kFirstStepAfterTriggerUs)) /
                1000,
            5000 + 10 - 1);  // DELAY 5 s, then the first pulse at 100 Hz rising (just under 10 ms)
  // 120 MOVE -30 NOWAIT / 130 TRIG / 150 TRIG AUTO
  ASSERT_EQ(move(-30, false, true), 0u);
  ASSERT_EQ(trig(2), 0u);
  wait_s(9);
  EXPECT_EQ(mechanical(), -200);
  EXPECT_NEAR(get(index(0, kPosition)), -20.0, 1e-9);
  ASSERT_EQ(trig(1), 0u);

  // 160 SUSTAIN 10 (10 units/s = 100 pulses/s, the minimum; the 5 s DELAY still applies).
  ASSERT_EQ(sustain(10, true), 0u);
  wait_s(10);
  EXPECT_EQ(done(), -1);
  EXPECT_EQ(static_cast<int32_t>(*sdo_read(0x2007, 0)), 100);
  int32_t p = mechanical();
  EXPECT_NEAR(p - (-200), 500, 2);  // 5 s of delay, 5 s at 100 Hz
  // 180 SUSTAIN 50: 500 pulses/s after the delay and a 2 s ramp.
  ASSERT_EQ(sustain(50, true), 0u);
  wait_s(10);
  EXPECT_EQ(static_cast<int32_t>(*sdo_read(0x2007, 0)), 500);
  // Reversing now is error 91 (3-3), answered with an abort and an EMCY.
  size_t before = sent.size();
  EXPECT_EQ(sustain(-10, true), kDeviceState);
  EXPECT_EQ(error(), 91);
  ASSERT_EQ(emcys(before).size(), 1u);
  EXPECT_EQ(emcy_code(emcys(before)[0]), 0xFF5B);
  // 200 SUSTAIN 0 "Stop to change direction" / 220 SUSTAIN -10 "Reverse direction"
  ASSERT_EQ(sustain(0, true), 0u);
  wait_s(10);
  EXPECT_EQ(done(), 0);
  ASSERT_EQ(sustain(-10, true), 0u);
  wait_s(10);
  EXPECT_EQ(static_cast<int32_t>(*sdo_read(0x2007, 0)), -100);
  // 240 HALT SGL
  ASSERT_EQ(sdo_write(index(0, kLimits), hp44714a::limits_sub::kHaltSgl, 1, 1), 0u);
  EXPECT_EQ(done(), 1);
  int32_t stopped = mechanical();
  wait_s(2);
  EXPECT_EQ(mechanical(), stopped);
  EXPECT_EQ(*sdo_read(out, hp44714a::output_sub::kStbyLevel), 0u);  // AUTO: power off 1 s later
}

TEST_F(HpBus, InterruptExampleAsTpdoAndEmcy) {
  // PROFILE FREQ 0 1200 250 50E-6 / ENABLE INTR / MOVE 100 / WAIT 5 / SUSTAIN 1000 / WAIT 10
  // / HALT SGL; the service routine re-enables (the master writes 0x201D:1 again).
  ASSERT_EQ(profile(0, 0, 1200, 250, 50e-6), 0u);
  uint16_t in = index(0, kInterrupt);
  ASSERT_EQ(sdo_write(in, hp44714a::intr_sub::kEnable, 1, 1), 0u);
  size_t from = sent.size();
  ASSERT_EQ(move(100, false, true), 0u);
  wait_s(5);
  auto tpdos = with_id(kTpdo4, from);
  ASSERT_FALSE(tpdos.empty());
  EXPECT_EQ(tpdos.back().dlc, 3);
  EXPECT_EQ(tpdos.back().data[0], 0);                         // DONE? 0
  EXPECT_EQ(tpdos.back().data[2], 1);                         // event: pulses stopped after a MOVE
  EXPECT_EQ(*sdo_read(in, hp44714a::intr_sub::kEnable), 0u);  // disabled once sent
  ASSERT_EQ(sdo_write(in, hp44714a::intr_sub::kEnable, 1, 1), 0u);
  from = sent.size();
  uint64_t sustain_at = t;
  ASSERT_EQ(sustain(1000, true), 0u);
  wait_s(10);
  tpdos = with_id(kTpdo4, from);
  auto times = times_of(kTpdo4, from);
  bool reached = false;
  for (size_t i = 0; i < tpdos.size(); ++i)
    if (tpdos[i].data[2] == 2) {
      reached = true;
      EXPECT_EQ(static_cast<int8_t>(tpdos[i].data[0]), -1);  // SUSTAIN running
      EXPECT_NEAR(static_cast<double>(times[i] - sustain_at) / 1e6, 4.0,
                  0.01);  // 1000 Hz / 250 Hz/s
    }
  EXPECT_TRUE(reached);
  ASSERT_EQ(sdo_write(in, hp44714a::intr_sub::kEnable, 1, 1), 0u);
  from = sent.size();
  ASSERT_EQ(sdo_write(index(0, kLimits), hp44714a::limits_sub::kHaltSgl, 1, 1), 0u);
  tpdos = with_id(kTpdo4, from);
  ASSERT_FALSE(tpdos.empty());
  EXPECT_EQ(tpdos.back().data[0], 1);
  EXPECT_EQ(tpdos.back().data[2], 8);  // HALT SGL
  auto e = emcys(from);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(emcy_code(e[0]), 0xFF44);
}

TEST_F(HpBus, PscaleRoundOffExamplesRelAndAbs) {
  ASSERT_EQ(put(index(0, kPosition), 0, 0), 0u);  // POS 0
  ASSERT_EQ(put(index(0, kPscale), 0, 2), 0u);    // PSCALE 2
  for (double expected : {2.0, 4.0, 6.0}) {
    ASSERT_EQ(move(1), 0u);  // MOVE 1 REL
    wait_s(1);
    EXPECT_EQ(get(index(0, kPosition)), expected);
  }
  ASSERT_EQ(put(index(0, kPosition), 0, 0), 0u);
  for (auto [target, expected] : {std::pair{1.0, 2.0}, {2.0, 2.0}, {3.0, 4.0}}) {
    ASSERT_EQ(move(target, true), 0u);  // MOVE n ABS
    wait_s(1);
    EXPECT_EQ(get(index(0, kPosition)), expected);
  }
}

TEST_F(HpBus, AMoveOfMoreThanTheModulesPulsesIsARangeAbort) {
  // 1e300 steps (or 1e10 units at PSCALE 1e-300) overflowed llround in rel_steps: the MOVE
  // was accepted, "completed" at once without a step and DONE? read 0.
  constexpr uint32_t kRange = 0x06090030;
  EXPECT_EQ(move(1e300), kRange);
  EXPECT_EQ(move(-1e300, true), kRange);
  ASSERT_EQ(put(index(0, kPscale), 0, 1e-300), 0u);
  EXPECT_EQ(move(1e10), kRange);
  ASSERT_EQ(put(index(0, kPscale), 0, 1), 0u);
  // Appendix A: at most 2,147,483,647 pulses in one MOVE.
  EXPECT_EQ(move(2147483648.0), kRange);
  EXPECT_EQ(move(-2147483648.0), kRange);
  EXPECT_EQ(move(5), 0u);  // an ordinary move still goes
  wait_s(1);
  EXPECT_EQ(get(index(0, kPosition)), 5.0);
}

TEST_F(HpBus, ASustainFinerThanTheRateResolutionIsARangeAbortAndNothingMoves) {
  // Appendix A "Pulse Rate ... Resolution 2.5 µHz". SUSTAIN 1E-12 NOWAIT (power-on
  // PROFILE: min 0, so the clamp let it through) overflowed freq_ramp's llround: the
  // motor jumped to the simulated limit within a tick, or with no limits the node spun.
  constexpr uint32_t kRange = 0x06090030;
  EXPECT_EQ(sustain(1e-12, true), kRange);
  // PSCALE 1E12; SUSTAIN 1 is 1e-12 pulses/s too.
  ASSERT_EQ(put(index(0, kPscale), 0, 1e12), 0u);
  EXPECT_EQ(sustain(1, true), kRange);
  ASSERT_EQ(put(index(0, kPscale), 0, 1), 0u);
  wait_s(1);
  EXPECT_EQ(mechanical(), 0);
  EXPECT_EQ(done(), 0);
  EXPECT_EQ(error(), 0);  // not an HP error number: 0x2n19 is unchanged
  // At the resolution the SUSTAIN is legal (one pulse in 4.6 days) and the node serves on.
  EXPECT_EQ(sustain(2.5e-6, true), 0u);
  wait_s(1);
  EXPECT_LT(done(), 0);
  EXPECT_EQ(mechanical(), 0);
  // From there to 100 pulses/s ramps at the PROFILE's 500 Hz/s (0.2 s), not one µHz level
  // per tick for minutes of CPU.
  EXPECT_EQ(sustain(100, true), 0u);
  wait_s(1.2);
  EXPECT_EQ(done(), -1);
  int32_t p0 = mechanical();
  wait_s(1);
  EXPECT_NEAR(mechanical() - p0, 100, 1);
}

TEST_F(HpBus, ProfileConflictsAndErrorNumbersAreAborts) {
  EXPECT_EQ(profile(0, 500, 100, 200, 2e-3), kIncompatible);
  EXPECT_EQ(*sdo_read(index(0, kConflict), 0), 5u);
  EXPECT_EQ(profile(0, 0, 1000, 500, 2e-3), kIncompatible);
  EXPECT_EQ(*sdo_read(index(0, kConflict), 0), 4u);
  // 92: MOVE in WIDTH mode.
  ASSERT_EQ(profile(1, 1e-3, 10e-3, 5e-3, 20e-3), 0u);
  EXPECT_EQ(move(10), kDeviceState);
  EXPECT_EQ(error(), 92);
  ASSERT_EQ(profile(0, 0, 250, 500, 50e-6), 0u);
  // 94: STANDBY ON.
  size_t from = sent.size();
  ASSERT_EQ(sdo_write(index(0, kOutput), hp44714a::output_sub::kStandbyMode, 1, 1), 0u);
  EXPECT_EQ(move(10), kDeviceState);
  EXPECT_EQ(error(), 94);
  ASSERT_EQ(emcys(from).size(), 1u);
  EXPECT_EQ(emcy_code(emcys(from)[0]), 0xFF5E);
  ASSERT_EQ(sdo_write(index(0, kOutput), hp44714a::output_sub::kStandbyMode, 2, 1), 0u);
  // 93: the simulated TEST jumper.
  ASSERT_EQ(sdo_write(sim_index(0), hp44714a::sim_sub::kTestJumper, 1, 1), 0u);
  EXPECT_EQ(move(10), kDeviceState);
  EXPECT_EQ(error(), 93);
  ASSERT_EQ(sdo_write(sim_index(0), hp44714a::sim_sub::kTestJumper, 0, 1), 0u);
  // 90: TRIG SGL with nothing armed. 89: a MOVE while one runs.
  ASSERT_EQ(trig(0), 0u);
  EXPECT_EQ(trig(2), kDeviceState);
  EXPECT_EQ(error(), 90);
  ASSERT_EQ(trig(1), 0u);
  ASSERT_EQ(move(500, false, true), 0u);
  EXPECT_EQ(error(), 0);
  EXPECT_EQ(move(5, false, true), kDeviceState);
  EXPECT_EQ(error(), 89);
}

TEST_F(HpBus, HaltSwitchAndHardLimitOverTheBus) {
  ASSERT_EQ(sdo_write(index(0, kInterrupt), hp44714a::intr_sub::kEnable, 1, 1), 0u);
  ASSERT_EQ(sustain(200, true), 0u);
  wait_s(1);
  ASSERT_EQ(sdo_write(index(0, kInterrupt), hp44714a::intr_sub::kEnable, 1, 1), 0u);
  size_t from = sent.size();
  ASSERT_EQ(sdo_write(sim_index(0), hp44714a::sim_sub::kHaltInputHigh, 0, 1), 0u);  // switch closes
  EXPECT_EQ(done(), 1);
  ASSERT_EQ(emcys(from).size(), 1u);
  EXPECT_EQ(emcy_code(emcys(from)[0]), 0xFF45);
  ASSERT_EQ(sdo_write(sim_index(0), hp44714a::sim_sub::kHaltInputHigh, 1, 1), 0u);
  // The simulated upper limit (0x5000:6) at 300 steps.
  ASSERT_EQ(sdo_write(0x5000, 6, 300), 0u);
  ASSERT_EQ(move(1000, false, true), 0u);
  wait_s(5);
  EXPECT_EQ(done(), 2);
  EXPECT_EQ(mechanical(), 300);
}

TEST_F(HpBus, TrigSysStartsTwoAxesOnOneSync) {
  build(2);
  for (unsigned a = 0; a < 2; ++a) {
    ASSERT_EQ(trig(3, a), 0u);
    ASSERT_EQ(move(50, false, true, a), 0u);
    EXPECT_EQ(done(a), -3);
  }
  advance_us(2'345);
  t += 123;  // the SYNC arrives between ticks
  sync();
  uint64_t sync_at = t;
  wait_s(2);
  uint32_t first[2];
  for (unsigned a = 0; a < 2; ++a) {
    EXPECT_EQ(done(a), 0);
    EXPECT_EQ(mechanical(a), 50);
    first[a] = *sdo_read(index(a, kTiming), hp44714a::timing_sub::kFirstStepUs);
    EXPECT_EQ(*sdo_read(index(a, kTiming), hp44714a::timing_sub::kTriggerUs),
              static_cast<uint32_t>(sync_at));
  }
  EXPECT_EQ(first[0], first[1]);
  // The power-on profile starts from 0 Hz at 500 Hz/s: the first step 63.2 ms after SYNC.
  EXPECT_NEAR(static_cast<double>(first[0] - static_cast<uint32_t>(sync_at)) / 1000, 63.2, 0.2);
}

TEST_F(HpBus, TrigSysStartsAtTheSyncFramesArrivalNotWhenItWasRead) {
  ASSERT_EQ(trig(3), 0u);
  ASSERT_EQ(move(5, false, true), 0u);
  advance_us(3'000);
  device->on_frame(CanFrame(0x80, {}), t,
                   t - 700);  // it reached the socket 700 us before it was read
  EXPECT_EQ(*sdo_read(index(0, kTiming), hp44714a::timing_sub::kTriggerUs),
            static_cast<uint32_t>(t - 700));
  wait_s(1);
  EXPECT_EQ(mechanical(), 5);
}

// A MOVE waiting for the SYNC (TRIG SYS): PROFILE WIDTH meanwhile is a settings conflict
// (0x2n1A 7: the mode of a waiting command); STANDBY ON is accepted, and at the SYNC the
// MOVE is refused with error 94, "Motor cannot move when powered down by STANDBY in the ON
// mode" (3-3): 0x2n19 and TPDO 4 carry it, and the motor does not move.
TEST_F(HpBus, AMoveWaitingForTheSyncKeepsItsModeAndMeetsError94AtTheSync) {
  ASSERT_EQ(trig(3), 0u);
  ASSERT_EQ(move(20, false, true), 0u);
  EXPECT_EQ(done(), -3);
  EXPECT_EQ(profile(1, 1e-3, 10e-3, 5e-3, 20e-3), kIncompatible);
  EXPECT_EQ(*sdo_read(index(0, kConflict), 0), 7u);
  ASSERT_EQ(sdo_write(index(0, kOutput), hp44714a::output_sub::kStandbyMode, 1, 1), 0u);
  size_t from = sent.size();
  sync();
  wait_s(1);
  EXPECT_EQ(error(), 94);
  EXPECT_EQ(done(), 0);
  EXPECT_EQ(mechanical(), 0);
  auto tpdos = with_id(kTpdo4, from);
  ASSERT_FALSE(tpdos.empty());
  EXPECT_EQ(tpdos.back().data[1], 94);
}

TEST_F(HpBus, StoredSettingsComeBackAfterResetNode) {
  // PSCALE, PROFILE and DELAY are stored by 0x1010 and applied at the next power-up (the
  // PROFILE before the PSCALE, as Figure 3-3 gives them).
  ASSERT_EQ(profile(0, 100, 100, 0, 25e-6), 0u);
  ASSERT_EQ(put(index(0, kPscale), 0, 0.5), 0u);
  ASSERT_EQ(sdo_write(index(0, kDelay), 0, 250, 2), 0u);
  ASSERT_EQ(sdo_write(0x1010, 1, 0x65766173), 0u);  // "save"
  nmt(0x81);                                        // reset node
  advance_us(10'000);
  nmt(0x01);
  EXPECT_EQ(get(index(0, kPscale)), 0.5);
  ASSERT_EQ(move(10, false, true), 0u);  // 20 steps at 100 Hz after 250 ms
  wait_s(0.25 + 0.195);
  EXPECT_LT(mechanical(), 20);
  wait_s(0.02);
  EXPECT_EQ(mechanical(), 20);
}

TEST_F(HpBus, AStoredProfileTheChannelRefusesIsReportedAndTheObjectsShowThePowerOnOne) {
  // The PROFILE subs are staged objects: a refused PROFILE (a FREQ minimum under the
  // 2.5 µHz resolution, conflict row 6) still leaves them stored. At the next power-up it
  // was dropped in silence while the objects kept showing it.
  uint16_t p = index(0, kProfile);
  EXPECT_EQ(profile(0, 1e-7, 800, 200, 25e-6), kIncompatible);
  ASSERT_EQ(sdo_write(0x1010, 1, 0x65766173), 0u);  // "save"
  size_t from = sent.size();
  nmt(0x81);  // reset node
  advance_us(10'000);
  std::vector<CanFrame> e;
  for (const CanFrame& f : emcys(from))
    if (emcy_code(f) == 0x5530) e.push_back(f);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].data[3], static_cast<uint8_t>(p));
  EXPECT_EQ(e[0].data[4], static_cast<uint8_t>(p >> 8));
  EXPECT_EQ(get(p, hp44714a::profile_sub::kMin), 0.0);  // power-on: 0 250 500 50E-6
  EXPECT_EQ(get(p, hp44714a::profile_sub::kMax), 250.0);
}

TEST_F(HpBus, Tpdo4IsMappedToDoneErrorAndEvent) {
  EXPECT_EQ(*sdo_read(0x1A03, 0), 3u);
  EXPECT_EQ(*sdo_read(0x1A03, 1), 0x20180008u);
  EXPECT_EQ(*sdo_read(0x1A03, 2), 0x20190008u);
  EXPECT_EQ(*sdo_read(0x1A03, 3), 0x201D0208u);
}

}  // namespace
}  // namespace stepnode::node::test

namespace stepnode::node::test {
namespace {

// STANDBY (3-13) in the simulation: the STBY output is the motor's power. With STANDBY ON
// an HP MOVE is refused (error 94); a Horner move still runs and counts its steps, but the
// unpowered motor holds no torque and the load does not move. AUTO powers the motor before
// the pulses, whichever front end sends them; OFF applies power.
TEST_F(HpBus, StandbyOnLeavesTheMotorUnpoweredSoHornerStepsMoveNothing) {
  uint16_t out = index(0, kOutput);
  auto horner_move_rel = [&](int32_t steps) {
    ASSERT_EQ(sdo_write(0x2000, 0, 0, 2), 0u);
    ASSERT_EQ(sdo_write(0x2002, 0, static_cast<uint32_t>(steps)), 0u);
    ASSERT_EQ(sdo_write(0x2000, 0, 1u << 7, 2), 0u);  // %Q8 move relative
    wait_s(2);
  };
  ASSERT_EQ(sdo_write(0x2000, 0, 1u << 13, 2), 0u);  // %Q14 Clear Errors (power-up)
  ASSERT_EQ(sdo_write(out, hp44714a::output_sub::kStandbyMode, 1, 1), 0u);  // STANDBY ON
  EXPECT_EQ(*sdo_read(out, hp44714a::output_sub::kMotorPowered), 0u);
  EXPECT_EQ(move(1), kDeviceState);
  EXPECT_EQ(error(), 94);
  horner_move_rel(100);
  EXPECT_EQ(static_cast<int32_t>(*sdo_read(0x2005, 0)), 100) << "the module counted its steps";
  EXPECT_EQ(mechanical(), 0) << "an unpowered motor does not move";

  ASSERT_EQ(sdo_write(out, hp44714a::output_sub::kStandbyMode, 2, 1), 0u);  // AUTO
  horner_move_rel(100);
  EXPECT_EQ(mechanical(), 100);
  ASSERT_EQ(sdo_write(out, hp44714a::output_sub::kStandbyMode, 0, 1), 0u);  // OFF: power applied
  EXPECT_EQ(*sdo_read(out, hp44714a::output_sub::kMotorPowered), 1u);
  horner_move_rel(-50);
  EXPECT_EQ(mechanical(), 50);
}

// 3-28's WIDTH example over the bus (issue 11 item 12): 0x2n16:10 shows the width at the
// outputs now, 0x5n05:3 the width of the last pulse the simulated drive received; with
// STANDBY ON the STBY output follows the pulse train (3-29) and the unpowered motor of a
// stepper is powered only while it runs.
TEST_F(HpBus, Hp3_28_WidthExamplePulseWidthsAndStbyOverTheBus) {
  uint16_t out = index(0, kOutput);
  ASSERT_EQ(sdo_write(out, hp44714a::output_sub::kStandbyMode, 1, 1), 0u);  // STANDBY ON (HI)
  EXPECT_EQ(*sdo_read(out, hp44714a::output_sub::kStbyLevel), 1u);
  ASSERT_EQ(profile(1, 1e-3, 10e-3, 5e-3, 20e-3), 0u);
  ASSERT_EQ(sustain(2e-3, true), 0u);
  EXPECT_EQ(error(), 0);
  wait_s(0.1);
  EXPECT_EQ(*sdo_read(out, hp44714a::output_sub::kStbyLevel), 0u);
  EXPECT_NEAR(get(out, hp44714a::output_sub::kPulseWidth), 1.5e-3, 0.03e-3);
  wait_s(0.5);
  EXPECT_EQ(get(out, hp44714a::output_sub::kPulseWidth), 2e-3);
  EXPECT_EQ(*sdo_read(sim_index(0), hp44714a::sim_sub::kLastPulseWidthNs), 2'000'000u);
  EXPECT_GT(mechanical(), 0) << "STBY powers the drive during the pulse train";
  ASSERT_EQ(put_int<uint8_t>(index(0, kLimits), hp44714a::limits_sub::kHaltSgl, 1), 0u);
  EXPECT_EQ(*sdo_read(out, hp44714a::output_sub::kStbyLevel), 1u);
  EXPECT_EQ(get(out, hp44714a::output_sub::kPulseWidth), 0);
  EXPECT_EQ(*sdo_read(out, hp44714a::output_sub::kMotorPowered), 0u);
}

// TEST (Command Summary 4-3) over the bus: the answer in 0x2n1F:2 (0 passed), refused with
// error 89 while a move is in progress.
TEST_F(HpBus, Hp4_3_TestAnswersPassOrFail) {
  const uint16_t t = index(0, kTest);
  ASSERT_EQ(put_int<uint8_t>(t, hp44714a::test_sub::kRun, 1), 0u);
  EXPECT_EQ(*sdo_read(t, hp44714a::test_sub::kResult), 0u);
  EXPECT_EQ(*sdo_read(t, hp44714a::test_sub::kFailedChecks), 0u);
  ASSERT_EQ(move(50, false, true), 0u);
  EXPECT_EQ(put_int<uint8_t>(t, hp44714a::test_sub::kRun, 1), kDeviceState);
  EXPECT_EQ(error(), 89);
  wait_s(2);
  EXPECT_EQ(put_int<uint8_t>(t, hp44714a::test_sub::kRun, 1), 0u);
  EXPECT_EQ(error(), 0);
}

}  // namespace
}  // namespace stepnode::node::test
