// The node's kernel receive filters: exactly the CAN-IDs of CiA 301's pre-defined
// connection set (7.3.3, table 43) it serves, plus what its dictionary configures, and
// nothing of other nodes. The expected identifiers are written from the standard for
// node-ID 5 (NMT 000h, SYNC 080h, EMCY 080h+id, TIME 100h, SDO 600h+id / 580h+id, NMT error
// control 700h+id, RPDO1 200h+id) and CiA 305 (LSS master 7E5h).
#include <gtest/gtest.h>

#include "node/receive_filters.hpp"
#include "node/tests/node_harness.hpp"
#include "od/communication_objects.hpp"

namespace stepnode::node::test {
namespace {

using F = ReceiveFilter::Frames;

std::vector<ReceiveFilter> bare_node_5() {
  return {{0x000, F::Data}, {0x080, F::Data}, {0x085, F::Data},          {0x100, F::Data},
          {0x585, F::Data}, {0x605, F::Data}, {0x705, F::DataAndRemote}, {0x7E5, F::Data}};
}

std::vector<ReceiveFilter> with(std::vector<ReceiveFilter> list,
                                std::initializer_list<ReceiveFilter> more) {
  list.insert(list.end(), more);
  std::sort(list.begin(), list.end());
  return list;
}

bool has(const std::vector<ReceiveFilter>& list, uint32_t id) {
  return std::any_of(list.begin(), list.end(), [id](const ReceiveFilter& f) { return f.id == id; });
}

class ReceiveFilterTable : public ::testing::Test {
 protected:
  void SetUp() override {
    od::DeviceInfo info;
    info.node_id = 5;
    od::build_communication_objects(od, info, 4);
  }
  std::vector<ReceiveFilter> list() { return receive_filters(od, 5, 4); }
  od::Dictionary od;
};

TEST_F(ReceiveFilterTable, ABareSlaveHearsItsPredefinedConnectionSet) {
  // No RPDO has a mapping: none is received (CiA 301 7.5.2.36).
  EXPECT_EQ(list(), bare_node_5());
}

TEST_F(ReceiveFilterTable, HeartbeatConsumersAddTheWatchedNodesHeartbeat) {
  od.put<uint32_t>(0x1016, 1, 0x000101F4);  // node 1, 500 ms
  od.put<uint32_t>(0x1016, 2, 0x00200000);  // node 0x20, time 0: not used
  od.put<uint32_t>(0x1016, 3, 0x00000064);  // node 0: not used
  EXPECT_EQ(list(), with(bare_node_5(), {{0x701, F::Data}}));
}

TEST_F(ReceiveFilterTable, AValidMappedRpdoIsHeardAnInvalidOneNot) {
  od.put<uint8_t>(0x1600, 0, 1);
  od.put<uint32_t>(0x1600, 1, 0x20000108);
  od.put<uint32_t>(0x1400, 1, 0x00000205);
  od.put<uint8_t>(0x1601, 0, 1);
  od.put<uint32_t>(0x1601, 1, 0x20000108);
  od.put<uint32_t>(0x1401, 1, 0x80000305);  // bit 31: not valid
  EXPECT_EQ(list(), with(bare_node_5(), {{0x205, F::Data}}));
}

TEST_F(ReceiveFilterTable, TimeNotConsumedAndEmcyInvalidAreNotHeard) {
  od.put<uint32_t>(0x1012, 0, 0x40000100);  // producer only
  od.put<uint32_t>(0x1014, 0, 0x80000085);
  auto expected = bare_node_5();
  std::erase_if(expected, [](const ReceiveFilter& f) { return f.id == 0x100 || f.id == 0x085; });
  EXPECT_EQ(list(), expected);
}

TEST_F(ReceiveFilterTable, ExtraSdoChannelsAndAMovedSyncAreHeard) {
  od.put<uint32_t>(0x1201, 1, 0x00000641);
  od.put<uint32_t>(0x1201, 2, 0x000005C1);
  od.put<uint32_t>(0x1005, 0, 0x00000090);
  auto expected = bare_node_5();
  std::erase_if(expected, [](const ReceiveFilter& f) { return f.id == 0x080; });
  EXPECT_EQ(list(), with(expected, {{0x090, F::Data}, {0x641, F::Data}}));
}

TEST_F(ReceiveFilterTable, WithoutANodeIdOnlyLssAndNmt) {
  EXPECT_EQ(receive_filters(od, lss::kUnconfigured, 4),
            (std::vector<ReceiveFilter>{{0x000, F::Data}, {0x7E5, F::Data}}));
}

TEST(ReceiveFilterLimit, MoreThanTheKernelTakesIsEveryFrame) {
  od::DeviceInfo info;
  info.node_id = 5;
  od::Dictionary od;
  od::build_communication_objects(od, info, od::kMaxPdos);
  for (unsigned n = 0; n < od::kMaxPdos; ++n) {
    od.put<uint8_t>(od::rpdo_mapping(n), 0, 1);
    od.put<uint32_t>(od::rpdo_parameter(n), 1, 0x200 + n);  // 0x200..0x3FF, all distinct
  }
  EXPECT_TRUE(receive_filters(od, 5, od::kMaxPdos).empty());
}

// The whole device: the list follows the dictionary, and is given out before the SDO
// answer that changed it, so a master that then sends on the new COB-ID is heard.
class DeviceReceiveFilters : public NodeHarness {
 protected:
  void SetUp() override {
    NodeHarness::SetUp();
    device->set_receive_filter_sink([this](const std::vector<ReceiveFilter>& f) {
      lists.push_back(f);
      given_at.push_back(sent.size());
    });
  }
  std::vector<std::vector<ReceiveFilter>> lists;
  std::vector<size_t> given_at;  // frames sent when each list was given
};

TEST_F(DeviceReceiveFilters, TheCurrentListIsGivenAtOnce) {
  ASSERT_EQ(lists.size(), 1u);
  for (uint32_t id : {0x000u, 0x080u, 0x085u, 0x100u, 0x585u, 0x605u, 0x705u, 0x7E5u})
    EXPECT_TRUE(has(lists[0], id)) << id;
  EXPECT_FALSE(has(lists[0], 0x706));
  EXPECT_FALSE(has(lists[0], 0x606));
}

TEST_F(DeviceReceiveFilters, AHeartbeatConsumerWrittenOverSdoIsFilteredBeforeTheAnswer) {
  const size_t before = sent.size();
  ASSERT_EQ(sdo_write(0x1016, 1, 0x000101F4), 0u);
  ASSERT_EQ(lists.size(), 2u);
  EXPECT_TRUE(has(lists[1], 0x701));
  EXPECT_EQ(given_at[1], before);  // before the SDO answer went out
}

TEST_F(DeviceReceiveFilters, AnRpdoMadeInvalidIsNoLongerHeard) {
  ASSERT_TRUE(has(lists.back(), 0x205)) << "RPDO1 of the pre-defined set is valid by default";
  ASSERT_EQ(sdo_write(0x1400, 1, 0x80000205), 0u);
  EXPECT_FALSE(has(lists.back(), 0x205));
  ASSERT_EQ(sdo_write(0x1400, 1, 0x00000205), 0u);
  EXPECT_TRUE(has(lists.back(), 0x205));
}

TEST_F(DeviceReceiveFilters, ANewNodeIdOverLssMovesTheList) {
  frame(CanFrame(0x7E5, {0x04, 0x01, 0, 0, 0, 0, 0, 0}));  // switch state global: configuration
  frame(CanFrame(0x7E5, {0x11, 0x21, 0, 0, 0, 0, 0, 0}));  // configure node-ID 0x21
  frame(CanFrame(0x7E5, {0x04, 0x00, 0, 0, 0, 0, 0, 0}));  // waiting
  nmt(0x82);                                               // reset communication: it takes effect
  const auto& now = lists.back();
  for (uint32_t id : {0x0A1u, 0x5A1u, 0x621u, 0x721u}) EXPECT_TRUE(has(now, id)) << std::hex << id;
  for (uint32_t id : {0x085u, 0x585u, 0x605u, 0x705u}) EXPECT_FALSE(has(now, id)) << std::hex << id;
}

TEST_F(DeviceReceiveFilters, StoredParametersAreFilteredAtTheNextStart) {
  ASSERT_EQ(sdo_write(0x1016, 1, 0x000201F4), 0u);
  ASSERT_EQ(sdo_write(0x1010, 2, od::kSaveSignature), 0u);
  make();
  lists.clear();
  device->set_receive_filter_sink(
      [this](const std::vector<ReceiveFilter>& f) { lists.push_back(f); });
  EXPECT_TRUE(has(lists.back(), 0x702));
}

}  // namespace
}  // namespace stepnode::node::test
