// Two bridges on one bus both see the same boot-up and start discovery at the same moment:
// their first requests collide on the node's single SDO channel. Each gives up without an
// abort frame and waits for quiet plus a random extra, so one goes first and the other
// waits until it is done: both end up with the whole node.
#include <gtest/gtest.h>

#include <deque>

#include "bridge/observer/bus_observer.hpp"
#include "fake_node.hpp"
#include "recording_sink.hpp"

namespace stepnode::bridge::test {
namespace {

struct TwoBridges {
  explicit TwoBridges(uint32_t jitter_ms)
      : a(sink_a, config(jitter_ms, 1)), b(sink_b, config(jitter_ms, 2)) {}
  static ObserverConfig config(uint32_t jitter_ms, uint32_t seed) {
    ObserverConfig c;
    c.collision_jitter_ms = jitter_ms;
    c.random_seed = seed;
    return c;
  }
  RecordingSink sink_a, sink_b;
  BusObserver a, b;
  FakeNode node{{.id = 5, .axes = 2}};
  uint64_t now_us = 1'000'000;
  enum From { A, B, Other };
  std::deque<std::pair<od::CanFrame, From>> queue;

  void send(const od::CanFrame& f, From from = Other) {
    queue.emplace_back(f, from);
    drain();
  }
  void drain() {
    while (!queue.empty()) {
      auto [frame, origin] = queue.front();
      queue.pop_front();
      std::vector<od::CanFrame> out;
      ObservedFrame of{frame, now_us * 1000, false, 0, 0};
      if (origin != A) {
        a.on_frame(of, now_us, out);
        for (auto& o : out) queue.emplace_back(o, A);
        out.clear();
      }
      if (origin != B) {
        b.on_frame(of, now_us, out);
        for (auto& o : out) queue.emplace_back(o, B);
        out.clear();
      }
      node.on_frame(frame, now_us, out);
      for (auto& o : out) queue.emplace_back(o, Other);
    }
  }
  void run_ms(unsigned ms) {
    for (unsigned i = 0; i < ms; ++i) {
      now_us += 1000;
      std::vector<od::CanFrame> out_a, out_b;
      a.on_tick(now_us, 0, out_a);
      b.on_tick(now_us, 0, out_b);
      for (auto& f : out_a) queue.emplace_back(f, A);
      for (auto& f : out_b) queue.emplace_back(f, B);
      if (i % 100 == 0) queue.emplace_back(node.heartbeat(0x7F), Other);
      drain();
    }
  }
};

TEST(TwoBridges, BothDiscoverTheNodeDespiteCollidingFirst) {
  TwoBridges bus(200);
  bus.send(bus.node.boot_up());
  bus.run_ms(5000);
  const NodeHealthSample ha = bus.a.node_health(5, bus.now_us),
                         hb = bus.b.node_health(5, bus.now_us);
  EXPECT_TRUE(ha.discovered);
  EXPECT_TRUE(hb.discovered);
  EXPECT_EQ(ha.axes, 2);
  EXPECT_EQ(hb.axes, 2);
  EXPECT_GE(ha.sdo_failures + hb.sdo_failures, 1u) << "they did collide at first";
}

}  // namespace
}  // namespace stepnode::bridge::test
