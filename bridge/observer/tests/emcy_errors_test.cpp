// EMCY into code, register, manufacturer bytes and text (CiA 301 words, a stepnode's axis
// error bits by name as node/profiles/horner/service.cpp sends them); CAN error frames into the bus
// counters.
#include <gtest/gtest.h>

#include "bridge/observer/bus_error_counter.hpp"
#include "bridge/observer/emcy_decoder.hpp"
#include "test_bus.hpp"

namespace stepnode::bridge::test {
namespace {

struct WithNode : ::testing::Test {
  TestBus bus;
  FakeNode node{{.id = 5, .axes = 3}};
  void SetUp() override {
    bus.add(node);
    bus.boot(node);
    bus.run_ms(50);
    ASSERT_TRUE(bus.observer.node_health(5, bus.now_us).is_stepnode);
    bus.sink.clear();
  }
};

TEST_F(WithNode, AxisErrorNamesTheModulesErrorBits) {
  // Axis 2 latched lower limit + motor stalled; the status word also has power-up (%I8)
  // and position valid (%I9). Layout of node/profiles/horner/service.cpp on_axis_event.
  bus.send(node.emcy(0xFF02, 0x80, {0x12, 0x92, 0x01, 2, 0}));
  ASSERT_EQ(bus.sink.emergencies.size(), 1u);
  const EmergencySample& e = bus.sink.emergencies[0];
  EXPECT_EQ(e.node, 5);
  EXPECT_EQ(e.code, 0xFF02);
  EXPECT_EQ(e.error_register, 0x80);
  EXPECT_EQ(e.manufacturer, (std::array<uint8_t, 5>{0x12, 0x92, 0x01, 2, 0}));
  EXPECT_EQ(e.text,
            "axis 2 error: lower limit, motor stalled (also latched: power-up/watchdog); "
            "error register: manufacturer");
  EXPECT_EQ(e.can_time_ns, bus.now_us * 1000);
  const NodeHealthSample* h = bus.sink.last_health(5);
  ASSERT_NE(h, nullptr) << "an EMCY changes the node's health";
  EXPECT_EQ(h->last_emcy_code, 0xFF02);
  EXPECT_EQ(h->error_register, 0x80);
}

TEST_F(WithNode, CiA301CodesInWords) {
  bus.send(node.emcy(0x8130, 0x11, {}));
  bus.send(node.emcy(0x0000, 0x00, {}));
  ASSERT_EQ(bus.sink.emergencies.size(), 2u);
  EXPECT_EQ(bus.sink.emergencies[0].text,
            "life guard or heartbeat error; error register: generic, communication");
  EXPECT_EQ(bus.sink.emergencies[1].text, "error reset or no error; error register: no error");
}

TEST_F(WithNode, EveryErrorBitHasAName) {
  EXPECT_EQ(axis_error_bits_text(0x01), "emergency stop");
  EXPECT_EQ(axis_error_bits_text(0x02), "lower limit");
  EXPECT_EQ(axis_error_bits_text(0x04), "upper limit");
  EXPECT_EQ(axis_error_bits_text(0x08), "illegal move");
  EXPECT_EQ(axis_error_bits_text(0x10), "motor stalled");
  EXPECT_EQ(axis_error_bits_text(0x80), "power-up/watchdog");
  EXPECT_EQ(axis_error_bits_text(0x00), "");
}

TEST_F(WithNode, MalformedEmcyIsBad) {
  bus.send(od::CanFrame(0x085, {0x10, 0x81, 0x11}));
  EXPECT_TRUE(bus.sink.emergencies.empty());
  EXPECT_EQ(bus.observer.counters().bad_frames, 1u);
  EXPECT_EQ(bus.observer.node_health(5, bus.now_us).bad_frames, 1u);
}

TEST(Emcy, ThirdPartyManufacturerCodeIsNotTakenForAnAxis) {
  EXPECT_EQ(emcy_text(0xFF01, 0x80, {0x01, 0, 0, 1, 0}, false),
            "device specific error; error register: manufacturer");
  EXPECT_EQ(emcy_text(0xFF01, 0x80, {0x01, 0x01, 0, 1, 0}, true),
            "axis 1 error: emergency stop; error register: manufacturer");
}

TEST(Emcy, FromANodeNeverSeenIsStillPublished) {
  TestBus bus;
  bus.send(od::CanFrame(0x0A0, {0x10, 0x81, 0x11, 0, 0, 0, 0, 0}));
  ASSERT_EQ(bus.sink.emergencies.size(), 1u);
  EXPECT_EQ(bus.sink.emergencies[0].node, 0x20);
  EXPECT_EQ(bus.sink.emergencies[0].code, 0x8110);
  EXPECT_TRUE(bus.sink.healths.empty()) << "an EMCY alone does not make a node known";
}

TEST(ErrorFrames, CountedByKind) {
  RecordingSink sink;
  BusObserver obs(sink);
  std::vector<od::CanFrame> out;
  auto error = [&](uint32_t cls, uint8_t ctrl) {
    ObservedFrame f;
    f.error_frame = true;
    f.error_class = cls;
    f.controller_status = ctrl;
    obs.on_frame(f, 0, out);
  };
  error(can_err::kCrtl, can_err::kCrtlRxPassive);
  error(can_err::kCrtl, can_err::kCrtlTxPassive | can_err::kCrtlRxPassive);
  error(can_err::kCrtl, can_err::kCrtlRxOverflow);
  error(can_err::kBusOff, 0);
  error(0x00000008 /* CAN_ERR_PROT */, 0);
  const BusCounters& c = obs.counters();
  EXPECT_EQ(c.frames, 5u);
  EXPECT_EQ(c.error_frames, 5u);
  EXPECT_EQ(c.error_passive, 2u);
  EXPECT_EQ(c.overruns, 1u);
  EXPECT_EQ(c.bus_off, 1u);
  EXPECT_EQ(c.bad_frames, 0u);
  EXPECT_TRUE(out.empty());
}

// Frames the kernel dropped from the bridge's own full socket queue are lost as surely as a
// controller overflow's (found in review: they were read from the socket and never counted).
TEST(ErrorFrames, TheSocketsDroppedFramesCountAsOverruns) {
  RecordingSink sink;
  BusObserver obs(sink);
  EXPECT_EQ(obs.on_socket_overruns(0), 0u);
  EXPECT_EQ(obs.on_socket_overruns(7), 7u);
  EXPECT_EQ(obs.on_socket_overruns(7), 0u);
  EXPECT_EQ(obs.on_socket_overruns(10), 3u);
  EXPECT_EQ(obs.counters().overruns, 10u);
}

}  // namespace
}  // namespace stepnode::bridge::test

namespace stepnode::bridge::test {
namespace {

TEST(Emcy, HpErrorNumbersAndInterruptsInWords) {
  EXPECT_EQ(emcy_text(0xFF59, 0x80, {}, true),
            "HP error 89: accessory busy (a move is in progress); error register: manufacturer");
  EXPECT_EQ(emcy_text(0xFF5E, 0x80, {}, true),
            "HP error 94: cannot move while standby on; error register: manufacturer");
  EXPECT_EQ(emcy_text(0xFF43, 0x80, {}, true),
            "HP interrupt: hard limit; error register: manufacturer");
  EXPECT_EQ(emcy_text(0xFF45, 0x00, {}, true),
            "HP interrupt: HALT switch; error register: no error");
  for (uint8_t n = 89; n <= 94; ++n) EXPECT_NE(hp_error_text(n), nullptr);
  EXPECT_EQ(hp_error_text(88), nullptr);
}

}  // namespace
}  // namespace stepnode::bridge::test
