// The LSS slave's stored configuration: a round trip, one file per identity in a shared
// state directory, a damaged file ignored (the node then starts as the other sources say),
// and a store that cannot be written answered with CiA 305's "storage media access error".
#include <fstream>

#include "node/lss_store.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

constexpr lss::Identity kA{0, 0x53544550, 0x00010000, 1}, kB{0, 0x53544550, 0x00010000, 2};

TEST(LssStore, RoundTripOneFilePerIdentity) {
  TempDir dir;
  LssStore a(dir.path, kA), b(dir.path, kB);
  EXPECT_NE(a.file(), b.file());
  EXPECT_EQ(a.file().filename(), "lss-00000000-53544550-00000001.conf");
  EXPECT_EQ(a.load(), std::nullopt);  // first start: nothing stored
  ASSERT_TRUE(a.save({0x21, 3}));
  ASSERT_TRUE(b.save({0x22, std::nullopt}));
  EXPECT_EQ(a.load(), (LssStore::Contents{0x21, 3}));
  EXPECT_EQ(b.load(), (LssStore::Contents{0x22, std::nullopt}));
  ASSERT_TRUE(a.save({lss::kUnconfigured, std::nullopt}));  // "no node-ID" is stored too
  EXPECT_EQ(a.load(), (LssStore::Contents{lss::kUnconfigured, std::nullopt}));
}

TEST(LssStore, ADamagedFileIsIgnored) {
  TempDir dir;
  LssStore a(dir.path, kA);
  for (const char* text : {"garbage\n", "# stepnode LSS configuration v1\nnode_id 200\n",
                           "# stepnode LSS configuration v1\nnode_id 5\nbit_timing 5\n",
                           "# stepnode LSS configuration v1\n", "node_id 5\n"}) {
    std::ofstream(a.file()) << text;
    EXPECT_EQ(a.load(), std::nullopt) << text;
  }
}

class LssStoreNode : public NodeHarness {
 protected:
  void SetUp() override { start(); }
  void start() {
    NodeOptions o;
    o.device.node_id = lss::kUnconfigured;
    o.node_id_origin = NodeIdOrigin::None;
    o.state_dir = dir.path;
    make(o);
  }
  CanFrame lss(std::initializer_list<uint8_t> bytes) {
    CanFrame f(0x7E5, {0, 0, 0, 0, 0, 0, 0, 0});
    size_t i = 0;
    for (uint8_t b : bytes) f.data[i++] = b;
    return f;
  }
};

TEST_F(LssStoreNode, ADamagedFileLeavesTheNodeUnconfigured) {
  std::ofstream(node->lss_file()) << "node_id = 5\n";
  start();
  EXPECT_FALSE(node->configured());
  EXPECT_TRUE(sent.empty());
}

TEST_F(LssStoreNode, AStoreThatCannotBeWrittenIsAStorageMediaAccessError) {
  // A directory where the file should be: the rename over it fails, whoever runs the test.
  std::filesystem::create_directory(node->lss_file());
  frame(lss({0x04, 0x01}));
  frame(lss({0x11, 0x09}));
  clear_sent();
  frame(lss({0x17}));
  EXPECT_EQ(sent, std::vector<CanFrame>{CanFrame(0x7E4, {0x17, 0x02, 0, 0, 0, 0, 0, 0})});
  std::filesystem::remove(node->lss_file());
  clear_sent();
  frame(lss({0x17}));
  EXPECT_EQ(sent, std::vector<CanFrame>{CanFrame(0x7E4, {0x17, 0x00, 0, 0, 0, 0, 0, 0})});
  start();
  EXPECT_EQ(node->node_id(), 9);
}

}  // namespace
}  // namespace stepnode::node::test
