// Received frames the CAN socket dropped (SO_RXQ_OVFL, delivered by canio::SocketCan with
// the next frame) reach the node: EMCY 0x8110 per increase, a count in 0x2F10.
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

using ReceiveOverrun = NodeHarness;

TEST_F(ReceiveOverrun, FramesTheSocketDroppedAreEmcy8110AndCountedIn2F10) {
  // Flooded, the socket queue dropped frames and nobody knew (issue 14): the kernel's
  // SO_RXQ_OVFL count now reaches the node with the next frame received.
  size_t from = sent.size();
  node->on_receive_overruns(3, t);
  auto e = emcys(from);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(emcy_code(e[0]), 0x8110);    // CiA 301: CAN overrun (objects lost)
  EXPECT_EQ(e[0].data[2] & 0x10, 0x10);  // communication error
  EXPECT_EQ(e[0].data[3], 3);
  EXPECT_EQ(sdo_read(0x2F10, 0), 3u);
  node->on_receive_overruns(3, t);  // the same count: nothing new
  EXPECT_EQ(emcys(from).size(), 1u);
  advance_ms(100);  // past any EMCY inhibit time
  node->on_receive_overruns(5, t);
  e = emcys(from);
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(e[1].data[3], 2);
  EXPECT_EQ(sdo_read(0x2F10, 0), 5u);
  // Reset node: the object restarts at 0, only new drops count.
  nmt(0x81);
  EXPECT_EQ(sdo_read(0x2F10, 0), 0u);
  node->on_receive_overruns(6, t);
  EXPECT_EQ(sdo_read(0x2F10, 0), 1u);
}

}  // namespace
}  // namespace stepnode::node::test
