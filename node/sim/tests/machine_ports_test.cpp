// The simulated machine as a back end (motion::StepPort, motion::InputPort): queued steps
// move the motor only when flushed, taken-back ones never; every input change is an edge
// with the tick of the step that made it, or the back end's clock for a change from
// outside (a switch moved, the e-stop, HALT).
#include <gtest/gtest.h>

#include <vector>

#include "node/sim/machine.hpp"

namespace stepnode::sim {
namespace {

using motion::Input;
using motion::InputEdge;

std::vector<InputEdge> edges(AxisMachine& m) {
  std::vector<InputEdge> out;
  InputEdge e;
  while (m.next_edge(e)) out.push_back(e);
  return out;
}

TEST(SimMachinePorts, QueuedStepsMoveTheMotorWhenFlushedAndCancelledOnesNever) {
  AxisMachine m;
  m.set_horizon(1000);
  for (motion::Tick t = 100; t <= 1000; t += 100) m.queue(t, +1);
  EXPECT_EQ(m.position(), 0);  // nothing has gone out yet
  m.flush(450);
  EXPECT_EQ(m.position(), 4);
  EXPECT_EQ(m.last_step_time(), 400);
  m.cancel_after(600);  // the course changed at 600: 700..1000 will not go out
  m.flush(5000);
  EXPECT_EQ(m.position(), 6);
  EXPECT_EQ(m.pulses_received(), 6u);
  EXPECT_EQ(m.position_at(450), 4);
  EXPECT_EQ(m.position_at(50), 0);
}

TEST(SimMachinePorts, ASwitchEdgeCarriesTheTickOfTheStepThatReachedIt) {
  AxisMachineConfig c;
  c.home = Cam{3, 2};  // active at 3 and 4
  c.upper_limit = 6;
  c.encoder = EncoderKind::None;
  AxisMachine m(c);
  EXPECT_TRUE(edges(m).empty());
  for (motion::Tick t = 1; t <= 6; ++t) m.queue(t * 10, +1);
  m.flush(60);
  const std::vector<InputEdge> want{
      {30, Input::Home, true}, {50, Input::Home, false}, {60, Input::UpperLimit, true}};
  EXPECT_EQ(edges(m), want);
  EXPECT_TRUE(m.levels().upper_limit());
}

TEST(SimMachinePorts, TheMarkerIsAnEdgeOncePerRevolution) {
  AxisMachineConfig c;
  c.steps_per_rev = 10;
  c.marker_offset = 2;
  c.marker_width = 1;
  AxisMachine m(c);
  for (int i = 1; i <= 25; ++i) m.step(i, +1);
  std::vector<InputEdge> marks;
  for (const InputEdge& e : edges(m))
    if (e.input == Input::Marker) marks.push_back(e);
  // On at 2, 12 and 22 (the step's tick is its position here), off one step later.
  const std::vector<InputEdge> want{{2, Input::Marker, true},  {3, Input::Marker, false},
                                    {12, Input::Marker, true}, {13, Input::Marker, false},
                                    {22, Input::Marker, true}, {23, Input::Marker, false}};
  EXPECT_EQ(marks, want);
}

TEST(SimMachinePorts, AChangeFromOutsideIsAnEdgeAtTheBackEndsClock) {
  Machine machine;
  AxisMachineConfig c;
  c.encoder = EncoderKind::None;  // no marker
  machine.axes.assign(2, AxisMachine(c));
  machine.axes[0].flush(7000);  // the core's latest advance
  machine.set_emergency_stop(true);
  machine.axes[0].set_halt_input(false);
  const std::vector<InputEdge> want{{7000, Input::EmergencyStop, true}, {7000, Input::Halt, false}};
  EXPECT_EQ(edges(machine.axes[0]), want);
  const std::vector<InputEdge> other{{0, Input::EmergencyStop, true}};  // one switch, every axis
  EXPECT_EQ(edges(machine.axes[1]), other);
  machine.axes[0].config().home = Cam{-5, 10};  // a switch moved under the load
  const std::vector<InputEdge> home{{7000, Input::Home, true}};
  EXPECT_EQ(edges(machine.axes[0]), home);
  machine.axes[0].displace(100);
  const std::vector<InputEdge> off{{7000, Input::Home, false}};
  EXPECT_EQ(edges(machine.axes[0]), off);
}

}  // namespace
}  // namespace stepnode::sim
