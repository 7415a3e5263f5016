// PDOs (CiA 301 7.2.2, 7.5.2.35-38) configured the way a master does it, through SDO
// frames to the node: the dynamic mapping procedure, TPDOs on SYNC (types 0, 1, n), on
// change (254/255) with inhibit time and event timer, RPDOs (event-driven and
// synchronous), length errors and deadline monitoring.
#include "node/emcy.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

class PdoTest : public PdoHarness {};

TEST_F(PdoTest, MappingProcedureOverSdoAndItsRefusals) {
  // While the PDO exists (COB-ID bit 31 = 0) neither count nor entries may change.
  ASSERT_EQ(sdo_write(0x1400, 1, kRpdo1), 0u);
  EXPECT_EQ(sdo_write(0x1600, 0, 0, 1), 0x08000022u);
  EXPECT_EQ(sdo_write(0x1600, 1, kReg1), 0x08000022u);
  // Step 1: destroy the PDO.
  ASSERT_EQ(sdo_write(0x1400, 1, 0x80000000u | kRpdo1), 0u);
  // Entries change only while the count is 0.
  EXPECT_EQ(sdo_write(0x1600, 1, kReg1), 0x08000022u);
  // Step 2: disable the mapping.
  ASSERT_EQ(sdo_write(0x1600, 0, 0, 1), 0u);
  // Step 3: the entries. An object that cannot be mapped, or a wrong length, is refused.
  EXPECT_EQ(sdo_write(0x1600, 1, 0x10000020), 0x06040041u);  // device type: not mappable
  EXPECT_NE(sdo_write(0x1600, 1, 0x2F000110), 0u);           // 16 bits of a 32-bit entry
  EXPECT_EQ(sdo_write(0x1600, 1, 0x2F090020), 0x06020000u);  // no such object
  ASSERT_EQ(sdo_write(0x1600, 1, kReg1), 0u);
  ASSERT_EQ(sdo_write(0x1600, 2, kReg2), 0u);
  ASSERT_EQ(sdo_write(0x1600, 3, kReg3), 0u);
  // Step 4: enable. Three 32-bit entries are more than 64 bits (0x06040042).
  EXPECT_EQ(sdo_write(0x1600, 0, 3, 1), 0x06040042u);
  ASSERT_EQ(sdo_write(0x1600, 0, 2, 1), 0u);
  // Step 5: create the PDO.
  ASSERT_EQ(sdo_write(0x1400, 2, 255, 1), 0u);
  ASSERT_EQ(sdo_write(0x1400, 1, kRpdo1), 0u);
  EXPECT_EQ(sdo_read(0x1600, 0), 2u);
  EXPECT_EQ(sdo_read(0x1600, 1), kReg1);
  EXPECT_EQ(sdo_read(0x1600, 2), kReg2);
  EXPECT_EQ(sdo_read(0x1400, 1), kRpdo1);
  // And the PDO works with the new mapping.
  nmt(0x01);
  frame(CanFrame(kRpdo1, {1, 0, 0, 0, 2, 0, 0, 0}));
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 1u);
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 2), 2u);
}

TEST_F(PdoTest, TransmissionTypesReservedOrRtrOnlyAreRefused) {
  ASSERT_EQ(sdo_write(0x1800, 1, 0xC0000185), 0u);
  for (uint8_t type : {241, 250, 251, 252, 253})
    EXPECT_EQ(sdo_write(0x1800, 2, type, 1), 0x06090030u) << int(type);
}

TEST_F(PdoTest, TpdoType1GoesOutOnEverySyncWithTheCurrentValues) {
  map_tpdo(0, {kReg1, 0x10010008}, 1);  // a user register and the error register
  nmt(0x01);
  ASSERT_EQ(sdo_write(0x2F00, 1, 0xC0FFEE42), 0u);
  size_t from = sent.size();
  advance_ms(50);
  EXPECT_TRUE(with_id(kTpdo1, from).empty());  // synchronous: only on SYNC
  sync();
  auto pdo = with_id(kTpdo1, from);
  ASSERT_EQ(pdo.size(), 1u);
  EXPECT_EQ(pdo[0], CanFrame(kTpdo1, {0x42, 0xEE, 0xFF, 0xC0, 0x00}));
  for (uint32_t v = 1; v <= 4; ++v) {
    ASSERT_EQ(sdo_write(0x2F00, 1, v), 0u);
    sync();
  }
  pdo = with_id(kTpdo1, from);
  ASSERT_EQ(pdo.size(), 5u);
  EXPECT_EQ(pdo[4], CanFrame(kTpdo1, {4, 0, 0, 0, 0}));
}

TEST_F(PdoTest, TpdoTypeNGoesOutOnEveryNthSync) {
  map_tpdo(0, {kReg1}, 3);
  nmt(0x01);
  size_t from = sent.size();
  std::vector<int> on;
  for (int i = 1; i <= 10; ++i) {
    size_t before = with_id(kTpdo1, from).size();
    sync();
    if (with_id(kTpdo1, from).size() > before) on.push_back(i);
  }
  EXPECT_EQ(on, (std::vector<int>{3, 6, 9}));
}

TEST_F(PdoTest, TpdoType0GoesOutOnTheSyncAfterAChangeOnly) {
  map_tpdo(0, {kReg1}, 0);
  nmt(0x01);
  sync();  // whatever entering operational sent, from here on only changes count
  size_t from = sent.size();
  for (int i = 0; i < 5; ++i) sync();
  EXPECT_TRUE(with_id(kTpdo1, from).empty());
  ASSERT_EQ(sdo_write(0x2F00, 1, 77), 0u);
  advance_ms(20);
  EXPECT_TRUE(with_id(kTpdo1, from).empty());  // acyclic synchronous: waits for the SYNC
  sync();
  auto pdo = with_id(kTpdo1, from);
  ASSERT_EQ(pdo.size(), 1u);
  EXPECT_EQ(pdo[0], u32_frame(kTpdo1, 77));
  sync();
  sync();
  EXPECT_EQ(with_id(kTpdo1, from).size(), 1u);
}

TEST_F(PdoTest, TpdoOnChangeGoesOutAtOnce) {
  map_tpdo(0, {kReg1}, 254);
  ASSERT_EQ(sdo_write(0x2F00, 1, 5), 0u);
  size_t from = sent.size();
  nmt(0x01);
  // Entering operational: the current values once.
  auto pdo = with_id(kTpdo1, from);
  ASSERT_EQ(pdo.size(), 1u);
  EXPECT_EQ(pdo[0], u32_frame(kTpdo1, 5));
  ASSERT_EQ(sdo_write(0x2F00, 1, 6), 0u);
  pdo = with_id(kTpdo1, from);
  ASSERT_EQ(pdo.size(), 2u);
  EXPECT_EQ(pdo[1], u32_frame(kTpdo1, 6));
  // No change, no event timer, SYNCs: nothing.
  advance_ms(1000);
  sync();
  EXPECT_EQ(with_id(kTpdo1, from).size(), 2u);
  // Writing the same value is no change.
  ASSERT_EQ(sdo_write(0x2F00, 1, 6), 0u);
  EXPECT_EQ(with_id(kTpdo1, from).size(), 2u);
  // A value the application changes (not over SDO) goes out on the next tick.
  od().put<uint32_t>(0x2F00, 1, 8);
  advance_ms(1);
  EXPECT_EQ(with_id(kTpdo1, from).back(), u32_frame(kTpdo1, 8));
}

TEST_F(PdoTest, TpdoInhibitTimeHoldsBackTheLatestValue) {
  map_tpdo(0, {kReg1}, 254, 100);  // 100 x 100 us = 10 ms
  nmt(0x01);
  advance_ms(20);
  size_t from = sent.size();
  uint64_t t0 = t;
  ASSERT_EQ(sdo_write(0x2F00, 1, 1), 0u);  // sent at once
  advance_ms(2);
  ASSERT_EQ(sdo_write(0x2F00, 1, 2), 0u);  // inhibited...
  advance_ms(3);
  ASSERT_EQ(sdo_write(0x2F00, 1, 3), 0u);  // ...and superseded
  advance_us(4'900, 100);
  EXPECT_EQ(with_id(kTpdo1, from).size(), 1u);  // t0 + 9.9 ms
  advance_us(100, 100);
  auto pdo = with_id(kTpdo1, from);
  ASSERT_EQ(pdo.size(), 2u);
  EXPECT_EQ(pdo[0], u32_frame(kTpdo1, 1));
  EXPECT_EQ(pdo[1], u32_frame(kTpdo1, 3));
  auto times = times_of(kTpdo1, from);
  EXPECT_EQ(times[0], t0);
  EXPECT_EQ(times[1], t0 + 10'000);
  // The inhibit time may only change while the PDO does not exist (7.5.2.35).
  EXPECT_EQ(sdo_write(0x1800, 3, 5, 2), 0x06090030u);
}

TEST_F(PdoTest, TpdoEventTimerSendsWithoutChangeAndRestartsOnEachTransmission) {
  map_tpdo(0, {kReg1}, 255, 0, 100);  // event timer 100 ms
  size_t from = sent.size();
  uint64_t t0 = t;
  nmt(0x01);  // entering operational sends the current values once
  advance_ms(350);
  auto times = times_of(kTpdo1, from);
  ASSERT_EQ(times.size(), 4u);
  EXPECT_EQ(times[0], t0);
  EXPECT_EQ(times[1], t0 + 100'000);
  EXPECT_EQ(times[2], t0 + 200'000);
  EXPECT_EQ(times[3], t0 + 300'000);
  // A change at +350 ms goes out at once and the next timer event is 100 ms later.
  ASSERT_EQ(sdo_write(0x2F00, 1, 9), 0u);
  advance_ms(150);
  times = times_of(kTpdo1, from);
  ASSERT_EQ(times.size(), 6u);
  EXPECT_EQ(times[4], t0 + 350'000);
  EXPECT_EQ(times[5], t0 + 450'000);
  EXPECT_EQ(with_id(kTpdo1, from).back(), u32_frame(kTpdo1, 9));
}

TEST_F(PdoTest, RpdoEventDrivenIsAppliedAtOnce) {
  map_rpdo(0, {kReg1, kReg2}, 255);
  nmt(0x01);
  frame(CanFrame(kRpdo1, {0x01, 0x02, 0x03, 0x04, 0xAA, 0xBB, 0xCC, 0xDD}));
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 0x04030201u);
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 2), 0xDDCCBBAAu);
  EXPECT_EQ(sdo_read(0x2F00, 1), 0x04030201u);
  EXPECT_TRUE(emcys().empty());
}

TEST_F(PdoTest, RpdoOfAnotherIdOrRtrIsNotApplied) {
  map_rpdo(0, {kReg1}, 255);
  nmt(0x01);
  frame(u32_frame(0x206, 5));
  CanFrame rtr = u32_frame(kRpdo1, 6);
  rtr.rtr = true;
  frame(rtr);
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 0u);
}

TEST_F(PdoTest, SynchronousRpdoIsAppliedAtTheNextSync) {
  map_rpdo(0, {kReg1}, 1);
  nmt(0x01);
  frame(u32_frame(kRpdo1, 10));
  advance_ms(50);
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 0u);
  frame(u32_frame(kRpdo1, 11));  // the newest before the SYNC wins
  sync();
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 11u);
  // Applied once: a later write is not overwritten by the next SYNC.
  od().put<uint32_t>(0x2F00, 1, 99);
  sync();
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 99u);
  // Leaving operational forgets data that waits for a SYNC.
  frame(u32_frame(kRpdo1, 12));
  nmt(0x80);
  nmt(0x01);
  sync();
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 99u);
}

TEST_F(PdoTest, SynchronousRpdoAndTpdoOnTheSameSync) {
  // A synchronous TPDO samples at the SYNC; the RPDO received before it is actuated then.
  map_rpdo(0, {kReg1}, 1);
  map_tpdo(0, {kReg1}, 1);
  nmt(0x01);
  frame(u32_frame(kRpdo1, 0x55));
  size_t from = sent.size();
  sync();
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 0x55u);
  ASSERT_EQ(with_id(kTpdo1, from).size(), 1u);
}

TEST_F(PdoTest, ShortRpdoIsNotAppliedAndRaisesEmcy8210) {
  map_rpdo(0, {kReg1, kReg2}, 255);
  nmt(0x01);
  size_t from = sent.size();
  frame(CanFrame(kRpdo1, {1, 2, 3, 4, 5, 6, 7}));  // 7 bytes for an 8-byte mapping
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 0u);    // not even the complete first entry
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 2), 0u);
  auto e = emcys(from);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(emcy_code(e[0]), 0x8210);  // PDO not processed due to length error
  EXPECT_EQ(e[0].data[2] & 0x10, 0x10);
  // A synchronous RPDO that is too short is not kept for the SYNC either.
  map_rpdo(0, {kReg1, kReg2}, 1);
  nmt(0x01);
  frame(CanFrame(kRpdo1, {1, 2, 3}));
  sync();
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 0u);
}

TEST_F(PdoTest, LongRpdoIsAppliedAndReportedWithEmcy8220) {
  map_rpdo(0, {kReg1}, 255);
  nmt(0x01);
  size_t from = sent.size();
  frame(CanFrame(kRpdo1, {1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 0x04030201u);
  auto e = emcys(from);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(emcy_code(e[0]), 0x8220);
}

TEST_F(PdoTest, RpdoDeadlineMonitoringRaisesEmcy8250) {
  map_rpdo(0, {kReg1}, 255, 100);  // event timer 100 ms
  nmt(0x01);
  advance_ms(1000);  // monitoring starts with the first reception
  EXPECT_TRUE(emcys().empty());
  frame(u32_frame(kRpdo1, 1));
  advance_ms(100);
  EXPECT_TRUE(emcys().empty());
  advance_ms(1);
  auto e = emcys();
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(emcy_code(e[0]), 0x8250);
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0) & 0x11, 0x11);
  advance_ms(500);
  EXPECT_EQ(emcys().size(), 1u);  // one event, not one per tick
  // The RPDO is back: error reset.
  frame(u32_frame(kRpdo1, 2));
  e = emcys();
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(emcy_code(e[1]), 0x0000);
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0);
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 2u);
}

TEST_F(PdoTest, RpdoTimeoutSurvivesLeavingOperationalUntilTheRpdoIsBack) {
  map_rpdo(0, {kReg1}, 255, 100);
  nmt(0x01);
  frame(u32_frame(kRpdo1, 1));
  advance_ms(150);
  ASSERT_EQ(emcys().size(), 1u);
  nmt(0x80);
  nmt(0x01);
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0x11);  // still late
  size_t from = sent.size();
  frame(u32_frame(kRpdo1, 2));
  auto e = emcys(from);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(emcy_code(e[0]), 0x0000);
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0);
}

TEST_F(PdoTest, RpdoTimeoutClearsOnlyWhenEveryLateRpdoIsBack) {
  map_rpdo(0, {kReg1}, 255, 100);
  map_rpdo(1, {kReg2}, 255, 100);
  nmt(0x01);
  frame(u32_frame(kRpdo1, 1));
  frame(u32_frame(0x305, 1));
  advance_ms(150);
  ASSERT_EQ(emcys().size(), 1u);
  size_t from = sent.size();
  frame(u32_frame(kRpdo1, 2));
  EXPECT_TRUE(emcys(from).empty());  // RPDO 2 is still late
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0x11);
  frame(u32_frame(0x305, 2));
  ASSERT_EQ(emcys(from).size(), 1u);
  EXPECT_EQ(emcy_code(emcys(from)[0]), 0x0000);
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0);
}

TEST_F(PdoTest, RpdoTimeoutEndsWhenThePdoIsDestroyed) {
  map_rpdo(0, {kReg1}, 255, 100);
  nmt(0x01);
  frame(u32_frame(kRpdo1, 1));
  advance_ms(150);
  ASSERT_EQ(od().get<uint8_t>(0x1001, 0), 0x11);
  size_t from = sent.size();
  ASSERT_EQ(sdo_write(0x1400, 1, 0x80000000u | kRpdo1), 0u);
  advance_ms(1);
  ASSERT_EQ(emcys(from).size(), 1u);
  EXPECT_EQ(emcy_code(emcys(from)[0]), 0x0000);
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0);
}

TEST_F(PdoTest, ResetCommunicationForgetsRpdoTimeouts) {
  map_rpdo(0, {kReg1}, 255, 100);
  map_rpdo(1, {kReg2}, 255, 100);
  ASSERT_EQ(sdo_write(0x1010, 2, 0x65766173), 0u);  // keep the mapping over the reset
  nmt(0x01);
  frame(u32_frame(kRpdo1, 1));
  frame(u32_frame(0x305, 1));
  advance_ms(150);
  ASSERT_EQ(od().get<uint8_t>(0x1001, 0), 0x11);
  nmt(0x82);  // errors and history start afresh
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0);
  nmt(0x01);
  frame(u32_frame(0x305, 2));  // only RPDO 2 comes back, and is late again
  advance_ms(150);
  ASSERT_EQ(od().get<uint8_t>(0x1001, 0), 0x11);
  size_t from = sent.size();
  frame(u32_frame(0x305, 3));
  ASSERT_EQ(emcys(from).size(), 1u);  // RPDO 1's timeout from before the reset is gone
  EXPECT_EQ(emcy_code(emcys(from)[0]), 0x0000);
  EXPECT_EQ(od().get<uint8_t>(0x1001, 0), 0);
}

TEST_F(PdoTest, PdoInvalidatedWhileOperationalStopsAndComesBack) {
  map_tpdo(0, {kReg1}, 1);
  nmt(0x01);
  ASSERT_EQ(sdo_write(0x1800, 1, 0xC0000185), 0u);
  size_t from = sent.size();
  sync();
  EXPECT_TRUE(with_id(kTpdo1, from).empty());
  ASSERT_EQ(sdo_write(0x1800, 1, 0x40000185), 0u);
  sync();
  EXPECT_EQ(with_id(kTpdo1, from).size(), 1u);
}

}  // namespace
}  // namespace stepnode::node::test
