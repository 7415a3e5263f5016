// A remote frame on a TPDO's COB-ID (CiA 301 7.2.2, 7.5.2.37 bit 30 of the COB-ID: 0 = RTR
// allowed): the node answers with the PDO, the current values, where the COB-ID allows it
// and not where it does not (the default, bit 30 = 1). Found in review (2026-12-06): a
// master could clear bit 30, was confirmed, and heard nothing; python-canopen's PDO save()
// clears it unless told otherwise.
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

class PdoRemoteRequest : public PdoHarness {
 protected:
  static CanFrame remote(uint32_t id, uint8_t dlc) {
    CanFrame f(id, {});
    f.rtr = true;
    f.dlc = dlc;
    return f;
  }
};

TEST_F(PdoRemoteRequest, AnEventDrivenTpdoWithRtrAllowedAnswersARemoteFrame) {
  map_tpdo(0, {kReg1}, 254);
  ASSERT_EQ(sdo_write(0x1800, 1, 0x80000000u | kTpdo1), 0u);
  ASSERT_EQ(sdo_write(0x1800, 1, kTpdo1), 0u);  // valid, bit 30 = 0: RTR allowed
  nmt(0x01);
  ASSERT_EQ(sdo_write(0x2F00, 1, 0x11), 0u);
  const size_t from = sent.size();
  frame(remote(kTpdo1, 4));
  advance_ms(1);
  EXPECT_EQ(with_id(kTpdo1, from), std::vector<CanFrame>{u32_frame(kTpdo1, 0x11)});
}

TEST_F(PdoRemoteRequest, ASynchronousTpdoAnswersWithTheNextSync) {
  map_tpdo(0, {kReg1}, 0);  // acyclic synchronous: on the SYNC after a change
  ASSERT_EQ(sdo_write(0x1800, 1, 0x80000000u | kTpdo1), 0u);
  ASSERT_EQ(sdo_write(0x1800, 1, kTpdo1), 0u);
  nmt(0x01);
  sync();  // the first transmission
  const size_t from = sent.size();
  sync();  // no change: nothing
  EXPECT_TRUE(with_id(kTpdo1, from).empty());
  frame(remote(kTpdo1, 4));
  advance_ms(1);
  EXPECT_TRUE(with_id(kTpdo1, from).empty()) << "not before the SYNC";
  sync();
  EXPECT_EQ(with_id(kTpdo1, from).size(), 1u);
}

TEST_F(PdoRemoteRequest, NoAnswerWhereTheCobIdSaysNoRtr) {
  map_tpdo(0, {kReg1}, 254);  // the default COB-ID: 0x40000180 + id, bit 30 = 1
  ASSERT_EQ(sdo_read(0x1800, 1).value_or(0) & 0x40000000u, 0x40000000u);
  nmt(0x01);
  const size_t from = sent.size();
  frame(remote(kTpdo1, 4));
  advance_ms(1);
  EXPECT_TRUE(with_id(kTpdo1, from).empty());
}

TEST_F(PdoRemoteRequest, NoAnswerOutsideOperational) {
  map_tpdo(0, {kReg1}, 254);
  ASSERT_EQ(sdo_write(0x1800, 1, 0x80000000u | kTpdo1), 0u);
  ASSERT_EQ(sdo_write(0x1800, 1, kTpdo1), 0u);
  const size_t from = sent.size();
  frame(remote(kTpdo1, 4));  // pre-operational: no PDO
  advance_ms(1);
  EXPECT_TRUE(with_id(kTpdo1, from).empty());
}

}  // namespace
}  // namespace stepnode::node::test
