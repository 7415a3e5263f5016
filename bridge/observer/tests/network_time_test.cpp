// TIME in the bridge's timestamps (issue 12): TIME_OF_DAY frames written from CiA 301's
// layout (7.2.6.3: ms after midnight in bits 0-27, days since 1984-01-01 in bits 32-47,
// little-endian), checked against a calendar date's Unix time.
#include <gtest/gtest.h>

#include "bridge/observer/network_time.hpp"
#include "test_bus.hpp"

namespace stepnode::bridge::test {
namespace {

// 2024-01-01 12:34:56.789 UTC. 2024-01-01 is day 14,610 after 1984-01-01 (40 years, 10 of
// them leap: 1984 ... 2020) and Unix second 1,704,067,200; 12:34:56.789 is 45,296,789 ms
// = 0x02B32C95 after midnight.
const od::CanFrame kNoonish(0x100, {0x95, 0x2C, 0xB3, 0x02, 0x12, 0x39});
constexpr uint64_t kNoonishUnixNs = (1'704'067'200ull * 1000 + 45'296'789) * 1'000'000;

TEST(NetworkTime, TimeOfDayIsMillisecondsAndDaysSince1984) {
  EXPECT_EQ(time_of_day_unix_ns(kNoonish), kNoonishUnixNs);
  // Midnight of 1984-01-01 itself: Unix second 441,763,200.
  EXPECT_EQ(time_of_day_unix_ns(od::CanFrame(0x100, {0, 0, 0, 0, 0, 0})),
            441'763'200ull * 1'000'000'000);
  // The 4 reserved bits above the milliseconds are not part of the time.
  EXPECT_EQ(time_of_day_unix_ns(od::CanFrame(0x100, {0x95, 0x2C, 0xB3, 0xF2, 0x12, 0x39})),
            kNoonishUnixNs);
}

TEST(NetworkTime, AFrameThatIsNoTimeOfDayIsRefused) {
  EXPECT_FALSE(
      time_of_day_unix_ns(od::CanFrame(0x100, {0x95, 0x2C, 0xB3, 0x02, 0x12})));  // 5 bytes
  // 86,400,000 ms = 0x05265C00 is the next midnight, not a time of this day.
  EXPECT_FALSE(time_of_day_unix_ns(od::CanFrame(0x100, {0x00, 0x5C, 0x26, 0x05, 0x12, 0x39})));
  NetworkTime t;
  EXPECT_FALSE(t.on_time(od::CanFrame(0x100, {1, 2, 3}), 5));
  EXPECT_FALSE(t.known());
  EXPECT_EQ(t.to_network(123), 123u) << "the host clock until a TIME frame";
}

struct Discovered {
  explicit Discovered(bool network_time) : bus(config(network_time)) {
    bus.add(node);
    bus.boot(node);
    bus.run_ms(50);
    EXPECT_TRUE(bus.observer.node_health(5, bus.now_us).discovered);
    bus.sink.clear();
  }
  static ObserverConfig config(bool network_time) {
    ObserverConfig c;
    c.network_time = network_time;
    return c;
  }
  // TPDO1 (axis 1's status) as the node sends it now; the sample's timestamp.
  uint64_t status_time() {
    node.set_status(0, static_cast<uint16_t>(++status));
    bus.send(node.tpdo(0));
    EXPECT_FALSE(bus.sink.statuses.empty());
    return bus.sink.statuses.empty() ? 0 : bus.sink.statuses.back().can_time_ns;
  }
  FakeNode node{{.id = 5, .axes = 1}};
  TestBus bus;
  uint16_t status = 0x0100;
};

TEST(NetworkTime, TimestampsFollowTheLastTimeFrameByItsKernelArrival) {
  Discovered d(true);
  EXPECT_EQ(d.status_time(), d.bus.now_us * 1000) << "no TIME yet: the host clock";
  const uint64_t time_arrival_ns = d.bus.now_us * 1000;
  d.bus.send(kNoonish);
  ASSERT_TRUE(d.bus.observer.network_time_offset_ns());
  d.bus.run_ms(5);
  EXPECT_EQ(d.status_time(), kNoonishUnixNs + 5'000'000) << "5 ms after the TIME frame's arrival";
  EXPECT_EQ(*d.bus.observer.network_time_offset_ns(),
            static_cast<int64_t>(kNoonishUnixNs) - static_cast<int64_t>(time_arrival_ns));

  // A producer that stamps the next frame 1 s later (by its clock) 990 ms later (by ours):
  // the new offset applies from that frame on.
  d.bus.run_ms(985);
  const od::CanFrame one_second_later(0x100,
                                      {0x7D, 0x30, 0xB3, 0x02, 0x12, 0x39});  // 45,297,789 ms
  d.bus.send(one_second_later);
  d.bus.run_ms(2);
  EXPECT_EQ(d.status_time(), kNoonishUnixNs + 1'000'000'000 + 2'000'000);
}

TEST(NetworkTime, ABadTimeFrameKeepsTheLastOffset) {
  Discovered d(true);
  d.bus.send(kNoonish);
  const int64_t offset = *d.bus.observer.network_time_offset_ns();
  const uint64_t bad_before = d.bus.observer.counters().bad_frames;
  d.bus.send(od::CanFrame(0x100, {0x00, 0x5C, 0x26, 0x05, 0x12, 0x39}));  // 24:00:00.000
  EXPECT_EQ(d.bus.observer.counters().bad_frames, bad_before + 1);
  EXPECT_EQ(*d.bus.observer.network_time_offset_ns(), offset);
}

TEST(NetworkTime, OffTimeFramesChangeNothing) {
  Discovered d(false);
  d.bus.send(kNoonish);
  EXPECT_FALSE(d.bus.observer.network_time_offset_ns());
  d.bus.run_ms(5);
  EXPECT_EQ(d.status_time(), d.bus.now_us * 1000) << "the host clock, as before the option";
}

}  // namespace
}  // namespace stepnode::bridge::test
