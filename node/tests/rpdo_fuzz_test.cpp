// Fuzz of the receive paths: 200,000 random frames (fixed seed) at an operational node
// with RPDOs and TPDOs mapped and the heartbeat consumer on, ids biased to what this node
// listens to (NMT, SYNC, its SDO server, its RPDOs, heartbeats), random DLC and bytes, SDO
// requests biased to real command specifiers and objects, and virtual time running. The
// node must not crash (the sanitizer build runs this too), must stay in a valid state, and
// everything it sends must be well-formed for its kind.
#include <random>
#include <set>

#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

class RpdoFuzzTest : public NodeHarness {
 protected:
  std::mt19937_64 rng{0x5EED'CAFE'2026ull};
  uint64_t pick(uint64_t n) { return rng() % n; }
  bool chance(unsigned percent) { return pick(100) < percent; }

  CanFrame random_frame() {
    static const uint32_t kIds[] = {0x000, 0x080, 0x605, 0x605, 0x605, 0x205, 0x205, 0x305,
                                    0x405, 0x505, 0x720, 0x721, 0x705, 0x185, 0x585, 0x085};
    CanFrame f;
    f.id = chance(80) ? kIds[pick(std::size(kIds))] : static_cast<uint32_t>(pick(0x800));
    f.dlc = static_cast<uint8_t>(chance(60) ? 8 : pick(9));
    for (auto& b : f.data) b = static_cast<uint8_t>(rng());
    f.rtr = chance(2);
    // Data frames on 0x705, 0x585 and 0x085 are another device with this node-ID, which the
    // node yields to (node_id_conflict_test.cpp); as remote frames they still reach the paths.
    if (f.id == 0x705 || f.id == 0x585 || f.id == 0x085) f.rtr = true;
    if (f.id == 0x000) {
      // Mostly well-formed NMT commands, to this node, to all, or to others.
      static const uint8_t kCs[] = {0x01, 0x01, 0x01, 0x02, 0x80, 0x81, 0x82};
      if (chance(80)) {
        f.dlc = 2;
        f.data[0] = kCs[pick(std::size(kCs))];
        f.data[1] = chance(70) ? kId : chance(50) ? 0 : static_cast<uint8_t>(rng());
      }
    } else if (f.id == 0x605 && chance(70)) {
      // Plausible SDO requests at real objects.
      static const uint8_t kCmd[] = {0x20, 0x21, 0x22, 0x23, 0x27, 0x2B, 0x2F, 0x40,
                                     0x60, 0x70, 0x00, 0x10, 0x01, 0x11, 0xC0, 0xC2,
                                     0xC1, 0xA0, 0xA3, 0xA2, 0xA1, 0x80, 0x41};
      static const uint16_t kIdx[] = {0x1000, 0x1001, 0x1003, 0x1005, 0x1006, 0x1008, 0x1010,
                                      0x1011, 0x1014, 0x1015, 0x1016, 0x1017, 0x1018, 0x1019,
                                      0x1021, 0x1200, 0x1400, 0x1401, 0x1402, 0x1600, 0x1601,
                                      0x1602, 0x1800, 0x1801, 0x1A00, 0x1A01, 0x2F00, 0x2F01,
                                      0x2000, 0x2001, 0x2002, 0x2003, 0x5000, 0x6000};
      f.data[0] = kCmd[pick(std::size(kCmd))];
      uint16_t idx = kIdx[pick(std::size(kIdx))];
      f.data[1] = static_cast<uint8_t>(idx);
      f.data[2] = static_cast<uint8_t>(idx >> 8);
      f.data[3] = static_cast<uint8_t>(pick(10));
    } else if (f.id == 0x080 && chance(80)) {
      f.dlc = 0;  // mostly proper SYNCs
    }
    return f;
  }

  std::set<uint32_t> valid_tpdo_ids() {
    std::set<uint32_t> ids;
    for (unsigned n = 0; n < 4; ++n) {
      uint32_t c = od().get<uint32_t>(static_cast<uint16_t>(0x1800 + n), 1);
      if (!(c & 0x80000000u)) ids.insert(c & 0x7FF);
    }
    return ids;
  }
};

bool valid_state(NmtState s) {
  return s == NmtState::PreOperational || s == NmtState::Operational || s == NmtState::Stopped;
}

TEST_F(RpdoFuzzTest, RandomFramesNeitherCrashNorCorrupt) {
  // The set-up a master would make, stored so that a random NMT reset node keeps it.
  map_rpdo(0, {0x2F000120, 0x2F000220}, 255);
  map_rpdo(1, {0x2F000320}, 1, 50);            // synchronous, deadline 50 ms
  map_rpdo(2, {0x00050008, 0x2F000420}, 255);  // dummy (UNSIGNED8) + register
  map_rpdo(3, {0x00070020, 0x2F000520}, 254);  // dummy (UNSIGNED32) + register
  map_tpdo(0, {0x2F000120}, 254, 10);
  map_tpdo(1, {0x2F000220, 0x10010008}, 1);
  map_tpdo(2, {0x2F000320}, 255, 0, 20);
  ASSERT_EQ(sdo_write(0x1016, 1, (0x20u << 16) | 100), 0u);
  ASSERT_EQ(sdo_write(0x1010, 1, 0x65766173), 0u);
  nmt(0x01);
  ASSERT_EQ(node->state(), NmtState::Operational);

  size_t checked = 0, operational_frames = 0, sdo_answers = 0, rpdo_frames = 0;
  for (int i = 0; i < 200'000; ++i) {
    CanFrame f = random_frame();
    NmtState before = node->state();
    bool is_nmt = f.id == 0 && !f.rtr && f.dlc == 2;
    clear_sent();
    t += pick(700);
    frame(f);
    if (chance(5)) {
      t += 1000;
      node->on_tick(t);
    }
    NmtState after = node->state();
    ASSERT_TRUE(valid_state(after)) << "frame " << i;
    operational_frames += after == NmtState::Operational;
    rpdo_frames += f.id == 0x205 && after == NmtState::Operational;

    uint32_t emcy_id = od().get<uint32_t>(0x1014, 0) & 0x7FF;
    uint32_t sync_id = od().get<uint32_t>(0x1005, 0) & 0x7FF;
    std::set<uint32_t> tpdos = valid_tpdo_ids();
    for (const CanFrame& out : sent) {
      ++checked;
      ASSERT_LE(out.dlc, 8) << "frame " << i;
      ASSERT_LE(out.id, 0x7FFu) << "frame " << i;
      ASSERT_FALSE(out.rtr);
      if (out.id == kSdoTx) {
        ++sdo_answers;
        ASSERT_EQ(out.dlc, 8) << "SDO response, frame " << i;
        ASSERT_NE(before, NmtState::Stopped) << "SDO answered in stopped, frame " << i;
      } else if (out.id == kHeartbeatId) {
        ASSERT_EQ(out.dlc, 1);
        ASSERT_TRUE(out.data[0] == 0x00 || out.data[0] == 0x04 || out.data[0] == 0x05 ||
                    out.data[0] == 0x7F)
            << int(out.data[0]);
      } else {
        // Anything else is not sent from stopped (unless an NMT command left it).
        if (!is_nmt) {
          ASSERT_NE(before, NmtState::Stopped) << std::hex << out.id << " frame " << i;
        }
        if (out.id == emcy_id) {
          ASSERT_EQ(out.dlc, 8) << "EMCY, frame " << i;
        } else if (out.id == sync_id) {
          ASSERT_LE(out.dlc, 1) << "SYNC, frame " << i;
        } else if (tpdos.count(out.id) && !is_nmt) {
          ASSERT_EQ(before, NmtState::Operational) << "PDO outside operational, frame " << i;
        }
      }
    }
    // Keep the node mostly operational, as a master would.
    if (after != NmtState::Operational && chance(20)) nmt(0x01);
  }
  // The run exercised what it claims to.
  EXPECT_GT(operational_frames, 100'000u);
  EXPECT_GT(rpdo_frames, 10'000u);
  EXPECT_GT(sdo_answers, 20'000u);
  EXPECT_GT(checked, 50'000u);

  // Afterwards a reset node brings the stored set-up back and the node works normally.
  nmt(0x81);
  ASSERT_EQ(node->state(), NmtState::PreOperational);
  ASSERT_EQ(sdo_write(0x2F00, 1, 0), 0u);
  EXPECT_EQ(sdo_read(0x1000, 0), 0u);
  nmt(0x01);
  frame(CanFrame(0x205, {1, 0, 0, 0, 2, 0, 0, 0}));
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 1), 1u);
  EXPECT_EQ(od().get<uint32_t>(0x2F00, 2), 2u);
}

}  // namespace
}  // namespace stepnode::node::test
