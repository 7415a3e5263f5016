// The bridge at scale (issue 13), in virtual time: 32 real nodes power up within 100 ms on
// a simulated 500 kbit/s bus that drops 1 % of the deliveries to every receiver, and the
// BusObserver with stepbridge's pacing discovers every one of them. The bounds are from
// the reads a node needs, not from a run: bridge/bench/discovery_bench.cpp prints figures.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <string>

#include "bridge/bench/sim_bus.hpp"
#include "bridge/observer/tests/recording_sink.hpp"

namespace stepnode::bridge::sim {
namespace {

struct StateDir {
  std::filesystem::path path;
  StateDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "stepnode-scale-XXXXXX").string();
    if (!::mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
    path = tmpl;
  }
  ~StateDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

SimBusOptions options(const StateDir& dir, unsigned nodes, double loss) {
  SimBusOptions o;
  o.nodes = nodes;
  o.loss = loss;
  o.seed = 13;
  o.state_dir = dir.path;
  o.observer.sdo_max_outstanding = 8;  // stepbridge's defaults
  o.observer.sdo_rate_per_s = 1000;
  return o;
}

// Every request frame the bridge sends to one node and the most that may be on the bus at
// once: measured over the run in which every node is discovered.
TEST(DiscoveryScale, ThirtyTwoNodesWithFrameLossAreAllDiscovered) {
  StateDir dir;
  test::RecordingSink sink;
  SimBus bus(options(dir, 32, 0.01), sink);
  const uint64_t t = bus.run(120'000'000, [&] { return bus.all_discovered(); });
  ASSERT_TRUE(bus.all_discovered()) << bus.discovered() << " of 32 after " << t / 1000 << " ms";

  // A stepnode with 3 axes takes about 90 reads (identity, name, 3 axis probes, the CiA 402
  // probe, 3 PSCALE, 12 TPDOs with their mappings, 3 x 5 snapshot reads), the name
  // segmented. A lost frame costs one timeout and the same read again; at 1 % loss that is
  // a few per node. Twice the lossless count bounds it with room, and it must not grow
  // with the number of nodes: the flood of issue 13 was 482 requests for no node found.
  uint64_t most = 0;
  for (unsigned id = 1; id <= 32; ++id) most = std::max(most, bus.stats().requests_to[id]);
  StateDir dir2;
  test::RecordingSink sink2;
  SimBus lossless(options(dir2, 1, 0.0), sink2);
  lossless.run(10'000'000, [&] { return lossless.all_discovered(); });
  ASSERT_TRUE(lossless.all_discovered());
  const uint64_t one_node = lossless.stats().requests_to[1];
  EXPECT_GT(one_node, 50u) << "the plan's reads, each a request";
  EXPECT_LE(most, 2 * one_node) << "requests per node bounded";
  // 32 nodes of ~100 requests at 1000 starts/s: a few seconds, not minutes.
  EXPECT_LT(t, 30'000'000u);
}

TEST(DiscoveryScale, WithoutLossEveryNodeTakesTheSameReads) {
  StateDir dir;
  test::RecordingSink sink;
  SimBus bus(options(dir, 16, 0.0), sink);
  bus.run(60'000'000, [&] { return bus.all_discovered(); });
  ASSERT_TRUE(bus.all_discovered());
  for (unsigned id = 2; id <= 16; ++id)
    EXPECT_EQ(bus.stats().requests_to[id], bus.stats().requests_to[1]) << id;
  for (unsigned id = 1; id <= 16; ++id)
    EXPECT_EQ(bus.observer().node_health(static_cast<uint8_t>(id), bus.now_us()).sdo_failures, 0u)
        << id;
}

}  // namespace
}  // namespace stepnode::bridge::sim
