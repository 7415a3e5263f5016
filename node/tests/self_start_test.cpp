// Self-start (CiA 302-2, 0x1F80 NMT startup): with bit 2 = 0 the device enters operational
// by itself after every boot-up; the default (bit 2 = 1) waits for the NMT master. Frames
// from CiA 301 7.2.8.3.2: boot-up = 0x700+id {00}, then each state change confirmed by a
// heartbeat {7F} pre-operational, {05} operational.
#include "node/config.hpp"
#include "node/tests/node_harness.hpp"

#include <fstream>

namespace stepnode::node::test {
namespace {

class SelfStartTest : public NodeHarness {
 protected:
  std::vector<uint8_t> heartbeat_states(size_t from = 0) {
    std::vector<uint8_t> out;
    for (const CanFrame& f : with_id(kHeartbeatId, from)) out.push_back(f.data[0]);
    return out;
  }
};

TEST_F(SelfStartTest, TheDefaultWaitsForTheMaster) {
  EXPECT_EQ(*sdo_read(0x1F80, 0), 0x00000004u);
  EXPECT_EQ(heartbeat_states(), (std::vector<uint8_t>{0x00, 0x7F}));
  EXPECT_EQ(node->state(), NmtState::PreOperational);
}

TEST_F(SelfStartTest, Bit2ClearStoredEntersOperationalAfterBootUp) {
  ASSERT_EQ(sdo_write(0x1F80, 0, 0x00000000), 0u);
  ASSERT_EQ(sdo_write(0x1010, 2, 0x65766173), 0u);  // stored with the communication group
  make();
  EXPECT_EQ(heartbeat_states(), (std::vector<uint8_t>{0x00, 0x7F, 0x05}));
  EXPECT_EQ(node->state(), NmtState::Operational);
  // Operational: the event-driven TPDO of axis 1 (status, 0x185) goes out at once.
  EXPECT_FALSE(with_id(0x185).empty());

  // An NMT command still rules afterwards, and a reset communication boots and starts again.
  nmt(0x80);
  EXPECT_EQ(node->state(), NmtState::PreOperational);
  size_t from = sent.size();
  nmt(0x82);
  EXPECT_EQ(heartbeat_states(from), (std::vector<uint8_t>{0x00, 0x7F, 0x05}));
}

TEST_F(SelfStartTest, ThisDeviceIsNoNmtMasterOtherBitsAreRefused) {
  // CiA 302-2: changing a bit of a function the device does not support is 0x06090030.
  EXPECT_EQ(sdo_write(0x1F80, 0, 0x00000001), 0x06090030u);  // NMT master
  EXPECT_EQ(sdo_write(0x1F80, 0, 0x00000005), 0x06090030u);
  EXPECT_EQ(sdo_write(0x1F80, 0, 0x0000000C), 0x06090030u);  // bit 3: a master function
  EXPECT_EQ(sdo_write(0x1F80, 0, 0x80000004), 0x06090030u);
  EXPECT_EQ(*sdo_read(0x1F80, 0), 0x00000004u);
}

TEST_F(SelfStartTest, TheConfigKeySetsTheDefault) {
  const auto path = dir.path / "self.toml";
  std::ofstream(path) << "self_start = true\n";
  std::string prog = "stepnode", a1 = "--node-id", a2 = "5", a3 = "--config", a4 = path.string(),
              a5 = "--iface", a6 = "vcan0";
  std::vector<char*> argv{prog.data(), a1.data(), a2.data(), a3.data(),
                          a4.data(),   a5.data(), a6.data()};
  bool exit_now = false;
  int code = 0;
  NodeConfig cfg = parse_command_line(static_cast<int>(argv.size()), argv.data(), exit_now, code);
  cfg.options.state_dir = dir.path;
  stop();
  device = std::make_unique<Device>(cfg.options, cfg.object_defaults,
                                    [this](const CanFrame& f) { sent.push_back(f); });
  node = &device->canopen();
  sent.clear();
  device->start(t);
  EXPECT_EQ(*sdo_read(0x1F80, 0), 0u);
  EXPECT_EQ(node->state(), NmtState::Operational);
}

}  // namespace
}  // namespace stepnode::node::test
