// The golden step trains: a representative set of moves driven over the bus objects of a
// node in virtual time, every step the simulated motor received (its tick on the 4.9152 MHz
// timebase and its direction) compared with the trains recorded in tests/golden/ from the
// engine before the device was restructured (issue 9). A change of structure must
// reproduce them tick for tick; a change of behaviour must say why and re-record:
//   STEPNODE_GOLDEN_RECORD=1 build/node/node_tests --gtest_filter='GoldenTrains.*'
// File format: "train NAME STEPS", then one signed number per step: its direction as the
// sign, and the ticks since the previous step (the first: since tick 0); "end".
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "node/profiles/horner/bits.hpp"
#include "node/profiles/horner/objects.hpp"
#include "node/profiles/hp44714a/objects.hpp"
#include "node/profiles/sim/objects.hpp"
#include "node/tests/node_harness.hpp"

#ifndef STEPNODE_GOLDEN_DIR
#error "STEPNODE_GOLDEN_DIR: the directory of the recorded trains"
#endif

namespace stepnode::node::test {
namespace {

namespace axis_obj = horner::obj;
namespace hp_obj = hp44714a::obj;
namespace cmd = horner::command;
using Train = std::vector<sim::TracedStep>;

std::string golden_path(const std::string& name) {
  return std::string(STEPNODE_GOLDEN_DIR) + "/" + name + ".train";
}

void write_train(const std::string& name, const Train& train) {
  std::ofstream out(golden_path(name));
  out << "train " << name << " " << train.size() << "\n";
  motion::Tick previous = 0;
  for (size_t i = 0; i < train.size(); ++i) {
    motion::Tick delta = train[i].time - previous;
    previous = train[i].time;
    out << (train[i].direction > 0 ? "+" : "-") << delta << ((i % 12 == 11) ? "\n" : " ");
  }
  out << "\nend\n";
}

// The recorded train, or an empty one with `error` set.
Train read_train(const std::string& name, std::string& error) {
  std::ifstream in(golden_path(name));
  if (!in) {
    error = "no recorded train " + golden_path(name);
    return {};
  }
  std::string word, recorded_name;
  size_t count = 0;
  in >> word >> recorded_name >> count;
  if (word != "train" || recorded_name != name) {
    error = "not the train of " + name;
    return {};
  }
  Train train;
  motion::Tick previous = 0;
  while (in >> word && word != "end") {
    int direction = word[0] == '-' ? -1 : +1;
    previous += std::stoll(word.substr(1));
    train.push_back({previous, direction});
  }
  if (word != "end" || train.size() != count) error = "the file of " + name + " is cut short";
  return train;
}

// Each scenario runs with the step port's horizon (microseconds) of the parameter: the
// steps are given to the simulated machine that far ahead of their time, and a change of
// course (a stop, the home switch, a new velocity) takes the queued ones back. The trains
// must be the same at every horizon.
class GoldenTrains : public NodeHarness, public ::testing::WithParamInterface<uint32_t> {
 protected:
  void SetUp() override { build(DeviceLayout{.axes = 1}); }
  // A device with the profiles of `layout` (all of them by default), operational.
  void build(DeviceLayout layout) {
    layout.step_horizon_us = GetParam();
    make(layout);
    nmt(0x01);
    train.clear();
    device->machine().axes[0].trace_into(&train);
  }

  // Compares the train with the recorded one (or records it), step by step.
  void check(const std::string& name) {
    ASSERT_GT(train.size(), 10u) << "the scenario moved nothing";
    if (std::getenv("STEPNODE_GOLDEN_RECORD")) {
      if (GetParam() != 0) GTEST_SKIP() << "recorded at horizon 0 only";
      write_train(name, train);
      GTEST_SKIP() << "recorded " << golden_path(name);
    }
    std::string error;
    Train golden = read_train(name, error);
    ASSERT_TRUE(error.empty()) << error;
    size_t n = std::min(golden.size(), train.size());
    for (size_t i = 0; i < n; ++i) {
      ASSERT_EQ(train[i].time, golden[i].time) << name << ": step " << i << " of " << golden.size();
      ASSERT_EQ(train[i].direction, golden[i].direction) << name << ": step " << i;
    }
    EXPECT_EQ(train.size(), golden.size()) << name << ": steps";
  }

  // Horner: a command bit's rising edge, then the bits back to `held`.
  void command(uint16_t bits, uint16_t held = 0) {
    ASSERT_EQ(sdo_write(axis_obj::index(0, axis_obj::kCommandBits), 0, bits | held, 2), 0u);
    ASSERT_EQ(sdo_write(axis_obj::index(0, axis_obj::kCommandBits), 0, held, 2), 0u);
  }
  void destination(int32_t d) {
    ASSERT_EQ(sdo_write(axis_obj::index(0, axis_obj::kDestination), 0, static_cast<uint32_t>(d)),
              0u);
  }
  void profile_word(uint8_t sub, uint16_t v) {
    ASSERT_EQ(sdo_write(axis_obj::index(0, axis_obj::kProfile), sub, v, 2), 0u);
  }
  // HP: PROFILE mode min max slope last.
  void hp_profile(uint8_t mode, double min, double max, double slope, double last) {
    uint16_t p = hp_obj::index(0, hp_obj::kProfile);
    ASSERT_EQ(put_int<uint8_t>(p, hp44714a::profile_sub::kMode, mode), 0u);
    ASSERT_EQ(put(p, hp44714a::profile_sub::kMin, min), 0u);
    ASSERT_EQ(put(p, hp44714a::profile_sub::kMax, max), 0u);
    ASSERT_EQ(put(p, hp44714a::profile_sub::kSlope, slope), 0u);
    ASSERT_EQ(put(p, hp44714a::profile_sub::kLast, last), 0u);
    ASSERT_EQ(put_int<uint8_t>(p, hp44714a::profile_sub::kApply, 1), 0u);
  }
  // Two moves of a Horner trapezoid: relative 3000, then absolute to -1200.
  void horner_trapezoid() {
    command(cmd::kClearErrors);
    profile_word(horner::profile_sub::kDeceleration, 300);
    destination(0);
    command(cmd::kSetPosition);  // MOVE ABSOLUTE needs a valid position (SPM30 3.3.1)
    destination(3000);
    command(cmd::kMoveRelative);
    advance_ms(5000);
    destination(-1200);
    command(cmd::kMoveAbsolute);
    advance_ms(6000);
    ASSERT_EQ(device->machine().axes[0].position(), -1200);
    check("horner_trapezoid");
  }
  // HP manual Figure 3-3: PROFILE FREQ 100 800 200 25E-6, PSCALE 0.1, MOVE 20, MOVE -30.
  void hp_freq_move() {
    hp_profile(0, 100, 800, 200, 25e-6);
    ASSERT_EQ(put(hp_obj::index(0, hp_obj::kPscale), 0, 0.1), 0u);
    ASSERT_EQ(put(hp_obj::index(0, hp_obj::kMove), hp44714a::move_sub::kRelative, 20), 0u);
    advance_ms(3000);
    ASSERT_EQ(put(hp_obj::index(0, hp_obj::kMove), hp44714a::move_sub::kRelative, -30), 0u);
    advance_ms(4000);
    check("hp_freq_move");
  }
  void hp_sustain(double v) { ASSERT_EQ(put(hp_obj::index(0, hp_obj::kSustain), 0, v), 0u); }

  Train train;
};

TEST_P(GoldenTrains, HornerTrapezoid) { horner_trapezoid(); }

TEST_P(GoldenTrains, HornerTriangle) {
  command(cmd::kClearErrors);
  profile_word(horner::profile_sub::kAcceleration, 800);
  destination(250);
  command(cmd::kMoveRelative);
  advance_ms(3000);
  check("horner_triangle");
}

TEST_P(GoldenTrains, HornerJog) {
  command(cmd::kClearErrors);
  ASSERT_EQ(sdo_write(axis_obj::index(0, axis_obj::kCommandBits), 0, cmd::kJogUp, 2), 0u);
  advance_ms(1500);
  // Jogging: the steps of the horizon wait in the port (none without one).
  if (GetParam() == 0) EXPECT_EQ(device->machine().axes[0].queued(), 0u);
  else EXPECT_GT(device->machine().axes[0].queued(), 0u);
  ASSERT_EQ(sdo_write(axis_obj::index(0, axis_obj::kCommandBits), 0, 0, 2), 0u);
  advance_ms(1500);
  ASSERT_EQ(sdo_write(axis_obj::index(0, axis_obj::kCommandBits), 0, cmd::kJogDown, 2), 0u);
  advance_ms(700);
  ASSERT_EQ(sdo_write(axis_obj::index(0, axis_obj::kCommandBits), 0, 0, 2), 0u);
  advance_ms(1500);
  check("horner_jog");
}

TEST_P(GoldenTrains, HornerIndexedMove) {
  uint16_t sw = sim::obj::index(0, sim::obj::kSwitches);
  ASSERT_EQ(sdo_write(sw, sim::switches_sub::kIndexPosition, 1800), 0u);
  ASSERT_EQ(sdo_write(sw, sim::switches_sub::kIndexWidth, 10), 0u);
  command(cmd::kClearErrors);
  uint16_t ix = axis_obj::index(0, axis_obj::kIndexedMove);
  ASSERT_EQ(sdo_write(ix, horner::indexed_sub::kDestination, 400), 0u);
  ASSERT_EQ(sdo_write(ix, horner::indexed_sub::kDeceleration, 250, 2), 0u);
  ASSERT_EQ(sdo_write(ix, horner::indexed_sub::kWindowOpen, 1000), 0u);
  ASSERT_EQ(sdo_write(ix, horner::indexed_sub::kWindowClose, 6000), 0u);
  destination(8000);
  command(cmd::kMoveIndexed);
  advance_ms(6000);
  check("horner_indexed");
}

TEST_P(GoldenTrains, HornerHoming) {
  // The home switch of the simulated machine is at 1000..1049 (its default).
  command(cmd::kClearErrors);
  command(cmd::kFindHomeUp);
  advance_ms(8000);
  destination(-500);
  command(cmd::kMoveRelative);
  advance_ms(2000);
  command(cmd::kFindHomeDown);
  advance_ms(8000);
  check("horner_homing");
}

TEST_P(GoldenTrains, HpFrequencyRampMoves) { hp_freq_move(); }

// A device with one profile runs the same engine: the same trains, tick for tick.
TEST_P(GoldenTrains, HornerTrapezoidOnAHornerOnlyDevice) {
  build(DeviceLayout{.axes = 1, .hp = false, .user = false});
  ASSERT_EQ(od().object(hp_obj::index(0, hp_obj::kProfile)), nullptr);
  horner_trapezoid();
}

TEST_P(GoldenTrains, HpFrequencyRampMovesOnAnHpOnlyDevice) {
  build(DeviceLayout{.axes = 1, .horner = false, .user = false});
  ASSERT_EQ(od().object(axis_obj::index(0, axis_obj::kCommandBits)), nullptr);
  hp_freq_move();
}

TEST_P(GoldenTrains, HpSustainChanges) {
  hp_profile(0, 100, 2000, 1000, 25e-6);
  ASSERT_EQ(put_int<uint8_t>(hp_obj::index(0, hp_obj::kMove), hp44714a::move_sub::kNowait, 1), 0u);
  hp_sustain(1500);
  advance_ms(2500);
  hp_sustain(300);
  advance_ms(1500);
  hp_sustain(0);
  advance_ms(2000);
  hp_sustain(-700);  // the other way once stopped
  advance_ms(2000);
  hp_sustain(0);
  advance_ms(2000);
  check("hp_sustain");
}

TEST_P(GoldenTrains, HpWidthMode) {
  // HP manual 3-28: PROFILE WIDTH 1E-3 10E-3 5E-3 20E-3, SUSTAIN 2E-3, then SUSTAIN 0.
  hp_profile(1, 1e-3, 10e-3, 5e-3, 20e-3);
  ASSERT_EQ(put_int<uint8_t>(hp_obj::index(0, hp_obj::kMove), hp44714a::move_sub::kNowait, 1), 0u);
  hp_sustain(2e-3);
  advance_ms(1300);
  hp_sustain(0);
  advance_ms(1000);
  check("hp_width");
}

// 0: each step given as it falls due; 1 ms: about one tick of the node ahead; 100 ms: far
// ahead (hundreds of steps queued at the top rates).
INSTANTIATE_TEST_SUITE_P(Horizon, GoldenTrains, ::testing::Values(0u, 1000u, 100000u),
                         [](const ::testing::TestParamInfo<uint32_t>& p) {
                           return std::to_string(p.param) + "us";
                         });

}  // namespace
}  // namespace stepnode::node::test
