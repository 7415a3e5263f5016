#include "node/profiles/cia402/homing.hpp"

namespace stepnode::cia402 {
namespace {

using Then = HomingSearch::Then;
using E = HomingEvent;
constexpr int kNeg = -1, kPos = +1;
constexpr bool kFast = true, kSlow = false;

// Methods 3..6 and 19..22: the home switch and, for 3..6, the index pulse after its edge.
// `active_side`: the direction in which the switch is active (3, 4, 19, 20: positive home
// switch; 5, 6, 21, 22: negative); `index_side`: where of the edge the home position lies;
// `with_index`: 3..6.
std::vector<HomingSearch> home_switch_plan(int active_side, int index_side, bool with_index,
                                           bool home_active) {
  std::vector<HomingSearch> plan;
  auto edge = [&](int direction, HomingEvent until, bool fast, Then then) {
    plan.push_back({direction, fast, until, then});
  };
  // The last search crosses the edge toward `index_side` at the slow speed: onto the home
  // position (19..22), or on to the index pulse (3..6).
  const Then at_edge = with_index ? Then::Continue : Then::Home;
  // Crossing toward index_side leaves the switch when index_side is its inactive side.
  const bool leave_toward_index = index_side != active_side;
  if (!home_active) {
    edge(active_side, E::HomeOn, kFast, Then::Stop);  // find the switch
    if (leave_toward_index) {
      edge(-active_side, E::HomeOff, kSlow, at_edge);  // back out of it, slowly
    } else {
      edge(-active_side, E::HomeOff, kSlow, Then::Stop);  // back out, then in again slowly
      edge(active_side, E::HomeOn, kSlow, at_edge);
    }
  } else if (leave_toward_index) {
    edge(-active_side, E::HomeOff, kSlow, at_edge);  // on the switch: leave it
  } else {
    edge(-active_side, E::HomeOff, kFast, Then::Stop);  // leave it, then come back slowly
    edge(active_side, E::HomeOn, kSlow, at_edge);
  }
  if (with_index) edge(index_side, E::IndexOn, kSlow, Then::Home);
  return plan;
}

// Methods 7..14 and 23..30: a home switch active over a part of the travel only (CiA 402-2:
// "in effect the switch has a momentary action as the axle's position sweeps past it").
// The home position is on one of its two edges (`upper`: the edge toward positive
// positions), crossed last in `final_direction` at the slow speed, and for 7..14 the first
// index pulse beyond it in that direction. The first search runs in `initial_direction`
// (7..10 positive, 11..14 negative) until the switch comes on, reversing once at the limit
// switch if that direction leads away from it; it stops inside the switch (wider than the
// stopping distance). On the switch at the start, the drive goes for the edge at once.
std::vector<HomingSearch> home_window_plan(int initial_direction, bool upper, int final_direction,
                                           bool with_index, bool home_active) {
  std::vector<HomingSearch> plan;
  if (!home_active) {
    HomingSearch find{initial_direction, kFast, E::HomeOn, Then::Stop};
    find.reverse_at_limit = true;
    plan.push_back(find);
  }
  // From inside the switch: the edge is left in `final_direction` when that direction
  // points out through it (upper edge and positive, lower edge and negative); otherwise the
  // drive leaves through the edge the other way, then comes back across it.
  const Then at_edge = with_index ? Then::Continue : Then::Home;
  const int outward = upper ? kPos : kNeg;
  if (final_direction == outward) {
    plan.push_back({final_direction, kSlow, E::HomeOff, at_edge});
  } else {
    plan.push_back({outward, home_active ? kFast : kSlow, E::HomeOff, Then::Stop});
    plan.push_back({final_direction, kSlow, E::HomeOn, at_edge});
  }
  if (with_index) plan.push_back({final_direction, kSlow, E::IndexOn, Then::Home});
  return plan;
}

// One of 7..14: its initial direction, edge and final direction, as listed in homing_plan.
std::vector<HomingSearch> window_method(int8_t method, bool with_index, bool home_active) {
  struct Row {
    int initial;
    bool upper;
    int final_direction;
  };
  static constexpr Row kRows[] = {
      {kPos, false, kNeg}, {kPos, false, kPos}, {kPos, true, kNeg},  {kPos, true, kPos},   // 7..10
      {kNeg, true, kPos},  {kNeg, true, kNeg},  {kNeg, false, kPos}, {kNeg, false, kNeg},  // 11..14
  };
  const Row& r = kRows[method - 7];
  return home_window_plan(r.initial, r.upper, r.final_direction, with_index, home_active);
}

}  // namespace

bool happened(HomingEvent event, const HomingInputs& b, const HomingInputs& a) {
  switch (event) {
    case E::NegativeLimitOn: return a.negative_limit && !b.negative_limit;
    case E::NegativeLimitOff: return !a.negative_limit && b.negative_limit;
    case E::PositiveLimitOn: return a.positive_limit && !b.positive_limit;
    case E::PositiveLimitOff: return !a.positive_limit && b.positive_limit;
    case E::HomeOn: return a.home && !b.home;
    case E::HomeOff: return !a.home && b.home;
    case E::IndexOn: return a.index && !b.index;
    case E::Block: return false;  // not an input: the drive detects it
  }
  return false;
}

std::optional<std::vector<HomingSearch>> homing_plan(int8_t method, bool home_active) {
  switch (method) {
    // Limit switch, then (1, 2) the first index pulse after it is released.
    case 1:
      return std::vector<HomingSearch>{{kNeg, kFast, E::NegativeLimitOn, Then::Stop},
                                       {kPos, kSlow, E::NegativeLimitOff, Then::Continue},
                                       {kPos, kSlow, E::IndexOn, Then::Home}};
    case 2:
      return std::vector<HomingSearch>{{kPos, kFast, E::PositiveLimitOn, Then::Stop},
                                       {kNeg, kSlow, E::PositiveLimitOff, Then::Continue},
                                       {kNeg, kSlow, E::IndexOn, Then::Home}};
    case 17:
      return std::vector<HomingSearch>{{kNeg, kFast, E::NegativeLimitOn, Then::Stop},
                                       {kPos, kSlow, E::NegativeLimitOff, Then::Home}};
    case 18:
      return std::vector<HomingSearch>{{kPos, kFast, E::PositiveLimitOn, Then::Stop},
                                       {kNeg, kSlow, E::PositiveLimitOff, Then::Home}};
    // The manufacturer's methods on a hard stop: 1, 2, 17, 18 with the block in place of the
    // limit switch. The drive stops at the block at once (no ramp into a wall); the home
    // position is the block itself (-17, -18: the load cannot be anywhere else), or the
    // first index pulse on the way back at the slow speed (-1, -2).
    case -1:
      return std::vector<HomingSearch>{{kNeg, kFast, E::Block, Then::Stop},
                                       {kPos, kSlow, E::IndexOn, Then::Home}};
    case -2:
      return std::vector<HomingSearch>{{kPos, kFast, E::Block, Then::Stop},
                                       {kNeg, kSlow, E::IndexOn, Then::Home}};
    case -17: return std::vector<HomingSearch>{{kNeg, kFast, E::Block, Then::Home}};
    case -18: return std::vector<HomingSearch>{{kPos, kFast, E::Block, Then::Home}};
    // Home switch: positive (active on the positive side) for 3, 4, 19, 20, negative for
    // 5, 6, 21, 22; the home position left (3, 6, 19, 22) or right (4, 5, 20, 21) of its edge.
    case 3: return home_switch_plan(kPos, kNeg, true, home_active);
    case 4: return home_switch_plan(kPos, kPos, true, home_active);
    case 5: return home_switch_plan(kNeg, kPos, true, home_active);
    case 6: return home_switch_plan(kNeg, kNeg, true, home_active);
    case 19: return home_switch_plan(kPos, kNeg, false, home_active);
    case 20: return home_switch_plan(kPos, kPos, false, home_active);
    case 21: return home_switch_plan(kNeg, kPos, false, home_active);
    case 22: return home_switch_plan(kNeg, kNeg, false, home_active);
    // Home switch between the limit switches (CiA 402-2 figures "homing on the home switch
    // and index pulse, positive / negative initial move"): 7..10 start positive, 11..14
    // negative; the home position by the lower edge (7: below it, 8: above it) or the
    // upper edge (9: below, 10: above), 11..14 the same edges from the other side (11:
    // above the upper, 12: below the upper, 13: above the lower, 14: below the lower).
    // 23..30 are 7..14 with the edge itself as the home position.
    case 7:
    case 8:
    case 9:
    case 10:
    case 11:
    case 12:
    case 13:
    case 14: return window_method(method, true, home_active);
    case 23:
    case 24:
    case 25:
    case 26:
    case 27:
    case 28:
    case 29:
    case 30: return window_method(static_cast<int8_t>(method - 16), false, home_active);
    case 33: return std::vector<HomingSearch>{{kNeg, kSlow, E::IndexOn, Then::Home}};
    case 34: return std::vector<HomingSearch>{{kPos, kSlow, E::IndexOn, Then::Home}};
    case 35:
    case 37: return std::vector<HomingSearch>{};
    default: return std::nullopt;
  }
}

}  // namespace stepnode::cia402
