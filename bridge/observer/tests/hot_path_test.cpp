// The TPDO path must keep up with ~80,000 frames/s: no heap allocation per frame (checked
// by counting operator new while frames are decoded) and the rate printed for the record
// (a measurement, not an assertion: this machine is shared).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <new>

#include "test_bus.hpp"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<uint64_t> g_allocations{0};
}  // namespace

// Replaced for the whole test binary; counts only while g_counting is set. GCC sees the
// malloc inside "new" and the free inside "delete" and calls them mismatched; they are a
// matched pair by construction here.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t size) {
  if (g_counting.load(std::memory_order_relaxed))
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace stepnode::bridge::test {
namespace {

// A sink that does what a publisher's conversion would, without keeping anything.
struct CountingSink : SampleSink {
  uint64_t statuses = 0, positions = 0, drives = 0;
  int64_t checksum = 0;
  void axis_status(const AxisStatusSample& s) override {
    ++statuses;
    checksum += s.status_bits;
  }
  void axis_position(const AxisPositionSample& s) override {
    ++positions;
    checksum += s.motor_position;
  }
  void node_health(const NodeHealthSample&) override {}
  void emergency(const EmergencySample&) override {}
  void drive_status(const DriveStatusSample& s) override {
    ++drives;
    checksum += s.position_actual;
  }
  void dispose_axes(uint8_t, uint8_t) override {}
};

TEST(HotPath, TpdosAreDecodedWithoutAllocation) {
  // Ten nodes of three axes, discovered over SDO on the virtual bus first.
  TestBus bus;
  std::vector<std::unique_ptr<FakeNode>> nodes;
  for (uint8_t id = 1; id <= 10; ++id) {
    nodes.push_back(std::make_unique<FakeNode>(FakeNodeOptions{.id = id, .axes = 3}));
    bus.add(*nodes.back());
    bus.boot(*nodes.back());
  }
  // And two CiA 402 only nodes of two axes (TPDO1..4: statusword/mode, position/velocity).
  for (uint8_t id = 11; id <= 12; ++id) {
    nodes.push_back(std::make_unique<FakeNode>(FakeNodeOptions{
        .id = id, .axes = 2, .horner = false, .hp = false, .user = false, .cia402 = true}));
    bus.add(*nodes.back());
    bus.boot(*nodes.back());
  }
  bus.run_ms(100);
  std::vector<ObservedFrame> frames;
  for (auto& n : nodes) {
    if (n->id() > 10) {
      for (unsigned a = 0; a < 2; ++a) {
        n->set_drive(a, 0x0637, 1);
        n->set_drive_position(a, 500 * static_cast<int32_t>(a), 10);
      }
      for (unsigned k = 0; k < 4; ++k) frames.push_back(ObservedFrame{n->tpdo(k), 0, false, 0, 0});
      continue;
    }
    for (unsigned k = 0; k < 3; ++k) {
      n->set_status(0, static_cast<uint16_t>(0x0100 | k));
      n->set_position(0, 1000 * k, 999 * k);
      ObservedFrame f;
      f.frame = n->tpdo(k);
      frames.push_back(f);
    }
  }
  frames.push_back(ObservedFrame{od::CanFrame(0x080, {3}), 0, false, 0, 0});  // SYNC

  // The real observer, but with a sink that keeps nothing.
  CountingSink sink;
  BusObserver obs(sink);
  std::vector<od::CanFrame> out;
  out.reserve(64);
  for (auto& n : nodes) {
    // Discovery again for this observer (answers come from the same fake nodes).
    std::vector<od::CanFrame> pending;
    obs.on_frame(ObservedFrame{n->boot_up(), 0, false, 0, 0}, 1, pending);
    while (!pending.empty()) {
      std::vector<od::CanFrame> replies, next;
      for (const auto& f : pending) n->on_frame(f, 1, replies);
      for (const auto& r : replies) obs.on_frame(ObservedFrame{r, 0, false, 0, 0}, 1, next);
      pending.swap(next);
    }
    ASSERT_TRUE(obs.node_health(n->id(), 1).discovered);
  }

  const uint64_t snapshot_positions = sink.positions;  // discovery's own
  const uint64_t snapshot_drives = sink.drives;
  constexpr int kRounds = 20'000;
  g_allocations = 0;
  g_counting = true;
  const auto start = std::chrono::steady_clock::now();
  for (int r = 0; r < kRounds; ++r)
    for (ObservedFrame& f : frames) {
      f.can_time_ns = static_cast<uint64_t>(r);
      obs.on_frame(f, 2, out);
    }
  const auto end = std::chrono::steady_clock::now();
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0u);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(sink.positions - snapshot_positions, uint64_t{kRounds} * 30);
  EXPECT_EQ(sink.drives - snapshot_drives, uint64_t{kRounds} * 8)
      << "a DriveStatus per CiA 402 TPDO";
  const double seconds = std::chrono::duration<double>(end - start).count();
  const double rate = static_cast<double>(kRounds) * static_cast<double>(frames.size()) / seconds;
  std::printf("[ measured ] observer on_frame: %.0f frames/s (%zu frames x %d rounds, %.3f s)\n",
              rate, frames.size(), kRounds, seconds);
}

}  // namespace
}  // namespace stepnode::bridge::test
