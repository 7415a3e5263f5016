// peek() is the step next() takes: the axes send a step when its peeked time has come, so
// a peek later than the step delays it and an earlier one sends it early. On random moves
// of every ramp kind, changed between steps (stop, quick stop, new velocity, new end,
// constant level, halt), every peek is compared with the next step, and the whole train
// with the one a generator that never peeks makes (peek() keeps state for next(): a run's
// step is found by next() for the peek after it).
#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <random>
#include <vector>

#include "node/motion/ramp.hpp"
#include "node/motion/step_generator.hpp"

namespace stepnode::motion {
namespace {

int64_t pick(std::mt19937_64& rng, int64_t lo, int64_t hi) {
  return lo + static_cast<int64_t>(rng() % static_cast<uint64_t>(hi - lo + 1));
}

// A ramp of one of the kinds the front ends make.
RampSpec random_ramp(std::mt19937_64& rng) {
  switch (rng() % 4) {
    case 0: {  // CiA 402 profile position / velocity
      const int64_t accel = pick(rng, 1'000, 3'000'000), decel = pick(rng, 1'000, 3'000'000);
      return profile_ramp(pick(rng, 10, 60'000), accel, decel,
                          profile_levels_per_hz(std::max(accel, decel)));
    }
    case 1:  // HP PROFILE FREQ in Hz and mHz/s
      return frequency_ramp(pick(rng, 0, 50), pick(rng, 60, 20'000),
                            pick(rng, 1'000, 2'000'000'000));
    case 2:  // Horner %AQ3..%AQ7
      return horner_ramp(pick(rng, 20, 2'000), pick(rng, 1, 100), pick(rng, 200, 8'191),
                         pick(rng, 1, 2'000), pick(rng, 0, 2'000));
    default: {  // CSP's segment: n steps evenly over a SYNC cycle, no ramp
      RampSpec r;
      r.phase_per_step = pick(rng, 1'000, 20'000);
      r.base_level = r.run_level = r.min_creep_level = pick(rng, 1, r.phase_per_step);
      r.accel_ticks_per_level = r.decel_ticks_per_level = Rational{1, 1};
      return r;
    }
  }
}

// One change of the motion at `at` (between the last step and the next).
void change(StepGenerator& g, const RampSpec& r, Tick at, std::mt19937_64& rng) {
  switch (rng() % 7) {
    case 0: g.stop(at); break;
    case 1:
      g.stop(at, Rational{r.decel_ticks_per_level.num, 2 * r.decel_ticks_per_level.den});
      break;
    case 2: g.change_velocity(at, pick(rng, 1, r.run_level)); break;
    case 3: g.retarget(at, pick(rng, 0, 2'000), r); break;
    case 4: g.set_level(at, pick(rng, 1, r.run_level)); break;
    case 5: g.halt(at); break;
    default: break;  // none
  }
}

struct Script {
  RampSpec ramp;
  std::optional<int64_t> distance;
  uint64_t seed = 0;
};

// The move's steps; with `peek`, each peek is checked against the step next() takes.
std::vector<Tick> run(const Script& script, bool peek) {
  std::mt19937_64 rng(script.seed);
  StepGenerator g;
  g.start(script.ramp, 0, rng() % 2 ? 1 : -1, script.distance);
  std::vector<Tick> out;
  int64_t change_at = pick(rng, 1, 300);
  Step s;
  while (out.size() < 6'000) {
    const std::optional<Tick> peeked = peek ? g.peek() : std::nullopt;
    const bool stepped = g.next(s);
    if (peek) {
      EXPECT_EQ(peeked.has_value(), stepped) << "step " << out.size();
      if (peeked && stepped) {
        EXPECT_EQ(*peeked, s.time) << "step " << out.size();
      }
      if (::testing::Test::HasFailure()) return out;
    }
    if (!stepped) break;
    out.push_back(s.time);
    if (static_cast<int64_t>(out.size()) == change_at) {
      change_at += pick(rng, 1, 300);
      // At the step or a few ticks after it, before the next one falls (a copy finds it).
      StepGenerator ahead = g;
      Step after;
      const Tick room = ahead.next(after) ? after.time - s.time - 1 : 3;
      const Tick at = s.time + (rng() % 2 ? 0 : pick(rng, 0, std::min<Tick>(3, room)));
      change(g, script.ramp, at, rng);
    }
  }
  return out;
}

TEST(StepGeneratorPeek, EveryPeekIsTheNextStepOnRandomChangedMoves) {
  std::mt19937_64 rng(1301);
  int64_t steps = 0;
  for (int i = 0; i < 600; ++i) {
    Script script;
    script.ramp = random_ramp(rng);
    if (rng() % 3 != 0) script.distance = pick(rng, 1, 5'000);
    script.seed = rng();
    const std::vector<Tick> peeked = run(script, true);
    ASSERT_FALSE(::testing::Test::HasFailure()) << "move " << i;
    const std::vector<Tick> alone = run(script, false);
    ASSERT_EQ(peeked, alone) << "move " << i;
    steps += static_cast<int64_t>(peeked.size());
  }
  EXPECT_GT(steps, 150'000);  // the moves ran: ramps, runs and creeps alike
}

}  // namespace
}  // namespace stepnode::motion
