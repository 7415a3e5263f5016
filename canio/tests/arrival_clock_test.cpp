// arrival_clock (issue 13): a frame's kernel timestamp on CLOCK_MONOTONIC. The clocks are
// tied by a reading bracketed by two monotonic reads; a reading whose bracket is wide (the
// process preempted between the reads) is taken again. Readings are scripted: the offsets
// and arrivals expected follow from them by hand.
#include "canio/arrival_clock.hpp"

#include <gtest/gtest.h>

#include <ctime>
#include <functional>
#include <vector>

namespace stepnode::canio {
namespace {

// Wall clock 1.7e18 ns (2023); monotonic 5 s since boot: the true offset.
constexpr int64_t kReal = 1'700'000'000'000'000'000;
constexpr int64_t kMono = 5'000'000'000;
constexpr int64_t kOffset = kReal - kMono;

// A reading whose realtime read came `delay_ns` after a monotonic read at `mono`, and
// whose second monotonic read came `width_ns` after the first.
ClockReading reading(int64_t mono, int64_t delay_ns, int64_t width_ns) {
  return {mono, kOffset + mono + delay_ns, mono + width_ns};
}

struct Script {
  std::vector<ClockReading> readings;
  size_t next = 0;
  ClockReading operator()() { return readings.at(next++); }
};

TEST(ArrivalClock, TightReadingIsTakenOnceAndErrsByHalfItsBracket) {
  Script s{{reading(kMono, 400, 1'000)}};
  const int64_t offset = realtime_offset_ns(std::ref(s));
  EXPECT_EQ(s.next, 1u);
  EXPECT_EQ(offset, kOffset + 400 - 500);  // the bracket's middle
}

TEST(ArrivalClock, PreemptedReadingIsTakenAgain) {
  // Away 1.838 ms between the first monotonic read and the realtime read (the spread a
  // loaded UML showed between two nodes' SYNC triggers): that reading alone would date
  // frames 1.8 ms early. The second reading is tight.
  Script s{{reading(kMono, 1'838'000, 1'840'000), reading(kMono + 2'000'000, 300, 600)}};
  const int64_t offset = realtime_offset_ns(std::ref(s));
  EXPECT_EQ(s.next, 2u);
  EXPECT_EQ(offset, kOffset + 300 - 300);
}

TEST(ArrivalClock, EveryReadingWideTakesTheTightest) {
  Script s{{reading(kMono, 900'000, 1'000'000), reading(kMono + 1'000'000, 150'000, 200'000),
            reading(kMono + 2'000'000, 10'000, 500'000), reading(kMono + 3'000'000, 0, 0)}};
  const int64_t offset = realtime_offset_ns(std::ref(s));
  EXPECT_EQ(s.next, static_cast<size_t>(kClockTries));  // the fourth is never read
  EXPECT_EQ(offset, kOffset + 150'000 - 100'000);
}

TEST(ArrivalClock, SystemClocksDateAStampByItsAge) {
  const auto ns_of = [](clockid_t clock) {
    timespec ts{};
    ::clock_gettime(clock, &ts);
    return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
  };
  const int64_t offset = realtime_offset_ns();
  // A frame stamped 2 ms before a realtime read that lies between two monotonic reads
  // (however long this process was away in between), dated against the monotonic clock.
  const int64_t before = ns_of(CLOCK_MONOTONIC), real = ns_of(CLOCK_REALTIME),
                after = ns_of(CLOCK_MONOTONIC);
  const uint64_t at = arrival_us(static_cast<uint64_t>(real - 2'000'000), offset,
                                 static_cast<uint64_t>(after / 1000 + 5'000));
  // The offset's own error: half its bracket, under kTightBracketNs unless the process was
  // away at all of its readings; 1 ms of slack each way.
  EXPECT_GE(static_cast<int64_t>(at), (before - 2'000'000) / 1000 - 1'000);
  EXPECT_LE(static_cast<int64_t>(at), (after - 2'000'000) / 1000 + 1'000);
}

TEST(ArrivalClock, StampOnTheMonotonicClock) {
  const uint64_t now_us = kMono / 1000;
  const auto stamp = [](int64_t mono_ns) { return static_cast<uint64_t>(kOffset + mono_ns); };
  EXPECT_EQ(arrival_us(stamp(kMono - 300'000), kOffset, now_us), now_us - 300);
  EXPECT_EQ(arrival_us(stamp(kMono), kOffset, now_us), now_us);
  EXPECT_EQ(arrival_us(stamp(kMono - 100'000'000), kOffset, now_us), now_us - 100'000);
}

TEST(ArrivalClock, NoStampOrAWallClockStepIsNow) {
  const uint64_t now_us = kMono / 1000;
  EXPECT_EQ(arrival_us(0, kOffset, now_us), now_us);
  // Later than now, or older than 100 ms: the wall clock moved, not the frame.
  EXPECT_EQ(arrival_us(static_cast<uint64_t>(kOffset + kMono + 1'000'000), kOffset, now_us),
            now_us);
  EXPECT_EQ(arrival_us(static_cast<uint64_t>(kOffset + kMono - 100'001'000), kOffset, now_us),
            now_us);
  // A stamp before the monotonic clock's zero.
  EXPECT_EQ(arrival_us(static_cast<uint64_t>(kOffset - 1'000), kOffset, now_us), now_us);
}

}  // namespace
}  // namespace stepnode::canio
