// LSS slave (CiA 305 V3.0) frame by frame: every request a master sends on 0x7E5 and the
// 8-byte answer on 0x7E4 the standard gives for it, written here from the protocol
// descriptions (command specifier, then the fields little-endian, unused bytes 0), not
// from the implementation. The fast scan runs the master's procedure of CiA 305 over
// several simulated slaves on one bus.
#include <gtest/gtest.h>

#include <initializer_list>
#include <memory>
#include <vector>

#include "node/lss_slave.hpp"

namespace stepnode::node {
namespace {

using od::CanFrame;

// An LSS request: the bytes given, then zeros up to 8.
CanFrame request(std::initializer_list<uint8_t> bytes) {
  CanFrame f(0x7E5, {0, 0, 0, 0, 0, 0, 0, 0});
  size_t i = 0;
  for (uint8_t b : bytes) f.data[i++] = b;
  return f;
}
CanFrame answer(std::initializer_list<uint8_t> bytes) {
  CanFrame f = request(bytes);
  f.id = 0x7E4;
  return f;
}
CanFrame with_u32(uint8_t cs, uint32_t v) {
  return request({cs, static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8),
                  static_cast<uint8_t>(v >> 16), static_cast<uint8_t>(v >> 24)});
}

constexpr lss::Identity kIdentity{0x12345678, 0x53544550, 0x00010002, 0x000000A1};

class LssSlaveTest : public ::testing::Test {
 protected:
  std::optional<CanFrame> send(const CanFrame& f) {
    last = slave.on_frame(f);
    return last.response;
  }
  void to_configuration() { ASSERT_FALSE(send(request({0x04, 0x01}))); }

  struct Stored {
    uint8_t node_id;
    std::optional<uint8_t> bit_timing;
  };
  std::vector<Stored> stored;
  bool store_works = true;
  LssSlave slave{kIdentity, 5, std::nullopt, [this](uint8_t id, std::optional<uint8_t> bt) {
                   stored.push_back({id, bt});
                   return store_works;
                 }};
  LssSlave::Result last;
};

TEST_F(LssSlaveTest, StartsWaitingAndSwitchStateGlobalHasNoAnswer) {
  EXPECT_EQ(slave.state(), lss::State::Waiting);
  EXPECT_FALSE(send(request({0x04, 0x01})));  // mode 1: configuration
  EXPECT_EQ(slave.state(), lss::State::Configuration);
  EXPECT_FALSE(send(request({0x04, 0x00})));  // mode 0: waiting
  EXPECT_EQ(slave.state(), lss::State::Waiting);
  EXPECT_FALSE(send(request({0x04, 0x02})));  // no such mode: ignored
  EXPECT_EQ(slave.state(), lss::State::Waiting);
}

TEST_F(LssSlaveTest, InquireIdentityAndNodeIdInConfiguration) {
  to_configuration();
  EXPECT_EQ(send(request({0x5A})), answer({0x5A, 0x78, 0x56, 0x34, 0x12}));  // vendor-ID
  EXPECT_EQ(send(request({0x5B})), answer({0x5B, 0x50, 0x45, 0x54, 0x53}));  // product code
  EXPECT_EQ(send(request({0x5C})), answer({0x5C, 0x02, 0x00, 0x01, 0x00}));  // revision number
  EXPECT_EQ(send(request({0x5D})), answer({0x5D, 0xA1, 0x00, 0x00, 0x00}));  // serial number
  EXPECT_EQ(send(request({0x5E})), answer({0x5E, 0x05}));                    // active node-ID
}

TEST_F(LssSlaveTest, ConfigurationServicesAreSilentWhileWaiting) {
  for (uint8_t cs : {0x11, 0x13, 0x15, 0x17, 0x5A, 0x5B, 0x5C, 0x5D, 0x5E})
    EXPECT_FALSE(send(request({cs, 0x07}))) << std::hex << int(cs);
  EXPECT_EQ(slave.pending_node_id(), 5);
  EXPECT_TRUE(stored.empty());
}

TEST_F(LssSlaveTest, ConfigureNodeIdAnswersErrorCodeAndChangesOnlyThePendingId) {
  to_configuration();
  EXPECT_EQ(send(request({0x11, 0x07})),
            answer({0x11, 0x00}));  // 0: protocol successfully completed
  EXPECT_EQ(slave.pending_node_id(), 7);
  EXPECT_EQ(slave.active_node_id(), 5);
  EXPECT_EQ(send(request({0x5E})), answer({0x5E, 0x05}));  // still the active one
  for (uint8_t bad : {0x00, 0x80, 0xFE})
    EXPECT_EQ(send(request({0x11, bad})), answer({0x11, 0x01})) << int(bad);  // 1: NID out of range
  EXPECT_EQ(slave.pending_node_id(), 7);
  EXPECT_EQ(send(request({0x11, 0x7F})), answer({0x11, 0x00}));
  EXPECT_EQ(send(request({0x11, 0xFF})), answer({0x11, 0x00}));  // 0xFF: no node-ID
  EXPECT_EQ(slave.pending_node_id(), 0xFF);
  EXPECT_EQ(slave.activate_pending_node_id(), 0xFF);  // NMT reset communication
  EXPECT_EQ(slave.active_node_id(), 0xFF);
}

TEST_F(LssSlaveTest, ConfigureBitTimingFromTheStandardTable) {
  to_configuration();
  // Table selector 0, index: 0 1000, 1 800, 2 500, 3 250, 4 125, 6 50, 7 20, 8 10 kbit/s.
  for (uint8_t index : {0, 1, 2, 3, 4, 6, 7, 8}) {
    EXPECT_EQ(send(request({0x13, 0x00, index})), answer({0x13, 0x00})) << int(index);
    EXPECT_EQ(slave.pending_bit_timing(), index);
  }
  // 5 is reserved, 9 (automatic bit rate detection) not offered, selector 1..255 not ours:
  // 1, bit timing not supported.
  EXPECT_EQ(send(request({0x13, 0x00, 0x05})), answer({0x13, 0x01}));
  EXPECT_EQ(send(request({0x13, 0x00, 0x09})), answer({0x13, 0x01}));
  EXPECT_EQ(send(request({0x13, 0x01, 0x03})), answer({0x13, 0x01}));
  EXPECT_EQ(slave.pending_bit_timing(), 8);
  EXPECT_EQ(lss::bit_rate_kbit(3), 250u);
  EXPECT_EQ(lss::bit_rate_kbit(5), std::nullopt);
}

TEST_F(LssSlaveTest, ActivateBitTimingHasNoAnswerAndCarriesTheSwitchDelay) {
  to_configuration();
  ASSERT_EQ(send(request({0x13, 0x00, 0x02})), answer({0x13, 0x00}));
  EXPECT_FALSE(send(request({0x15, 0xE8, 0x03})));  // switch delay 1000 ms, little-endian
  EXPECT_EQ(last.activate_bit_timing_delay_ms, 1000);
  EXPECT_EQ(slave.active_bit_timing(), 2);
}

TEST_F(LssSlaveTest, StoreConfigurationStoresThePendingValues) {
  to_configuration();
  send(request({0x11, 0x09}));
  send(request({0x13, 0x00, 0x03}));
  EXPECT_EQ(send(request({0x17})), answer({0x17, 0x00}));
  ASSERT_EQ(stored.size(), 1u);
  EXPECT_EQ(stored[0].node_id, 9);
  EXPECT_EQ(stored[0].bit_timing, 3);
  store_works = false;
  EXPECT_EQ(send(request({0x17})), answer({0x17, 0x02}));  // 2: storage media access error
  LssSlave no_store(kIdentity, 5, std::nullopt, nullptr);
  no_store.on_frame(request({0x04, 0x01}));
  EXPECT_EQ(no_store.on_frame(request({0x17})).response, answer({0x17, 0x01}));  // 1: not supported
}

TEST_F(LssSlaveTest, SwitchStateSelectiveNeedsAllFourPartsInOrder) {
  const CanFrame vendor = with_u32(0x40, kIdentity.vendor_id),
                 product = with_u32(0x41, kIdentity.product_code),
                 revision = with_u32(0x42, kIdentity.revision_number),
                 serial = with_u32(0x43, kIdentity.serial_number);
  EXPECT_FALSE(send(vendor));
  EXPECT_FALSE(send(product));
  EXPECT_FALSE(send(revision));
  EXPECT_EQ(send(serial), answer({0x44}));
  EXPECT_EQ(slave.state(), lss::State::Configuration);

  send(request({0x04, 0x00}));
  for (const CanFrame& f : {vendor, revision, serial}) EXPECT_FALSE(send(f));  // product skipped
  EXPECT_EQ(slave.state(), lss::State::Waiting);
  for (const CanFrame& f : {vendor, product, revision, with_u32(0x43, 0xA2)})
    EXPECT_FALSE(send(f));  // another serial
  EXPECT_EQ(slave.state(), lss::State::Waiting);
  // A wrong part ends the sequence: the right ones after it do not complete it.
  for (const CanFrame& f : {vendor, with_u32(0x41, 1), revision, serial}) EXPECT_FALSE(send(f));
  EXPECT_EQ(slave.state(), lss::State::Waiting);
  // A new vendor-ID starts again.
  for (const CanFrame& f : {vendor, product, vendor, product, revision}) EXPECT_FALSE(send(f));
  EXPECT_EQ(send(serial), answer({0x44}));
}

TEST_F(LssSlaveTest, IdentifyRemoteSlaveMatchesRangesInBothStates) {
  auto identify = [&](uint32_t rev_lo, uint32_t rev_hi, uint32_t ser_lo, uint32_t ser_hi) {
    std::optional<CanFrame> r;
    for (const CanFrame& f :
         {with_u32(0x46, kIdentity.vendor_id), with_u32(0x47, kIdentity.product_code),
          with_u32(0x48, rev_lo), with_u32(0x49, rev_hi), with_u32(0x4A, ser_lo)})
      EXPECT_FALSE(send(f));
    return send(with_u32(0x4B, ser_hi));
  };
  EXPECT_EQ(identify(0, 0xFFFFFFFF, 0, 0xFFFFFFFF), answer({0x4F}));
  EXPECT_EQ(identify(0x00010002, 0x00010002, 0xA1, 0xA1), answer({0x4F}));  // bounds inclusive
  EXPECT_FALSE(identify(0, 0x00010001, 0, 0xFFFFFFFF));                     // revision above
  EXPECT_FALSE(identify(0, 0xFFFFFFFF, 0xA2, 0xFFFFFFFF));                  // serial below
  to_configuration();
  EXPECT_EQ(identify(0, 0xFFFFFFFF, 0xA0, 0xA1), answer({0x4F}));
  EXPECT_EQ(slave.state(), lss::State::Configuration);  // identification changes no state
}

TEST(LssSlaveUnconfigured, IdentifyNonConfiguredAndBootOnSwitchToWaiting) {
  LssSlave slave(kIdentity, 0xFF, std::nullopt, nullptr);
  EXPECT_EQ(slave.on_frame(request({0x4C})).response, answer({0x50}));
  EXPECT_EQ(slave.on_frame(request({0x5E})).response, std::nullopt);  // waiting: no inquiry
  slave.on_frame(request({0x04, 0x01}));
  EXPECT_EQ(slave.on_frame(request({0x5E})).response, answer({0x5E, 0xFF}));  // none active
  EXPECT_EQ(slave.on_frame(request({0x11, 0x0C})).response, answer({0x11, 0x00}));
  // Configured now (pending), though not yet active: no longer "non-configured".
  EXPECT_EQ(slave.on_frame(request({0x4C})).response, std::nullopt);
  LssSlave::Result r = slave.on_frame(request({0x04, 0x00}));
  EXPECT_TRUE(r.boot);
  EXPECT_FALSE(r.response);
  EXPECT_EQ(slave.activate_pending_node_id(), 0x0C);
  // A configured device switched back to waiting does not boot again.
  slave.on_frame(request({0x04, 0x01}));
  slave.on_frame(request({0x11, 0x0D}));
  EXPECT_FALSE(slave.on_frame(request({0x04, 0x00})).boot);
}

TEST(LssSlaveFrames, OtherIdentifiersShortFramesAndRemoteFramesAreIgnored) {
  LssSlave slave(kIdentity, 0xFF, std::nullopt, nullptr);
  CanFrame other = request({0x4C});
  other.id = 0x7E4;  // another slave's answer
  EXPECT_FALSE(slave.on_frame(other).response);
  EXPECT_FALSE(slave.on_frame(CanFrame(0x7E5, {0x4C})).response);  // DLC 1
  CanFrame rtr = request({0x4C});
  rtr.rtr = true;
  EXPECT_FALSE(slave.on_frame(rtr).response);
}

// ---------------------------------------------------------------- fast scan

// Several slaves on one bus: a request reaches all; the master sees whether any answered.
struct Bus {
  std::vector<std::unique_ptr<LssSlave>> slaves;
  void add(uint32_t serial, uint8_t node_id = 0xFF) {
    lss::Identity id = kIdentity;
    id.serial_number = serial;
    slaves.push_back(std::make_unique<LssSlave>(id, node_id, std::nullopt, nullptr));
  }
  std::vector<CanFrame> send(const CanFrame& f) {
    std::vector<CanFrame> answers;
    for (auto& s : slaves)
      if (auto r = s->on_frame(f).response) answers.push_back(*r);
    return answers;
  }
};

CanFrame fast_scan(uint32_t id_number, uint8_t bit_checked, uint8_t lss_sub, uint8_t lss_next) {
  CanFrame f = with_u32(0x51, id_number);
  f.data[5] = bit_checked;
  f.data[6] = lss_sub;
  f.data[7] = lss_next;
  return f;
}

// The master's side of CiA 305 fast scan: reset, then for each of the four parts find the
// bits from 31 down (a bit is 0 when someone answers with it 0, else 1), and confirm the
// whole part with LSSNext the next part (after the serial number: back to 0, which puts
// the one slave left in configuration). Returns the identity found, or nullopt.
std::optional<lss::Identity> run_fast_scan(Bus& bus) {
  const CanFrame kAnswer = answer({0x4F});
  std::vector<CanFrame> any = bus.send(fast_scan(0, 0x80, 0, 0));
  if (any.empty()) return std::nullopt;
  for (const CanFrame& a : any) EXPECT_EQ(a, kAnswer);
  uint32_t found[4] = {};
  for (uint8_t sub = 0; sub < 4; ++sub) {
    uint32_t id = 0;
    for (int bit = 31; bit >= 0; --bit) {
      std::vector<CanFrame> r = bus.send(fast_scan(id, static_cast<uint8_t>(bit), sub, sub));
      for (const CanFrame& a : r) EXPECT_EQ(a, kAnswer);
      if (r.empty()) id |= 1u << bit;
    }
    const uint8_t next = sub < 3 ? static_cast<uint8_t>(sub + 1) : 0;
    std::vector<CanFrame> confirmed = bus.send(fast_scan(id, 0, sub, next));
    if (confirmed.empty()) return std::nullopt;
    found[sub] = id;
  }
  return lss::Identity{found[0], found[1], found[2], found[3]};
}

TEST(LssFastScan, FindsEachUnconfiguredSlaveInTurnAndEachGetsItsNodeId) {
  Bus bus;
  bus.add(0x000000A1);
  bus.add(0x000000A2);
  bus.add(0x001000A1);        // differs from the first in one high bit only
  bus.add(0x000000A0, 0x20);  // configured: never takes part
  std::vector<uint32_t> serials;
  for (uint8_t next_id = 1; next_id <= 3; ++next_id) {
    std::optional<lss::Identity> found = run_fast_scan(bus);
    ASSERT_TRUE(found) << "scan " << int(next_id);
    // Exactly the slave with that identity is in configuration; it alone answers.
    std::vector<CanFrame> r = bus.send(request({0x5D}));
    ASSERT_EQ(r.size(), 1u);
    const uint32_t serial = found->serial_number;
    EXPECT_EQ(r[0],
              answer({0x5D, static_cast<uint8_t>(serial), static_cast<uint8_t>(serial >> 8),
                      static_cast<uint8_t>(serial >> 16), static_cast<uint8_t>(serial >> 24)}));
    EXPECT_EQ(found->vendor_id, kIdentity.vendor_id);
    EXPECT_EQ(found->product_code, kIdentity.product_code);
    EXPECT_EQ(found->revision_number, kIdentity.revision_number);
    ASSERT_EQ(bus.send(request({0x11, next_id})), std::vector<CanFrame>{answer({0x11, 0x00})});
    // Back to waiting: that slave boots with its id (the node's job) and leaves the scan.
    bus.send(request({0x04, 0x00}));
    for (auto& s : bus.slaves)
      if (s->identity().serial_number == serial) {
        EXPECT_EQ(s->activate_pending_node_id(), next_id);
      }
    serials.push_back(serial);
  }
  // The lowest identity answers first (a 0 bit is tried first).
  EXPECT_EQ(serials, (std::vector<uint32_t>{0x000000A1, 0x000000A2, 0x001000A1}));
  EXPECT_FALSE(run_fast_scan(bus));  // nobody left
  EXPECT_TRUE(bus.send(request({0x4C})).empty());
}

TEST(LssFastScan, ASlaveAnswersOnlyWhileItsBitsMatchAndItsPositionIsAsked) {
  LssSlave slave(kIdentity, 0xFF, std::nullopt, nullptr);
  EXPECT_EQ(slave.on_frame(fast_scan(0, 0x80, 0, 0)).response, answer({0x4F}));
  // Vendor-ID 0x12345678: bits 31..28 are 0001.
  EXPECT_TRUE(slave.on_frame(fast_scan(0x10000000, 28, 0, 0)).response);
  EXPECT_FALSE(slave.on_frame(fast_scan(0x20000000, 28, 0, 0)).response);
  EXPECT_FALSE(
      slave.on_frame(fast_scan(0x12345678, 0, 1, 1)).response);  // not at the product code yet
  EXPECT_TRUE(slave.on_frame(fast_scan(0x12345678, 0, 0, 1)).response);   // vendor confirmed
  EXPECT_FALSE(slave.on_frame(fast_scan(0x12345678, 0, 0, 1)).response);  // now at position 1
  EXPECT_TRUE(slave.on_frame(fast_scan(kIdentity.product_code, 0, 1, 2)).response);
  EXPECT_TRUE(slave.on_frame(fast_scan(kIdentity.revision_number, 0, 2, 3)).response);
  EXPECT_EQ(slave.state(), lss::State::Waiting);
  EXPECT_TRUE(slave.on_frame(fast_scan(kIdentity.serial_number, 0, 3, 0)).response);
  EXPECT_EQ(slave.state(), lss::State::Configuration);
  // Invalid fields: BitChecked 32..0x7F, LSSSub or LSSNext above 3: no answer.
  LssSlave other(kIdentity, 0xFF, std::nullopt, nullptr);
  EXPECT_FALSE(other.on_frame(fast_scan(0, 32, 0, 0)).response);
  EXPECT_FALSE(other.on_frame(fast_scan(0, 31, 4, 0)).response);
  EXPECT_FALSE(other.on_frame(fast_scan(0, 31, 0, 4)).response);
}

TEST(LssBackToBack, EveryRequestIsAnsweredByItsOwnCall) {
  LssSlave slave(kIdentity, 5, std::nullopt, nullptr);
  slave.on_frame(request({0x04, 0x01}));
  std::vector<CanFrame> answers;
  for (uint8_t cs : {0x5A, 0x5B, 0x5C, 0x5D, 0x5E, 0x5E, 0x5A})
    answers.push_back(*slave.on_frame(request({cs})).response);
  ASSERT_EQ(answers.size(), 7u);
  EXPECT_EQ(answers[0], answer({0x5A, 0x78, 0x56, 0x34, 0x12}));
  EXPECT_EQ(answers[3], answer({0x5D, 0xA1}));
  EXPECT_EQ(answers[5], answer({0x5E, 0x05}));
  EXPECT_EQ(answers[6], answers[0]);
}

}  // namespace
}  // namespace stepnode::node
