// Error conditions across an NMT reset communication (found in review, 2026-12-06): CiA 301
// 7.3.2.2.1 puts back only the communication objects, so the errors the communication
// services raised end with them, and those of the CAN controller and of the application
// (an axis error) are still there: 0x1001 shows them and the node announces them again
// after its boot-up (0x1003 was put back with 0x1000-0x1FFF). Before, 0x1001 read 0 and
// their end sent no error reset. Frames from 7.2.7.3.1: code (LE), 0x1001, 5 bytes.
#include "node/motion/axis_registers.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

const CanFrame kErrorReset(0x85, {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00});
const CanFrame kErrorPassive(0x85, {0x20, 0x81, 0x11, 0, 0, 0, 0, 0});

class EmcyResetCommunication : public NodeHarness {
 protected:
  void SetUp() override {
    NodeHarness::SetUp();
    nmt(0x01);
    rpdo1(motion::command::kClearErrors, 0);  // the power-up error %I8 cleared first
    rpdo1(0, 0);
    ASSERT_EQ(*sdo_read(0x1001, 0), 0u);
  }
  void rpdo1(uint16_t bits, int32_t dest) {  // axis 1: command bits (U16) + destination (I32)
    auto d = static_cast<uint32_t>(dest);
    frame(CanFrame(0x205, {static_cast<uint8_t>(bits), static_cast<uint8_t>(bits >> 8),
                           static_cast<uint8_t>(d), static_cast<uint8_t>(d >> 8),
                           static_cast<uint8_t>(d >> 16), static_cast<uint8_t>(d >> 24)}));
    advance_ms(2);
  }
};

TEST_F(EmcyResetCommunication, TheControllersErrorPassiveOutlivesIt) {
  device->on_bus_event(BusEvent::ErrorPassive, t);
  size_t from = sent.size();
  nmt(0x82);
  advance_ms(2);
  EXPECT_EQ(*sdo_read(0x1001, 0), 0x11u) << "generic + communication: still error passive";
  EXPECT_EQ(emcys(from), std::vector<CanFrame>{kErrorPassive}) << "announced again";
  EXPECT_EQ(*sdo_read(0x1003, 1) & 0xFFFF, 0x8120u);
  from = sent.size();
  device->on_bus_event(BusEvent::ErrorActive, t);
  EXPECT_EQ(emcys(from), std::vector<CanFrame>{kErrorReset});
  EXPECT_EQ(*sdo_read(0x1001, 0), 0u);
}

TEST_F(EmcyResetCommunication, AnAxisErrorOutlivesIt) {
  rpdo1(motion::command::kMoveRelative, 8'388'608);  // outside the module's range: Illegal Move
  advance_ms(50);
  ASSERT_EQ(*sdo_read(0x1001, 0), 0x81u);
  size_t from = sent.size();
  nmt(0x82);
  nmt(0x01);
  advance_ms(2);
  EXPECT_EQ(*sdo_read(0x1001, 0), 0x81u) << "generic + manufacturer: the axis is in error";
  ASSERT_EQ(emcys(from).size(), 1u);
  EXPECT_EQ(emcys(from)[0].data[0], 0x01);  // 0xFF01 again
  EXPECT_EQ(emcys(from)[0].data[1], 0xFF);
  from = sent.size();
  rpdo1(motion::command::kClearErrors, 0);
  rpdo1(0, 0);
  EXPECT_EQ(emcys(from), std::vector<CanFrame>{kErrorReset});
}

TEST_F(EmcyResetCommunication, TheCommunicationServicesErrorsEndWithIt) {
  ASSERT_EQ(sdo_write(0x1016, 1, (0x20u << 16) | 100), 0u);  // watch node 0x20, 100 ms
  frame(CanFrame(0x720, {0x05}));
  advance_ms(200);  // lost: EMCY 0x8130
  ASSERT_EQ(*sdo_read(0x1001, 0) & 0x10u, 0x10u);
  const size_t from = sent.size();
  nmt(0x82);
  advance_ms(2);
  // The consumer starts anew: its 0x8130 is not announced again (the axis error the lost
  // heartbeat latched, %I8, is the application's and is).
  for (const CanFrame& f : emcys(from)) EXPECT_FALSE(f.data[0] == 0x30 && f.data[1] == 0x81);
  EXPECT_EQ(*sdo_read(0x1001, 0) & 0x10u, 0u) << "no communication error left";
}

}  // namespace
}  // namespace stepnode::node::test
