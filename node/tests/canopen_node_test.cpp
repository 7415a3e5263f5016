// The CiA 301 slave in virtual time: NMT (every transition), boot-up, heartbeat, EMCY,
// SDO in each state, PDOs (SYNC, change, RPDO, length errors), store/restore, and a
// fuzz of the receive paths.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "node/canopen_node.hpp"
#include "node/config.hpp"
#include "node/tests/recording_application.hpp"

namespace stepnode::node {
namespace {

using od::CanFrame;

class NodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = std::filesystem::temp_directory_path() /
          ("stepnode-test-" + std::to_string(::getpid()) + "-" +
           ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir);
    make();
  }
  void TearDown() override { std::filesystem::remove_all(dir); }
  void make() {
    NodeOptions o;
    o.device.node_id = 5;
    o.state_dir = dir;
    node = std::make_unique<CanopenNode>(o, [this](const CanFrame& f) { sent.push_back(f); });
    // The stepnode's object tables with nothing behind them: the slave's rules alone.
    add_profile_objects(node->dictionary(), o.layout);
    node->start(t);
  }
  void nmt(uint8_t cs, uint8_t id = 5) { frame(CanFrame(0, {cs, id})); }
  void frame(const CanFrame& f) { node->on_frame(f, t); }
  void tick_ms(int ms) {
    for (int i = 0; i < ms; ++i) {
      t += 1000;
      node->on_tick(t);
    }
  }
  // Expedited SDO download; returns the response command byte (0x60 ok, 0x80 abort).
  uint32_t sdo_write(uint16_t index, uint8_t sub, uint32_t value, uint8_t size) {
    sent.clear();
    uint8_t cs = static_cast<uint8_t>(0x23 | ((4 - size) << 2));
    frame(CanFrame(0x605, {cs, static_cast<uint8_t>(index), static_cast<uint8_t>(index >> 8), sub,
                           static_cast<uint8_t>(value), static_cast<uint8_t>(value >> 8),
                           static_cast<uint8_t>(value >> 16), static_cast<uint8_t>(value >> 24)}));
    for (const auto& f : sent)
      if (f.id == 0x585) return f.data[0] == 0x80 ? od::get_u32(&f.data[4]) : 0;
    return 0xFFFFFFFF;  // no answer
  }
  std::vector<CanFrame> with_id(uint32_t id) const {
    std::vector<CanFrame> out;
    for (const auto& f : sent)
      if (f.id == id) out.push_back(f);
    return out;
  }
  void map_tpdo1(std::initializer_list<uint32_t> words, uint8_t type) {
    ASSERT_EQ(sdo_write(0x1800, 1, 0xC0000185, 4), 0u);
    ASSERT_EQ(sdo_write(0x1A00, 0, 0, 1), 0u);
    uint8_t n = 0;
    for (uint32_t w : words) ASSERT_EQ(sdo_write(0x1A00, ++n, w, 4), 0u);
    ASSERT_EQ(sdo_write(0x1A00, 0, n, 1), 0u);
    ASSERT_EQ(sdo_write(0x1800, 2, type, 1), 0u);
    ASSERT_EQ(sdo_write(0x1800, 1, 0x40000185, 4), 0u);
  }

  std::filesystem::path dir;
  uint64_t t = 1'000'000;
  std::vector<CanFrame> sent;
  std::unique_ptr<CanopenNode> node;
};

TEST_F(NodeTest, BootUpThenPreOperationalWithoutErrorsOnAFirstStart) {
  ASSERT_GE(sent.size(), 1u);
  EXPECT_EQ(sent[0], CanFrame(0x705, {0x00}));  // CiA 301 7.2.8.3.2.1
  EXPECT_EQ(node->state(), NmtState::PreOperational);
  EXPECT_EQ(node->dictionary().get<uint8_t>(0x1001, 0), 0);
  EXPECT_TRUE(with_id(0x85).empty());  // no EMCY
}

// Every NMT transition of CiA 301 figure 48, each confirmed by a heartbeat at once.
TEST_F(NodeTest, EveryNmtTransitionIsConfirmedByAHeartbeat) {
  struct Step {
    uint8_t cs;
    NmtState expect;
  };
  const Step steps[] = {{0x01, NmtState::Operational},    {0x80, NmtState::PreOperational},
                        {0x02, NmtState::Stopped},        {0x01, NmtState::Operational},
                        {0x02, NmtState::Stopped},        {0x80, NmtState::PreOperational},
                        {0x81, NmtState::PreOperational}, {0x01, NmtState::Operational},
                        {0x82, NmtState::PreOperational}, {0x02, NmtState::Stopped},
                        {0x82, NmtState::PreOperational}, {0x02, NmtState::Stopped},
                        {0x81, NmtState::PreOperational}};
  for (const Step& s : steps) {
    sent.clear();
    nmt(s.cs);
    EXPECT_EQ(node->state(), s.expect) << "command 0x" << std::hex << int(s.cs);
    auto hb = with_id(0x705);
    ASSERT_FALSE(hb.empty());
    if (s.cs == 0x81 || s.cs == 0x82) {
      EXPECT_EQ(hb.front().data[0], 0x00);  // boot-up first
    }
    EXPECT_EQ(hb.back().data[0], static_cast<uint8_t>(s.expect));
    tick_ms(5);
  }
  // Broadcast (node 0) applies; another node's id and malformed frames do not.
  nmt(0x01, 0);
  EXPECT_EQ(node->state(), NmtState::Operational);
  nmt(0x02, 6);
  EXPECT_EQ(node->state(), NmtState::Operational);
  frame(CanFrame(0, {0x02}));
  frame(CanFrame(0, {0x02, 5, 0}));
  frame(CanFrame(0, {0x77, 5}));
  EXPECT_EQ(node->state(), NmtState::Operational);
}

TEST_F(NodeTest, StoppedAnswersNoSdoAndSendsNoPdo) {
  nmt(0x02);
  EXPECT_EQ(sdo_write(0x1017, 0, 100, 2), 0xFFFFFFFFu);
  sent.clear();
  frame(CanFrame(0x80, {}));
  tick_ms(10);
  for (const auto& f : sent) EXPECT_TRUE(f.id == 0x705) << std::hex << f.id;
}

TEST_F(NodeTest, HeartbeatProducerPeriodAndChange) {
  sent.clear();
  tick_ms(3000);
  EXPECT_EQ(with_id(0x705).size(), 3u);  // default 1000 ms
  ASSERT_EQ(sdo_write(0x1017, 0, 100, 2), 0u);
  sent.clear();
  tick_ms(1000);
  EXPECT_NEAR(static_cast<double>(with_id(0x705).size()), 10.0, 1.0);
  ASSERT_EQ(sdo_write(0x1017, 0, 0, 2), 0u);
  sent.clear();
  tick_ms(2000);
  EXPECT_TRUE(with_id(0x705).empty());
}

TEST_F(NodeTest, HeartbeatConsumerTimeoutRaisesEmcyAndRecovers) {
  test::RecordingApplication app;
  node->set_application(&app);
  auto lost = [&] { return app.lost == std::vector<uint8_t>{0x20}; };
  ASSERT_EQ(sdo_write(0x1016, 1, (0x20u << 16) | 300, 4), 0u);
  tick_ms(1000);
  EXPECT_FALSE(lost());  // monitoring starts with the first heartbeat
  frame(CanFrame(0x720, {0x05}));
  sent.clear();
  tick_ms(400);
  EXPECT_TRUE(lost());
  auto emcy = with_id(0x85);
  ASSERT_EQ(emcy.size(), 1u);
  EXPECT_EQ(od::get_u16(emcy[0].data.data()), 0x8130);
  EXPECT_EQ(emcy[0].data[2], 0x11);  // generic + communication
  EXPECT_EQ(node->dictionary().get<uint32_t>(0x1003, 1) & 0xFFFF, 0x8130u);
  sent.clear();
  frame(CanFrame(0x720, {0x05}));
  emcy = with_id(0x85);
  ASSERT_EQ(emcy.size(), 1u);
  EXPECT_EQ(od::get_u16(emcy[0].data.data()), 0x0000);  // error reset
  EXPECT_EQ(node->dictionary().get<uint8_t>(0x1001, 0), 0);
}

TEST_F(NodeTest, EmcyInhibitTimeDelaysTheNextMessage) {
  ASSERT_EQ(sdo_write(0x1015, 0, 500, 2), 0u);  // 50 ms
  sent.clear();
  node->emcy().report(0x1000, 0x01, {}, t);
  node->emcy().report(0x1001, 0x01, {}, t);
  EXPECT_EQ(with_id(0x85).size(), 1u);
  tick_ms(49);
  EXPECT_EQ(with_id(0x85).size(), 1u);
  tick_ms(2);
  EXPECT_EQ(with_id(0x85).size(), 2u);
}

TEST_F(NodeTest, TpdoOnSyncAndOnChange) {
  map_tpdo1({0x2F000120, 0x10010008}, 1);
  nmt(0x01);
  ASSERT_EQ(sdo_write(0x2F00, 1, 0xC0FFEE42, 4), 0u);
  sent.clear();
  tick_ms(20);
  EXPECT_TRUE(with_id(0x185).empty());  // synchronous: only on SYNC
  frame(CanFrame(0x80, {}));
  auto tpdo = with_id(0x185);
  ASSERT_EQ(tpdo.size(), 1u);
  EXPECT_EQ(tpdo[0], CanFrame(0x185, {0x42, 0xEE, 0xFF, 0xC0, 0x00}));
  // Type 2: every second SYNC.
  nmt(0x80);
  map_tpdo1({0x2F000120}, 2);
  nmt(0x01);
  sent.clear();
  for (int i = 0; i < 6; ++i) frame(CanFrame(0x80, {}));
  EXPECT_EQ(with_id(0x185).size(), 3u);
  // Type 254: on change, at once.
  nmt(0x80);
  map_tpdo1({0x2F000120}, 254);
  nmt(0x01);
  sent.clear();
  ASSERT_EQ(sdo_write(0x2F00, 1, 7, 4), 0u);
  tpdo = with_id(0x185);
  ASSERT_FALSE(tpdo.empty());
  EXPECT_EQ(tpdo.back(), CanFrame(0x185, {7, 0, 0, 0}));
  sent.clear();
  tick_ms(50);
  EXPECT_TRUE(with_id(0x185).empty());  // no change, no event timer
}

TEST_F(NodeTest, RpdoAppliedAndShortRpdoRefusedWithEmcy) {
  ASSERT_EQ(sdo_write(0x1400, 1, 0x80000205, 4), 0u);
  ASSERT_EQ(sdo_write(0x1600, 0, 0, 1), 0u);
  ASSERT_EQ(sdo_write(0x1600, 1, 0x2F000220, 4), 0u);
  ASSERT_EQ(sdo_write(0x1600, 0, 1, 1), 0u);
  ASSERT_EQ(sdo_write(0x1400, 1, 0x00000205, 4), 0u);
  frame(CanFrame(0x205, {1, 2, 3, 4}));
  EXPECT_EQ(node->dictionary().get<uint32_t>(0x2F00, 2), 0u);  // pre-operational: no PDOs
  nmt(0x01);
  frame(CanFrame(0x205, {1, 2, 3, 4}));
  EXPECT_EQ(node->dictionary().get<uint32_t>(0x2F00, 2), 0x04030201u);
  sent.clear();
  frame(CanFrame(0x205, {9, 9}));
  EXPECT_EQ(node->dictionary().get<uint32_t>(0x2F00, 2), 0x04030201u);  // not applied
  auto emcy = with_id(0x85);
  ASSERT_FALSE(emcy.empty());
  EXPECT_EQ(od::get_u16(emcy[0].data.data()), 0x8210);
}

TEST_F(NodeTest, StoreRestoreAcrossRestartAndResetNode) {
  ASSERT_EQ(sdo_write(0x1017, 0, 333, 2), 0u);
  ASSERT_EQ(sdo_write(0x2F00, 1, 0xDEADBEEF, 4), 0u);
  ASSERT_EQ(sdo_write(0x1010, 1, 0x65766173, 4), 0u);  // "save"
  EXPECT_EQ(sdo_write(0x1010, 1, 0x12345678, 4), 0x08000020u);
  EXPECT_TRUE(std::filesystem::exists(node->parameter_file()));
  ASSERT_EQ(sdo_write(0x1017, 0, 444, 2), 0u);
  nmt(0x82);  // reset communication: communication parameters back to stored
  EXPECT_EQ(node->dictionary().get<uint16_t>(0x1017, 0), 333);
  ASSERT_EQ(sdo_write(0x2F00, 1, 1, 4), 0u);
  nmt(0x82);  // ...but not the application's
  EXPECT_EQ(node->dictionary().get<uint32_t>(0x2F00, 1), 1u);
  nmt(0x81);  // reset node: everything back to stored
  EXPECT_EQ(node->dictionary().get<uint32_t>(0x2F00, 1), 0xDEADBEEFu);
  make();  // a new process with the same state directory
  EXPECT_EQ(node->dictionary().get<uint16_t>(0x1017, 0), 333);
  EXPECT_EQ(node->dictionary().get<uint32_t>(0x2F00, 1), 0xDEADBEEFu);
  ASSERT_EQ(sdo_write(0x1011, 1, 0x64616F6C, 4), 0u);  // "load": defaults after a reset
  EXPECT_EQ(node->dictionary().get<uint16_t>(0x1017, 0), 333);
  nmt(0x81);
  EXPECT_EQ(node->dictionary().get<uint16_t>(0x1017, 0), 1000);
  EXPECT_EQ(node->dictionary().get<uint32_t>(0x2F00, 1), 0u);
}

TEST_F(NodeTest, LinesAppendedToTheStoredFileMakeItDamagedAndTheNodeStartsOnDefaults) {
  ASSERT_EQ(sdo_write(0x1017, 0, 250, 2), 0u);
  ASSERT_EQ(sdo_write(0x1010, 1, 0x65766173, 4), 0u);
  {
    std::ofstream f(node->parameter_file(), std::ios::app);
    f << "garbage line\n1017:00 zz\n";
  }
  std::ofstream(node->parameter_file().string() + ".tmp") << "half-written";
  make();
  EXPECT_EQ(node->state(), NmtState::PreOperational);
  EXPECT_EQ(node->dictionary().get<uint16_t>(0x1017, 0), 1000);  // past the checksum: not ours
  EXPECT_FALSE(std::filesystem::exists(node->parameter_file().string() + ".tmp"));
}

TEST(NodeConfig, BadCommandLinesAreOneLineUsageErrors) {
  auto parse = [](std::vector<std::string> args) {
    std::vector<char*> argv;
    static std::string prog = "stepnode";
    argv.push_back(prog.data());
    for (auto& a : args) argv.push_back(a.data());
    bool exit_now = false;
    int code = 0;
    return parse_command_line(static_cast<int>(argv.size()), argv.data(), exit_now, code);
  };
  EXPECT_THROW(parse({"--iface", "vcan0", "--node-id", "0"}), UsageError);
  EXPECT_THROW(parse({"--iface", "vcan0", "--node-id", "128"}), UsageError);
  EXPECT_THROW(parse({"--node-id", "5"}), UsageError);
  EXPECT_THROW(parse({"--iface", "vcan0", "--node-id", "5", "--config", "/nonexistent.toml"}),
               UsageError);
  std::string bad = (std::filesystem::temp_directory_path() / "stepnode-bad.toml").string();
  std::ofstream(bad) << "node_id = [\n";
  try {
    parse({"--iface", "vcan0", "--config", bad});
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos);
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  }
  std::ofstream(bad) << "node_id = 9\n[defaults]\n\"1017\" = 250\n";
  NodeConfig cfg = parse({"--iface", "vcan0", "--config", bad});
  EXPECT_EQ(cfg.options.device.node_id, 9);
  ASSERT_EQ(cfg.object_defaults.size(), 1u);
  od::Dictionary d;
  build_device_objects(d, cfg.options.device, cfg.options.layout);
  apply_object_defaults(d, cfg.object_defaults);
  EXPECT_EQ(d.get<uint16_t>(0x1017, 0), 250);
  EXPECT_THROW(apply_object_defaults(d, {{"1000", "1"}}), UsageError);  // read-only
}

// Random frames at the receive paths (NMT aside): no crash, every answer well-formed.
TEST_F(NodeTest, FuzzReceivePaths) {
  map_tpdo1({0x2F000120}, 254);
  ASSERT_EQ(sdo_write(0x1400, 1, 0x80000205, 4), 0u);
  ASSERT_EQ(sdo_write(0x1600, 0, 0, 1), 0u);
  ASSERT_EQ(sdo_write(0x1600, 1, 0x2F000120, 4), 0u);
  ASSERT_EQ(sdo_write(0x1600, 2, 0x2F000220, 4), 0u);
  ASSERT_EQ(sdo_write(0x1600, 0, 2, 1), 0u);
  ASSERT_EQ(sdo_write(0x1400, 1, 0x00000205, 4), 0u);
  nmt(0x01);
  std::mt19937 rng(12345);
  const uint32_t ids[] = {0x080, 0x205, 0x305, 0x405, 0x505, 0x605, 0x705, 0x720, 0x123};
  for (int i = 0; i < 200'000; ++i) {
    CanFrame f;
    f.id = rng() % 4 ? ids[rng() % std::size(ids)] : rng() % 0x800;
    if (f.id == 0) f.id = 0x80;  // NMT would reset the node constantly
    f.dlc = static_cast<uint8_t>(rng() % 9);
    for (auto& b : f.data) b = static_cast<uint8_t>(rng());
    f.rtr = rng() % 50 == 0;
    // A data frame on 0x705, 0x585 or 0x85 is another device with this node-ID: the node
    // gives the id up (node_id_conflict_test.cpp). As remote frames they still test the paths.
    if (f.id == 0x705 || f.id == 0x585 || f.id == 0x85) f.rtr = true;
    sent.clear();
    frame(f);
    if (i % 100 == 0) tick_ms(1);
    for (const auto& out : sent) {
      ASSERT_LE(out.dlc, 8);
      if (out.id == 0x585) {
        ASSERT_EQ(out.dlc, 8);
      }
    }
  }
  EXPECT_EQ(node->state(), NmtState::Operational);
}

}  // namespace
}  // namespace stepnode::node
