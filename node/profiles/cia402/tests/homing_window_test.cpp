// CiA 402 homing methods 7..14 and 23..30 on the simulated machine, in virtual time: a home
// switch active over a part of the travel only, between the two limit switches (CiA 402-2
// "Homing on the home switch and index pulse, positive / negative initial move"; 23..30 the
// same without the index pulse). The standard, for each method: the initial direction
// (7..10 positive, 11..14 negative, except when the home switch is active at the start:
// then the direction of the edge sought), the reversal at the limit switch when that
// direction leads away from the home switch, and the home position:
//
//   method       7/23   8/24   9/25   10/26  11/27  12/28  13/29  14/30
//   edge         lower  lower  upper  upper  upper  upper  lower  lower
//   home side    below  above  below  above  above  below  above  below
//
// With the index pulse (7..14) the home position is the first index pulse on that side of
// the edge; without (23..30) the edge itself: the first position on that side of it.
//
// The machine: limit switches active at -6000 and below, 6000 and above; the home switch
// active at 1000..2999 (its lower edge between 999 and 1000, its upper one between 2999 and
// 3000); the index pulse is the encoder marker, 4 steps wide once per 2000 steps from 0, so
// its rising edge is met at 2000 k moving up and at 2000 k + 3 moving down. Each method
// starts below the switch, on it and above it.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "node/profiles/cia402/tests/drive_harness.hpp"

namespace stepnode::cia402 {
namespace {

constexpr uint16_t kHomingBits = (1u << 13) | (1u << 12) | (1u << 10);
constexpr uint16_t kInProgress = 0, kCompleted = (1u << 12) | (1u << 10);

constexpr int64_t kNegativeLimit = -6000, kPositiveLimit = 6000;
constexpr int64_t kSwitchFrom = 1000, kSwitchTo = 3000;  // active in [from, to)
constexpr int64_t kMarkerPeriod = 2000, kMarkerWidth = 4;

enum class Edge { Lower, Upper };
enum class Side { Below, Above };

// The home position of a method without the index pulse: the first position on `side` of
// `edge`.
int64_t edge_position(Edge edge, Side side) {
  const int64_t boundary = edge == Edge::Lower ? kSwitchFrom : kSwitchTo;  // first position above
  return side == Side::Above ? boundary : boundary - 1;
}
// With the index pulse: the first rising edge of the marker met moving away from the edge
// on `side` (up: at a multiple of the period; down: its last active position).
int64_t index_position(Edge edge, Side side) {
  const int64_t from = edge_position(edge, side);
  if (side == Side::Above) return (from + kMarkerPeriod - 1) / kMarkerPeriod * kMarkerPeriod;
  const int64_t last = kMarkerWidth - 1;
  return from - (from - last) % kMarkerPeriod;
}

class HomeSwitchBetweenLimits : public DriveAxis {
 protected:
  struct Run {
    uint16_t homing_bits_after_start = 0xFFFF;
    uint16_t homing_bits = 0xFFFF;
    int first_direction = 0;
    int64_t lowest = 0, highest = 0;  // the travel
  };

  // A fresh machine at `start` (with or without the home switch), enabled in homing mode,
  // method `m` started and run to its end.
  Run run_method(int8_t m, int64_t start, bool home_switch = true) {
    motor = RecordingMachine{};
    motor.config().lower_limit = kNegativeLimit;
    motor.config().upper_limit = kPositiveLimit;
    if (home_switch) motor.config().home = sim::Cam{kSwitchFrom, kSwitchTo - kSwitchFrom};
    motor.displace(start);
    core.power_up(now);
    core.set_position(static_cast<int32_t>(start));
    drive.power_up(now, drive.mode());
    core.advance_to(now);
    Parameters& p = drive.parameters();
    p.homing_method = m;
    p.homing_switch_speed = 2000;  // stopping distance 100 steps: well inside the switch
    p.homing_zero_speed = 200;
    p.homing_acceleration = 20'000;
    drive.set_mode(Mode::Homing, now);
    enable();
    Run r;
    cw(0x1F);  // homing operation start
    r.homing_bits_after_start = drive.statusword() & kHomingBits;
    for (int i = 0; i < 600 && (drive.statusword() & kHomingBits) == kInProgress; ++i) run_s(0.1);
    r.homing_bits = drive.statusword() & kHomingBits;
    int64_t at = start;
    r.lowest = r.highest = start;
    for (const sim::TracedStep& s : motor.steps) {
      at += s.direction;
      r.lowest = std::min(r.lowest, at);
      r.highest = std::max(r.highest, at);
    }
    if (!motor.steps.empty()) r.first_direction = motor.steps.front().direction;
    return r;
  }

  // Method `m` from below, on and above the switch ends at `home`, completed (13/12/10 =
  // 0/1/1 after 0/0/0 from the start edge), with 6064h the home offset. The first step goes
  // `initial` (the method's initial direction) unless the switch is active at the start,
  // then toward the edge sought; a start from which `initial` leads away from the switch
  // turns back at that limit switch.
  void expect_method(int8_t m, int initial, Edge edge, int64_t home) {
    const int toward_edge = edge == Edge::Upper ? +1 : -1;
    struct Start {
      int64_t at;
      int first_direction;
      bool reverses;
    };
    const std::vector<Start> starts = {
        {kSwitchFrom - 3500, initial, initial < 0},           // below
        {(kSwitchFrom + kSwitchTo) / 2, toward_edge, false},  // on the switch
        {kSwitchTo + 1500, initial, initial > 0},             // above
    };
    drive.parameters().home_offset = 250;
    for (const Start& s : starts) {
      SCOPED_TRACE(testing::Message() << "method " << int{m} << " from " << s.at);
      const Run r = run_method(m, s.at);
      EXPECT_EQ(r.homing_bits_after_start, kInProgress);
      EXPECT_EQ(r.homing_bits, kCompleted);
      EXPECT_EQ(motor.position(), home);
      EXPECT_EQ(drive.position_actual(), 250);  // 607Ch at the home position
      EXPECT_EQ(r.first_direction, s.first_direction);
      if (s.reverses) {
        EXPECT_TRUE(initial > 0 ? r.highest >= kPositiveLimit : r.lowest <= kNegativeLimit)
            << "no reversal";
      } else {
        EXPECT_TRUE(r.highest < kPositiveLimit && r.lowest > kNegativeLimit)
            << "went to a limit switch";
      }
    }
  }
};

TEST_F(HomeSwitchBetweenLimits, Method7IndexPulseBelowTheLowerEdgePositiveStart) {
  expect_method(7, +1, Edge::Lower, index_position(Edge::Lower, Side::Below));
}
TEST_F(HomeSwitchBetweenLimits, Method8IndexPulseAboveTheLowerEdgePositiveStart) {
  expect_method(8, +1, Edge::Lower, index_position(Edge::Lower, Side::Above));
}
TEST_F(HomeSwitchBetweenLimits, Method9IndexPulseBelowTheUpperEdgePositiveStart) {
  expect_method(9, +1, Edge::Upper, index_position(Edge::Upper, Side::Below));
}
TEST_F(HomeSwitchBetweenLimits, Method10IndexPulseAboveTheUpperEdgePositiveStart) {
  expect_method(10, +1, Edge::Upper, index_position(Edge::Upper, Side::Above));
}
TEST_F(HomeSwitchBetweenLimits, Method11IndexPulseAboveTheUpperEdgeNegativeStart) {
  expect_method(11, -1, Edge::Upper, index_position(Edge::Upper, Side::Above));
}
TEST_F(HomeSwitchBetweenLimits, Method12IndexPulseBelowTheUpperEdgeNegativeStart) {
  expect_method(12, -1, Edge::Upper, index_position(Edge::Upper, Side::Below));
}
TEST_F(HomeSwitchBetweenLimits, Method13IndexPulseAboveTheLowerEdgeNegativeStart) {
  expect_method(13, -1, Edge::Lower, index_position(Edge::Lower, Side::Above));
}
TEST_F(HomeSwitchBetweenLimits, Method14IndexPulseBelowTheLowerEdgeNegativeStart) {
  expect_method(14, -1, Edge::Lower, index_position(Edge::Lower, Side::Below));
}

TEST_F(HomeSwitchBetweenLimits, Method23BelowTheLowerEdgePositiveStart) {
  expect_method(23, +1, Edge::Lower, edge_position(Edge::Lower, Side::Below));
}
TEST_F(HomeSwitchBetweenLimits, Method24AboveTheLowerEdgePositiveStart) {
  expect_method(24, +1, Edge::Lower, edge_position(Edge::Lower, Side::Above));
}
TEST_F(HomeSwitchBetweenLimits, Method25BelowTheUpperEdgePositiveStart) {
  expect_method(25, +1, Edge::Upper, edge_position(Edge::Upper, Side::Below));
}
TEST_F(HomeSwitchBetweenLimits, Method26AboveTheUpperEdgePositiveStart) {
  expect_method(26, +1, Edge::Upper, edge_position(Edge::Upper, Side::Above));
}
TEST_F(HomeSwitchBetweenLimits, Method27AboveTheUpperEdgeNegativeStart) {
  expect_method(27, -1, Edge::Upper, edge_position(Edge::Upper, Side::Above));
}
TEST_F(HomeSwitchBetweenLimits, Method28BelowTheUpperEdgeNegativeStart) {
  expect_method(28, -1, Edge::Upper, edge_position(Edge::Upper, Side::Below));
}
TEST_F(HomeSwitchBetweenLimits, Method29AboveTheLowerEdgeNegativeStart) {
  expect_method(29, -1, Edge::Lower, edge_position(Edge::Lower, Side::Above));
}
TEST_F(HomeSwitchBetweenLimits, Method30BelowTheLowerEdgeNegativeStart) {
  expect_method(30, -1, Edge::Lower, edge_position(Edge::Lower, Side::Below));
}

// No home switch between the limits: the search reverses once at the first limit switch and
// ends at the other with a homing error (13 = 1), standing (10 = 1).
TEST_F(HomeSwitchBetweenLimits, WithoutAHomeSwitchTheSecondLimitIsAHomingError) {
  for (int8_t m : {8, 12, 24, 28}) {
    SCOPED_TRACE(int{m});
    const Run r = run_method(m, 0, false);
    EXPECT_EQ(r.homing_bits, (1u << 13) | (1u << 10));  // error, standing
    // Turned at the limit switch of the initial direction, stopped at the other one.
    const bool positive_start = m == 8 || m == 24;
    EXPECT_TRUE(positive_start ? r.highest >= kPositiveLimit : r.lowest <= kNegativeLimit);
    EXPECT_EQ(motor.position(), positive_start ? kNegativeLimit : kPositiveLimit);
  }
}

}  // namespace
}  // namespace stepnode::cia402
