// Frames for other nodes cost nothing (issue 13): a frame this node does not serve
// changes no object, sends nothing and does not even advance the axes, which the next
// tick or served frame does. The frames are CiA 301's pre-defined connection set of node 6
// (this node is 5): an NMT command for node 6, its SDO request 0x606, its RPDO1 0x206,
// its heartbeat 0x706, and a remote request on this node's TPDO1 0x185 (this device
// answers no TPDO remote request).
#include <gtest/gtest.h>

#include <map>

#include "node/profiles/horner/bits.hpp"
#include "node/profiles/horner/objects.hpp"
#include "node/profiles/sim/objects.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

using Snapshot = std::map<std::pair<uint16_t, uint8_t>, od::Bytes>;

class ForeignFrameTest : public NodeHarness {
 protected:
  Snapshot snapshot() {
    Snapshot s;
    for (const auto& [index, obj] : od().objects())
      for (const auto& [sub, e] : obj.entries) s[{index, sub}] = e.value;
    return s;
  }
  // Axis 1 jogging up, the node operational.
  void jog() {
    using namespace horner::obj;
    nmt(0x01);
    ASSERT_EQ(sdo_write(sim::obj::index(0, sim::obj::kSwitches),
                        sim::switches_sub::kUpperLimitEnabled, 0, 1),
              0u);
    ASSERT_EQ(sdo_write(index(0, kCommandBits), 0, horner::command::kClearErrors, 2), 0u);
    ASSERT_EQ(sdo_write(index(0, kCommandBits), 0, 0, 2), 0u);
    ASSERT_EQ(sdo_write(index(0, kCommandBits), 0, horner::command::kJogUp, 2), 0u);
    advance_ms(50);
    ASSERT_GT(device->axes().axis(0).motor_position(), 0);
  }
  static std::vector<CanFrame> foreign() {
    CanFrame rtr(0x185, {});
    rtr.rtr = true;
    return {CanFrame(0x000, {0x01, 6}), CanFrame(0x606, {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0}),
            CanFrame(0x206, {0x20, 0x00, 1, 0, 0, 0}), CanFrame(0x706, {0x05}), rtr};
  }
};

TEST_F(ForeignFrameTest, ChangesNothingSendsNothingAndDoesNotAdvanceTheAxes) {
  jog();
  const int64_t position = device->axes().axis(0).motor_position();
  const Snapshot before = snapshot();
  clear_sent();
  t += 20'000;  // 20 ms without a tick: a served frame would take the steps due by now
  for (const CanFrame& f : foreign()) frame(f);
  EXPECT_TRUE(sent.empty());
  EXPECT_EQ(device->axes().axis(0).motor_position(), position);
  EXPECT_EQ(snapshot(), before);
  EXPECT_EQ(node->state(), NmtState::Operational);
}

TEST_F(ForeignFrameTest, AServedFrameStillActsOnAnAxisCurrentToTheMicrosecond) {
  jog();
  const int64_t position = device->axes().axis(0).motor_position();
  t += 20'000;
  sdo_read(0x1000, 0);  // served: the axes advance to now before the request is answered
  EXPECT_GT(device->axes().axis(0).motor_position(), position);
}

TEST_F(ForeignFrameTest, AnNmtCommandForAllNodesIsServed) {
  frame(CanFrame(0x000, {0x01, 0}));
  EXPECT_EQ(node->state(), NmtState::Operational);
  frame(CanFrame(0x000, {0x80, 6}));  // for node 6 only
  EXPECT_EQ(node->state(), NmtState::Operational);
}

}  // namespace
}  // namespace stepnode::node::test
