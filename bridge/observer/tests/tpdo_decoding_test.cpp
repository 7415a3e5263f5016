// TPDOs decoded by the mapping the node has: values land on the right axis, AxisStatus only
// on change, AxisPosition per TPDO with a position/velocity/phase, short TPDOs refused,
// the SYNC counter carried, HP DONE?/error number, and the unpacking equal to od's.
#include <gtest/gtest.h>

#include <random>

#include "bridge/observer/tpdo_decoder.hpp"
#include "test_bus.hpp"

namespace stepnode::bridge::test {
namespace {

// Gives TPDO k (0-based) a COB-ID, as a configuration tool would have before the bridge
// started (the stepnode default leaves TPDOs 5.. without one).
void enable_tpdo(FakeNode& node, unsigned k, uint32_t cob) {
  node.dictionary().put<uint32_t>(static_cast<uint16_t>(0x1800 + k), 1, 0x40000000u | cob);
}
void set_mapping(FakeNode& node, unsigned k, std::vector<uint32_t> words) {
  const auto map = static_cast<uint16_t>(0x1A00 + k);
  uint8_t i = 0;
  for (uint32_t w : words) node.dictionary().put<uint32_t>(map, ++i, w);
  node.dictionary().put<uint8_t>(map, 0, i);
}

struct Discovered : ::testing::Test {
  TestBus bus;
  FakeNode node{{.id = 5, .axes = 3}};
  void SetUp() override {
    enable_tpdo(node, 4, 0x1A5);  // axis 2: status + motor position
    enable_tpdo(node, 6, 0x3A5);  // axis 2: velocity + phase
    bus.add(node);
    bus.boot(node);
    bus.run_ms(80);
    ASSERT_TRUE(bus.observer.node_health(5, bus.now_us).discovered);
    bus.sink.clear();
  }
};

TEST_F(Discovered, ValuesLandOnTheAxisTheObjectIndexNames) {
  node.set_status(1, 0x8100);  // axis 2: moving, position valid
  node.set_position(1, -4000, 7);
  node.set_velocity(1, -1500, 2);
  node.set_status(0, 0x0080);
  bus.send(node.tpdo(4));
  bus.send(node.tpdo(6));
  ASSERT_EQ(bus.sink.statuses.size(), 1u);
  EXPECT_EQ(bus.sink.statuses[0].axis, 2);
  EXPECT_EQ(bus.sink.statuses[0].status_bits, 0x8100);
  // DONE? is not in a TPDO here: what discovery's snapshot read stays (unknown when the
  // node has no such object).
  const od::Entry* done = node.dictionary().find(0x2118, 0);
  EXPECT_EQ(bus.sink.statuses[0].done_code,
            done ? static_cast<int8_t>(done->value[0]) : kDoneUnknown);
  ASSERT_EQ(bus.sink.positions.size(), 2u);
  EXPECT_EQ(bus.sink.positions[0].axis, 2);
  EXPECT_EQ(bus.sink.positions[0].motor_position, -4000);
  EXPECT_EQ(bus.sink.positions[1].velocity, -1500);
  EXPECT_EQ(bus.sink.positions[1].motion_phase, 2);
  EXPECT_EQ(bus.sink.positions[1].motor_position, -4000) << "last known value carried";
  EXPECT_EQ(bus.sink.positions[1].can_time_ns, bus.now_us * 1000);
  EXPECT_EQ(bus.observer.node_health(5, bus.now_us).frames > 0, true);
}

TEST_F(Discovered, StatusIsPublishedOnlyWhenItChanges) {
  node.set_status(0, 0x0180);
  for (int i = 0; i < 5; ++i) {
    node.set_position(0, i * 10, 0);
    bus.send(node.tpdo(0));  // status + motor position
  }
  EXPECT_EQ(bus.sink.statuses.size(), 1u);
  EXPECT_EQ(bus.sink.positions.size(), 5u) << "positions on every TPDO";
  node.set_status(0, 0x8180);
  bus.send(node.tpdo(0));
  bus.send(node.tpdo(0));
  ASSERT_EQ(bus.sink.statuses.size(), 2u);
  EXPECT_EQ(bus.sink.statuses[1].status_bits, 0x8180);
  node.set_status(0, 0x0180);
  bus.send(node.tpdo(0));
  EXPECT_EQ(bus.sink.statuses.size(), 3u);
}

TEST_F(Discovered, TpdoWithoutPositionFieldsPublishesNoPosition) {
  set_mapping(node, 3, {0x20010010});  // status bits only (written behind the bridge's back)
  // The bridge read TPDO4 as empty; it publishes nothing for it.
  bus.send(node.tpdo(3));
  EXPECT_TRUE(bus.sink.positions.empty());
  EXPECT_TRUE(bus.sink.statuses.empty());
}

TEST_F(Discovered, ShortTpdoIsCountedBadAndNotApplied) {
  node.set_status(0, 0x0100);
  node.set_position(0, 77, 0);
  od::CanFrame f = node.tpdo(0);
  ASSERT_EQ(f.dlc, 6);
  f.dlc = 5;
  const uint64_t bad_before = bus.observer.counters().bad_frames;
  bus.send(f);
  EXPECT_TRUE(bus.sink.statuses.empty());
  EXPECT_TRUE(bus.sink.positions.empty());
  EXPECT_EQ(bus.observer.counters().bad_frames, bad_before + 1);
  EXPECT_EQ(bus.observer.node_health(5, bus.now_us).bad_frames, 1u);
  // A longer frame is fine (extra bytes ignored).
  f = node.tpdo(0);
  f.dlc = 8;
  bus.send(f);
  EXPECT_EQ(bus.sink.positions.size(), 1u);
}

TEST_F(Discovered, SyncCounterIsCarried) {
  node.set_position(0, 1, 2);
  bus.send(node.tpdo(1));
  EXPECT_EQ(bus.sink.positions.back().sync_counter, 0) << "no SYNC seen yet";
  bus.send(od::CanFrame(0x080, {17}));
  bus.send(node.tpdo(1));
  EXPECT_EQ(bus.sink.positions.back().sync_counter, 17);
  bus.send(od::CanFrame(0x080, {}));  // SYNC without counter
  bus.send(node.tpdo(1));
  EXPECT_EQ(bus.sink.positions.back().sync_counter, 0);
  const uint64_t bad = bus.observer.counters().bad_frames;
  bus.send(od::CanFrame(0x080, {1, 2}));
  EXPECT_EQ(bus.observer.counters().bad_frames, bad + 1);
}

TEST(TpdoDecoding, HpDoneCodeAndErrorNumberAreStatus) {
  TestBus bus;
  FakeNode node({.id = 5, .axes = 1, .hp_objects = true});
  node.dictionary().put<uint32_t>(0x1803, 1, 0xC0000485);  // TPDO4 invalid while mapping
  set_mapping(node, 3, {0x20180008, 0x20190008, 0x20010010});
  node.dictionary().put<uint32_t>(0x1803, 1, 0x40000485);
  bus.add(node);
  bus.boot(node);
  bus.run_ms(80);
  bus.sink.clear();
  node.dictionary().put<int8_t>(0x2018, 0, -2);
  node.dictionary().put<uint8_t>(0x2019, 0, 91);
  bus.send(node.tpdo(3));
  ASSERT_EQ(bus.sink.statuses.size(), 1u);
  EXPECT_EQ(bus.sink.statuses[0].done_code, -2);
  EXPECT_EQ(bus.sink.statuses[0].hp_error, 91);
  bus.send(node.tpdo(3));
  EXPECT_EQ(bus.sink.statuses.size(), 1u);
  node.dictionary().put<int8_t>(0x2018, 0, 1);
  bus.send(node.tpdo(3));
  ASSERT_EQ(bus.sink.statuses.size(), 2u);
  EXPECT_EQ(bus.sink.statuses[1].done_code, 1);
}

TEST(TpdoDecoding, TpdoOfAnUndiscoveredNodeIsUndecodedNotBad) {
  TestBus bus;
  FakeNode node({.id = 5, .axes = 1});
  bus.send(node.tpdo(0));  // no heartbeat ever: nothing known
  EXPECT_EQ(bus.observer.counters().undecoded, 1u);
  EXPECT_EQ(bus.observer.counters().bad_frames, 0u);
  EXPECT_TRUE(bus.sink.positions.empty());
}

// The compiled shifts must give what od's bit-exact unpacking gives, for any mapping.
TEST(TpdoDecoding, UnpackingMatchesOdReadBitsForRandomMappings) {
  std::mt19937 rng(12345);
  for (int round = 0; round < 300; ++round) {
    RecordingSink sink;
    TpdoDecoder decoder(sink);
    NodeInfo info;
    info.axes = 8;
    TpdoInfo t{0, 0x181, {}};
    // Random layout of dummies (8/16 bits) and axis fields within 64 bits.
    const uint16_t offsets[] = {0x01, 0x05, 0x06, 0x07, 0x08, 0x18, 0x19};
    const uint8_t widths[] = {16, 32, 32, 32, 8, 8, 8};
    unsigned bits = 0;
    while (true) {
      if (rng() % 3 == 0) {
        const uint8_t w = (rng() % 2) ? 8 : 16;
        if (bits + w > 64 || t.mapping.size() == 8) break;
        t.mapping.push_back({0x0005, 0, w});
        bits += w;
        continue;
      }
      const unsigned f = rng() % 7;
      if (bits + widths[f] > 64 || t.mapping.size() == 8) break;
      t.mapping.push_back(
          {static_cast<uint16_t>(0x2000 + 0x100 * (rng() % 8) + offsets[f]), 0, widths[f]});
      bits += widths[f];
    }
    info.tpdos.push_back(t);
    decoder.install(1, info);
    ObservedFrame of;
    of.frame.id = 0x181;
    of.frame.dlc = 8;
    for (auto& b : of.frame.data) b = static_cast<uint8_t>(rng());
    uint8_t node = 0;
    ASSERT_EQ(decoder.on_frame(of, node), TpdoDecoder::Result::Decoded);
    // Expected: the last value of each field per axis, by od::read_bits.
    size_t offset = 0;
    std::map<std::pair<unsigned, uint16_t>, uint64_t> expected;
    for (const od::MappedEntry& e : t.mapping) {
      if (!e.dummy())
        expected[{(e.index - 0x2000u) >> 8, static_cast<uint16_t>(e.index & 0xFF)}] =
            od::read_bits(of.frame.payload(), offset, e.bits);
      offset += e.bits;
    }
    for (const auto& [key, v] : expected) {
      const uint8_t axis = static_cast<uint8_t>(key.first + 1);
      const AxisPositionSample* p = nullptr;
      for (const auto& s : sink.positions)
        if (s.axis == axis) p = &s;
      const AxisStatusSample* st = nullptr;
      for (const auto& s : sink.statuses)
        if (s.axis == axis) st = &s;
      switch (key.second) {
        case 0x01:
          ASSERT_TRUE(st);
          EXPECT_EQ(st->status_bits, static_cast<uint16_t>(v));
          break;
        case 0x05:
          ASSERT_TRUE(p);
          EXPECT_EQ(p->motor_position, static_cast<int32_t>(v));
          break;
        case 0x06:
          ASSERT_TRUE(p);
          EXPECT_EQ(p->encoder_position, static_cast<int32_t>(v));
          break;
        case 0x07:
          ASSERT_TRUE(p);
          EXPECT_EQ(p->velocity, static_cast<int32_t>(v));
          break;
        case 0x08:
          ASSERT_TRUE(p);
          EXPECT_EQ(p->motion_phase, static_cast<uint8_t>(v));
          break;
        case 0x18:
          if (static_cast<int8_t>(v) != kDoneUnknown) {
            ASSERT_TRUE(st);
            EXPECT_EQ(st->done_code, static_cast<int8_t>(v));
          }
          break;
        case 0x19:
          if (v != 0) {
            ASSERT_TRUE(st);
            EXPECT_EQ(st->hp_error, static_cast<uint8_t>(v));
          }
          break;
      }
    }
  }
}

}  // namespace
}  // namespace stepnode::bridge::test
