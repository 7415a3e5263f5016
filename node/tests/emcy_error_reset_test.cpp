// EMCY error reset (CiA 301 7.2.7.1): when an error condition ends and no other is active,
// the node sends EMCY 0x0000 with the error register as it is then; 0x1001 reads the same
// register and 0x1003 keeps the errors, not the resets. One test per clearable condition,
// the frames written from 7.2.7.3.1: code (LE), error register, 5 manufacturer bytes.
#include "node/motion/axis_registers.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

const CanFrame kErrorReset(0x85, {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00});

class EmcyErrorReset : public NodeHarness {
 protected:
  static constexpr uint32_t kRpdo1 = 0x205;  // axis 1: command bits (U16) + destination (I32)
  void SetUp() override {
    NodeHarness::SetUp();
    nmt(0x01);
    rpdo1(motion::command::kClearErrors, 0);  // the power-up error %I8 cleared first
    rpdo1(0, 0);
    ASSERT_EQ(*sdo_read(0x1001, 0), 0u);
    ASSERT_EQ(sdo_write(0x1003, 0, 0, 1), 0u);  // an empty history
  }
  void rpdo1(uint16_t bits, int32_t dest) {
    auto d = static_cast<uint32_t>(dest);
    frame(CanFrame(kRpdo1, {static_cast<uint8_t>(bits), static_cast<uint8_t>(bits >> 8),
                            static_cast<uint8_t>(d), static_cast<uint8_t>(d >> 8),
                            static_cast<uint8_t>(d >> 16), static_cast<uint8_t>(d >> 24)}));
    advance_ms(2);
  }
  // The register and the history after the reset: nothing active, one error recorded.
  void expect_consistent_after_reset(uint16_t code) {
    EXPECT_EQ(*sdo_read(0x1001, 0), 0u);
    EXPECT_EQ(*sdo_read(0x1003, 0), 1u);
    EXPECT_EQ(*sdo_read(0x1003, 1) & 0xFFFF, code);
  }
};

TEST_F(EmcyErrorReset, RpdoTooShortUntilTheNextRpdoOfTheRightLength) {
  size_t from = sent.size();
  frame(CanFrame(kRpdo1, {0x00, 0x00}));   // 2 bytes for a 6-byte mapping
  frame(CanFrame(kRpdo1, {0x00, 0x00}));   // still active: not sent again
  EXPECT_EQ(*sdo_read(0x1001, 0), 0x11u);  // generic + communication
  rpdo1(0, 0);
  // 0x8210, register 0x11, COB-ID 0x0205 LE, 2 bytes received; then the reset.
  EXPECT_EQ(emcys(from),
            (std::vector<CanFrame>{CanFrame(0x85, {0x10, 0x82, 0x11, 0x05, 0x02, 0x02, 0x00, 0x00}),
                                   kErrorReset}));
  expect_consistent_after_reset(0x8210);
}

TEST_F(EmcyErrorReset, RpdoTooLongUntilTheNextRpdoOfTheRightLength) {
  size_t from = sent.size();
  frame(CanFrame(kRpdo1,
                 {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}));  // 8 for 6: applied, reported
  rpdo1(0, 0);
  EXPECT_EQ(emcys(from),
            (std::vector<CanFrame>{CanFrame(0x85, {0x20, 0x82, 0x11, 0x05, 0x02, 0x08, 0x00, 0x00}),
                                   kErrorReset}));
  expect_consistent_after_reset(0x8220);
}

TEST_F(EmcyErrorReset, AnAxisErrorUntilClearErrors) {
  size_t from = sent.size();
  rpdo1(motion::command::kMoveRelative, 8'388'608);  // outside the module's range: Illegal Move
  advance_ms(50);
  auto e = emcys(from);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].data[0], 0x01);  // 0xFF01: axis 1
  EXPECT_EQ(e[0].data[1], 0xFF);
  EXPECT_EQ(e[0].data[2], 0x81);  // generic + manufacturer
  EXPECT_EQ(*sdo_read(0x1001, 0), 0x81u);
  rpdo1(motion::command::kClearErrors, 0);
  rpdo1(0, 0);
  e = emcys(from);
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(e[1], kErrorReset);
  expect_consistent_after_reset(0xFF01);
}

TEST_F(EmcyErrorReset, ErrorPassiveUntilErrorActive) {
  size_t from = sent.size();
  device->on_bus_event(BusEvent::ErrorPassive, t);
  device->on_bus_event(BusEvent::ErrorActive, t);
  EXPECT_EQ(emcys(from), (std::vector<CanFrame>{CanFrame(0x85, {0x20, 0x81, 0x11, 0, 0, 0, 0, 0}),
                                                kErrorReset}));
  expect_consistent_after_reset(0x8120);
}

TEST_F(EmcyErrorReset, BusOffUntilTheControllerRestartedAndTheAxisErrorCleared) {
  ASSERT_EQ(sdo_write(0x1029, 1, 1, 1), 0u);  // no change of NMT state: the EMCYs in operational
  size_t from = sent.size();
  device->on_bus_event(BusEvent::ErrorPassive, t);
  device->on_bus_event(BusEvent::BusOff, t);  // a lost master: axis 1 latches %I8 (EMCY 0xFF01)
  device->on_bus_event(BusEvent::Restarted, t);
  // Error passive; the axis error (register 0x91: generic, communication, manufacturer);
  // recovered from bus-off (0x8140); the bus error ends but the axis error is active: no
  // reset until Clear Errors.
  auto e = emcys(from);
  ASSERT_EQ(e.size(), 3u);
  EXPECT_EQ(e[0], CanFrame(0x85, {0x20, 0x81, 0x11, 0, 0, 0, 0, 0}));
  EXPECT_EQ(emcy_code(e[1]), 0xFF01);
  EXPECT_EQ(e[1].data[2], 0x91);
  EXPECT_EQ(e[2], CanFrame(0x85, {0x40, 0x81, 0x91, 0, 0, 0, 0, 0}));
  EXPECT_EQ(*sdo_read(0x1001, 0), 0x81u);  // only the axis error is left
  rpdo1(motion::command::kClearErrors, 0);
  rpdo1(0, 0);
  e = emcys(from);
  ASSERT_EQ(e.size(), 4u);
  EXPECT_EQ(e[3], kErrorReset);
  EXPECT_EQ(*sdo_read(0x1001, 0), 0u);
  EXPECT_EQ(*sdo_read(0x1003, 0), 3u);
  EXPECT_EQ(*sdo_read(0x1003, 1) & 0xFFFF, 0x8140u);  // newest first
  EXPECT_EQ(*sdo_read(0x1003, 2) & 0xFFFF, 0xFF01u);
  EXPECT_EQ(*sdo_read(0x1003, 3) & 0xFFFF, 0x8120u);
}

TEST_F(EmcyErrorReset, HeartbeatConsumerUntilTheHeartbeatIsBack) {
  ASSERT_EQ(sdo_write(0x1029, 1, 1, 1), 0u);
  ASSERT_EQ(sdo_write(0x2F11, 0, 1, 1), 0u);  // the master is node 1: node 0x20's loss is EMCY only
  ASSERT_EQ(sdo_write(0x1016, 1, (0x20u << 16) | 100), 0u);  // node 0x20, 100 ms
  frame(CanFrame(0x720, {0x05}));
  size_t from = sent.size();
  advance_ms(150);
  frame(CanFrame(0x720, {0x05}));
  // 0x8130, register 0x11, manufacturer byte 0: the node lost.
  EXPECT_EQ(emcys(from), (std::vector<CanFrame>{
                             CanFrame(0x85, {0x30, 0x81, 0x11, 0x20, 0, 0, 0, 0}), kErrorReset}));
  expect_consistent_after_reset(0x8130);
}

TEST_F(EmcyErrorReset, LifeGuardingUntilTheNextRequestAndTheAxisErrorCleared) {
  ASSERT_EQ(sdo_write(0x1029, 1, 1, 1), 0u);
  ASSERT_EQ(sdo_write(0x1017, 0, 0, 2), 0u);  // guarding instead of heartbeat
  ASSERT_EQ(sdo_write(0x100C, 0, 100, 2), 0u);
  ASSERT_EQ(sdo_write(0x100D, 0, 3, 1), 0u);  // node life time 300 ms
  CanFrame guard(0x705, {});
  guard.rtr = true;
  frame(guard);
  size_t from = sent.size();
  advance_ms(350);  // the guarding master is lost: 0x8130, and axis 1 latches %I8 (0xFF01)
  frame(guard);     // its requests are back: 0x8130 ends, the axis error stays
  auto e = emcys(from);
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(e[0], CanFrame(0x85, {0x30, 0x81, 0x11, 0, 0, 0, 0, 0}));
  EXPECT_EQ(emcy_code(e[1]), 0xFF01);
  EXPECT_EQ(*sdo_read(0x1001, 0), 0x81u);
  rpdo1(motion::command::kClearErrors, 0);
  rpdo1(0, 0);
  e = emcys(from);
  ASSERT_EQ(e.size(), 3u);
  EXPECT_EQ(e[2], kErrorReset);
  EXPECT_EQ(*sdo_read(0x1001, 0), 0u);
}

TEST_F(EmcyErrorReset, NoResetWhileAnotherErrorIsActiveTheLastOneSendsIt) {
  ASSERT_EQ(sdo_write(0x1029, 1, 1, 1), 0u);
  size_t from = sent.size();
  device->on_bus_event(BusEvent::ErrorPassive, t);
  frame(CanFrame(kRpdo1, {0x00}));
  rpdo1(0, 0);  // the RPDO error ends; error passive is still active: no reset, register 0x11
  EXPECT_EQ(emcys(from).size(), 2u);
  EXPECT_EQ(*sdo_read(0x1001, 0), 0x11u);
  device->on_bus_event(BusEvent::ErrorActive, t);
  ASSERT_EQ(emcys(from).size(), 3u);
  EXPECT_EQ(emcys(from)[2], kErrorReset);
}

// Error conditions across an NMT reset communication (found in review, 2026-12-06): CiA 301
// 7.3.2.2.1 puts back only the communication objects, so the errors the communication
// services raised end with them, and those of the CAN controller and of the application
// (an axis error) are still there: 0x1001 shows them and the node announces them again
// after its boot-up (0x1003 was put back with 0x1000-0x1FFF). Before, 0x1001 read 0 and
// their end sent no error reset.
class EmcyResetCommunication : public EmcyErrorReset {};

const CanFrame kErrorPassive(0x85, {0x20, 0x81, 0x11, 0, 0, 0, 0, 0});

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
