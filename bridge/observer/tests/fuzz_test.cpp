// Random frames (any identifier, length, RTR, error frames) mixed with a real node's traffic
// and random time steps: the observer never crashes, counts every frame, and keeps
// decoding the real node afterwards. Runs under ASan/UBSan in the sanitizer build.
#include <gtest/gtest.h>

#include <random>

#include "test_bus.hpp"

namespace stepnode::bridge::test {
namespace {

od::CanFrame random_frame(std::mt19937& rng) {
  od::CanFrame f;
  // Half the time an identifier the observer cares about (node 5's, SYNC, NMT).
  static const uint32_t interesting[] = {0x000, 0x080, 0x085, 0x185, 0x285, 0x385, 0x485,
                                         0x585, 0x605, 0x705, 0x706, 0x0FF, 0x77F};
  f.id = (rng() % 2) ? interesting[rng() % std::size(interesting)] : rng() % 0x800;
  f.dlc = static_cast<uint8_t>(rng() % 9);
  for (auto& b : f.data) b = static_cast<uint8_t>(rng());
  // SDO and heartbeat bytes that look right now and then.
  if (rng() % 4 == 0)
    f.data[0] =
        static_cast<uint8_t>(std::array{0x00, 0x04, 0x05, 0x7F, 0x60, 0x43, 0x4F, 0x80}[rng() % 8]);
  f.rtr = rng() % 20 == 0;
  return f;
}

TEST(Fuzz, RandomFramesNeverCrashAndAreAllCounted) {
  for (uint32_t seed = 1; seed <= 20; ++seed) {
    std::mt19937 rng(seed);
    TestBus bus;
    FakeNode node({.id = 5, .axes = 3});
    bus.add(node);
    bus.boot(node);
    uint64_t fed = 0;
    const uint64_t own_before = bus.observer.counters().frames;
    for (int i = 0; i < 3000; ++i) {
      ObservedFrame of;
      of.frame = random_frame(rng);
      if (rng() % 50 == 0) {
        of.error_frame = true;
        of.error_class = rng();
        of.controller_status = static_cast<uint8_t>(rng());
      }
      std::vector<od::CanFrame> out;
      bus.observer.on_frame(of, bus.now_us, out);
      ++fed;
      if (rng() % 10 == 0) bus.run_ms(rng() % 50);
    }
    const BusCounters& c = bus.observer.counters();
    EXPECT_GE(c.frames, own_before + fed);
    EXPECT_LE(c.bad_frames + c.undecoded + c.error_frames, c.frames);

    // Afterwards the real node is still understood (re-discovered if the noise said so).
    bus.boot(node);
    bus.run_ms(1000);
    EXPECT_TRUE(bus.observer.node_health(5, bus.now_us).discovered) << "seed " << seed;
    bus.sink.clear();
    node.set_position(2, 31337, 1);
    node.dictionary().put<uint32_t>(0x1809, 1, 0x40000000u | 0x1E5);  // axis 3 TPDO2
    bus.boot(node);
    bus.run_ms(100);
    bus.send(node.tpdo(9));
    ASSERT_FALSE(bus.sink.positions.empty()) << "seed " << seed;
    EXPECT_EQ(bus.sink.positions.back().axis, 3);
    EXPECT_EQ(bus.sink.positions.back().motor_position, 31337);
  }
}

TEST(Fuzz, RandomSdoAnswersDuringDiscovery) {
  // A node whose SDO server answers nonsense: discovery fails and retries, never crashes.
  for (uint32_t seed = 1; seed <= 20; ++seed) {
    std::mt19937 rng(seed);
    TestBus bus;
    bus.send(od::CanFrame(0x705, {0x7F}));
    for (int i = 0; i < 2000; ++i) {
      od::CanFrame f(0x585, {});
      f.dlc = static_cast<uint8_t>(rng() % 9);
      for (auto& b : f.data) b = static_cast<uint8_t>(rng());
      bus.send(f);
      if (rng() % 5 == 0) bus.run_ms(rng() % 300);
      if (rng() % 7 == 0) bus.send(od::CanFrame(0x705, {0x7F}));
    }
    SUCCEED();
  }
}

}  // namespace
}  // namespace stepnode::bridge::test
