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
std::vector<HomingSearch> home_switch_plan(int active_side, int index_side, bool with_index, bool home_active) {
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
  }
  return false;
}

std::optional<std::vector<HomingSearch>> homing_plan(int8_t method, bool home_active) {
  switch (method) {
    // Limit switch, then (1, 2) the first index pulse after it is released.
    case 1: return std::vector<HomingSearch>{{kNeg, kFast, E::NegativeLimitOn, Then::Stop},
                                             {kPos, kSlow, E::NegativeLimitOff, Then::Continue},
                                             {kPos, kSlow, E::IndexOn, Then::Home}};
    case 2: return std::vector<HomingSearch>{{kPos, kFast, E::PositiveLimitOn, Then::Stop},
                                             {kNeg, kSlow, E::PositiveLimitOff, Then::Continue},
                                             {kNeg, kSlow, E::IndexOn, Then::Home}};
    case 17: return std::vector<HomingSearch>{{kNeg, kFast, E::NegativeLimitOn, Then::Stop},
                                              {kPos, kSlow, E::NegativeLimitOff, Then::Home}};
    case 18: return std::vector<HomingSearch>{{kPos, kFast, E::PositiveLimitOn, Then::Stop},
                                              {kNeg, kSlow, E::PositiveLimitOff, Then::Home}};
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
    case 33: return std::vector<HomingSearch>{{kNeg, kSlow, E::IndexOn, Then::Home}};
    case 34: return std::vector<HomingSearch>{{kPos, kSlow, E::IndexOn, Then::Home}};
    case 35:
    case 37: return std::vector<HomingSearch>{};
    default: return std::nullopt;
  }
}

}  // namespace stepnode::cia402
