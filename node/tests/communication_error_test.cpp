// One policy for communication errors and NMT states, in virtual time through the whole
// device: CiA 301 0x1029 (error behaviour, sub 1 communication error: 0 pre-operational,
// 1 no change, 2 stopped) for a heartbeat consumer timeout and for bus-off; 0x2F11, the
// master whose heartbeat loss ramps the axes down; and NMT Stopped, which ramps them down
// as a lost master does. The expected frames are CiA 301's: a heartbeat (0x700 + node) with
// the new state at once (0x7F pre-operational, 0x04 stopped), EMCY 0x8130 with the lost
// node in its first manufacturer byte.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "node/diagnostic_objects.hpp"
#include "node/profiles/horner/bits.hpp"
#include "node/profiles/horner/objects.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

namespace axis_obj = horner::obj;
namespace cmd = horner::command;
namespace st = horner::status;

constexpr uint8_t kMaster = 0x20, kOther = 0x21;
constexpr uint32_t kValueTooHigh = 0x06090031;

class CommunicationErrors : public NodeHarness {
 protected:
  void SetUp() override {
    make(2);
    // Watch the master and another node, 300 ms each (CiA 301 0x1016: node << 16 | ms).
    ASSERT_EQ(sdo_write(0x1016, 1, (uint32_t{kMaster} << 16) | 300), 0u);
    ASSERT_EQ(sdo_write(0x1016, 2, (uint32_t{kOther} << 16) | 300), 0u);
    for (unsigned a = 0; a < 2; ++a) {
      command(a, cmd::kClearErrors);
      uint16_t p = axis_obj::index(a, axis_obj::kProfile);
      ASSERT_EQ(sdo_write(p, horner::profile_sub::kDeceleration, 400, 2), 0u);  // %AQ7: 400 ms
    }
    nmt(0x01);
    beat(kMaster);
    beat(kOther);
  }

  void command(unsigned a, uint16_t bits) {
    ASSERT_EQ(sdo_write(axis_obj::index(a, axis_obj::kCommandBits), 0, bits, 2), 0u);
    ASSERT_EQ(sdo_write(axis_obj::index(a, axis_obj::kCommandBits), 0, 0, 2), 0u);
  }
  void jog(unsigned a) {
    ASSERT_EQ(sdo_write(axis_obj::index(a, axis_obj::kCommandBits), 0, cmd::kJogUp, 2), 0u);
  }
  void beat(uint8_t n) { frame(CanFrame(0x700u + n, {0x05})); }
  // Heartbeats of `nodes` every 100 ms for `ms`.
  void beating(std::vector<uint8_t> nodes, uint64_t ms) {
    for (uint64_t done = 0; done < ms; done += 100) {
      advance_ms(100);
      for (uint8_t n : nodes) beat(n);
    }
  }
  uint16_t status(unsigned a) {
    return od().get<uint16_t>(axis_obj::index(a, axis_obj::kStatusBits), 0);
  }
  int32_t velocity(unsigned a) {
    return od().get<int32_t>(axis_obj::index(a, axis_obj::kVelocity), 0);
  }
  int32_t position(unsigned a) {
    return od().get<int32_t>(axis_obj::index(a, axis_obj::kMotorPosition), 0);
  }
  // The NMT states the node announced in heartbeats since `from`.
  std::vector<uint8_t> announced(size_t from) const {
    std::vector<uint8_t> out;
    for (const CanFrame& f : with_id(kHeartbeatId, from)) out.push_back(f.data[0]);
    return out;
  }
  size_t heartbeat_emcys(uint8_t node, size_t from) const {
    size_t n = 0;
    for (const CanFrame& f : emcys(from))
      if (emcy_code(f) == 0x8130 && f.data[3] == node) ++n;
    return n;
  }
};

TEST_F(CommunicationErrors, TheLostMasterRampsEveryAxisDownAndLatchesI8InVirtualTime) {
  ASSERT_EQ(sdo_write(0x1029, 1, 1, 1), 0u);  // no change of state: the TPDOs go on
  jog(0);
  jog(1);
  beating({kMaster, kOther}, 2000);
  ASSERT_EQ(velocity(0), 1000);  // the power-on profile's running velocity, steps/s
  ASSERT_EQ(velocity(1), 1000);
  uint64_t last_beat = t;
  size_t from = sent.size();
  // The master falls silent; the other node goes on.
  advance_ms(300);
  beat(kOther);
  EXPECT_EQ(velocity(0), 1000) << "the consumer time (300 ms) has not passed";
  EXPECT_EQ(status(0) & st::kPowerUp, 0);
  advance_ms(1);
  EXPECT_EQ(heartbeat_emcys(kMaster, from), 1u);
  for (unsigned a = 0; a < 2; ++a) {
    EXPECT_NE(status(a) & st::kDecelerating, 0) << "axis " << a;
    EXPECT_NE(status(a) & st::kPowerUp, 0) << "axis " << a << ": %I8 latches";
  }
  // The %AQ7 ramp (400 ms from 1000 steps/s), not a sudden stop.
  advance_ms(200);
  beat(kOther);
  EXPECT_GT(velocity(0), 300);
  EXPECT_LT(velocity(0), 700);
  advance_ms(250);
  beat(kOther);
  for (unsigned a = 0; a < 2; ++a) {
    EXPECT_EQ(velocity(a), 0) << "axis " << a;
    EXPECT_EQ(status(a) & st::kMoving, 0) << "axis " << a;
  }
  EXPECT_GT(t, last_beat + 300'000);
  // Nothing moves again until the errors are cleared, even with the master back.
  int32_t stopped = position(0);
  beat(kMaster);
  jog(0);
  beating({kMaster, kOther}, 500);
  EXPECT_EQ(position(0), stopped);
  EXPECT_EQ(announced(from), std::vector<uint8_t>(announced(from).size(), 0x05))
      << "still operational";
}

TEST_F(CommunicationErrors, OnlyTheConfiguredMasterStopsTheAxes) {
  ASSERT_EQ(sdo_write(0x1029, 1, 1, 1), 0u);
  ASSERT_EQ(sdo_write(kMasterNodeId, 0, kMaster, 1), 0u);
  jog(0);
  beating({kMaster, kOther}, 1000);
  size_t from = sent.size();
  beating({kMaster}, 1000);  // node 0x21 is lost: EMCY 0x8130 only
  EXPECT_EQ(heartbeat_emcys(kOther, from), 1u);
  EXPECT_EQ(velocity(0), 1000);
  EXPECT_EQ(status(0) & st::kPowerUp, 0);
  advance_ms(800);  // the master is lost (0x8130 is already active, for node 0x21)
  EXPECT_EQ(velocity(0), 0);
  EXPECT_NE(status(0) & st::kPowerUp, 0);
}

TEST_F(CommunicationErrors, AnyMonitoredNodeIsTheMasterWhen2F11IsZero) {
  ASSERT_EQ(sdo_write(0x1029, 1, 1, 1), 0u);
  jog(0);
  beating({kMaster, kOther}, 1000);
  beating({kMaster}, 500);
  EXPECT_NE(status(0) & st::kPowerUp, 0);
  EXPECT_EQ(od().get<uint8_t>(kMasterNodeId, 0), 0);
}

TEST_F(CommunicationErrors, Behaviour0TakesAnOperationalNodeToPreOperational) {
  ASSERT_EQ(od().get<uint8_t>(0x1029, 1), 0) << "CiA 301 default";
  size_t from = sent.size();
  beating({kOther}, 500);  // the master's heartbeat times out
  EXPECT_EQ(node->state(), NmtState::PreOperational);
  std::vector<uint8_t> states = announced(from);
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(states.front(), 0x7F) << "the new state is confirmed at once";
  // Pre-operational stays pre-operational on the next error.
  beating({}, 500);
  EXPECT_EQ(node->state(), NmtState::PreOperational);
}

TEST_F(CommunicationErrors, Behaviour0LeavesPreOperationalAndStoppedAsTheyAre) {
  nmt(0x02);  // stopped
  beating({kOther}, 500);
  EXPECT_EQ(node->state(), NmtState::Stopped);
  nmt(0x80);
  beat(kMaster);
  beating({kOther}, 500);
  EXPECT_EQ(node->state(), NmtState::PreOperational);
}

TEST_F(CommunicationErrors, Behaviour1KeepsTheState) {
  ASSERT_EQ(sdo_write(0x1029, 1, 1, 1), 0u);
  beating({kOther}, 500);
  EXPECT_EQ(node->state(), NmtState::Operational);
  EXPECT_EQ(heartbeat_emcys(kMaster, 0), 1u);
}

TEST_F(CommunicationErrors, Behaviour2StopsTheNodeFromOperationalAndPreOperational) {
  ASSERT_EQ(sdo_write(0x1029, 1, 2, 1), 0u);
  size_t from = sent.size();
  beating({kOther}, 500);
  EXPECT_EQ(node->state(), NmtState::Stopped);
  std::vector<uint8_t> states = announced(from);
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(states.front(), 0x04);
  // In stopped the node answers no SDO; NMT takes it back.
  nmt(0x80);
  beat(kMaster);
  beat(kOther);
  beating({kOther}, 500);
  EXPECT_EQ(node->state(), NmtState::Stopped);
}

TEST_F(CommunicationErrors, BusOffIsACommunicationErrorAndStopsTheAxes) {
  ASSERT_EQ(sdo_write(0x1029, 1, 2, 1), 0u);
  jog(1);
  beating({kMaster, kOther}, 1000);
  device->on_bus_event(BusEvent::BusOff, t);
  EXPECT_EQ(node->state(), NmtState::Stopped);
  EXPECT_NE(status(1) & st::kDecelerating, 0);
  EXPECT_NE(status(1) & st::kPowerUp, 0);
}

TEST_F(CommunicationErrors, NmtStoppedRampsTheAxesDownPreOperationalDoesNot) {
  ASSERT_EQ(sdo_write(0x1029, 1, 1, 1), 0u);
  jog(0);
  beating({kMaster, kOther}, 1000);
  nmt(0x80);  // pre-operational: SDO still reaches the axes, the job goes on
  beating({kMaster, kOther}, 500);
  EXPECT_EQ(velocity(0), 1000);
  EXPECT_EQ(status(0) & st::kPowerUp, 0);
  nmt(0x02);
  beating({kMaster, kOther}, 100);
  EXPECT_NE(status(0) & st::kDecelerating, 0);
  EXPECT_NE(status(0) & st::kPowerUp, 0);
  beating({kMaster, kOther}, 400);
  EXPECT_EQ(velocity(0), 0);
}

TEST_F(CommunicationErrors, ValuesOutsideTheStandardsAreRefusedAndBothAreStored) {
  EXPECT_EQ(sdo_write(0x1029, 1, 3, 1), kValueTooHigh);     // 3..0x7F reserved
  EXPECT_EQ(sdo_write(0x1029, 1, 0x80, 1), kValueTooHigh);  // no manufacturer values here
  EXPECT_EQ(sdo_write(kMasterNodeId, 0, 128, 1), kValueTooHigh);
  EXPECT_EQ(*sdo_read(0x1029, 0), 1u);  // highest sub-index
  ASSERT_EQ(sdo_write(0x1029, 1, 2, 1), 0u);
  ASSERT_EQ(sdo_write(kMasterNodeId, 0, kMaster, 1), 0u);
  ASSERT_EQ(sdo_write(0x1010, 1, 0x65766173), 0u);  // "save"
  make(2);                                          // a restart
  EXPECT_EQ(od().get<uint8_t>(0x1029, 1), 2);
  EXPECT_EQ(od().get<uint8_t>(kMasterNodeId, 0), kMaster);
}

}  // namespace
}  // namespace stepnode::node::test
