// solve_to_step's first guess (ramp_step.hpp): the generator hands it the levels the step
// before spanned (StepGenerator::peek_solved). Whatever the hint, right, off by a few, far
// off, beyond kHintedMost or too large for its 64-bit bound, the answer must be the
// level-by-level walk's, every field; the hint only decides how many exact evaluations it
// takes.
#include <gtest/gtest.h>

#include <random>

#include "node/motion/ramp_step.hpp"
#include "node/motion/tests/ramp_walk_check.hpp"

namespace stepnode::motion {
namespace {

using walk_check::expect_same;
using walk_check::pick;

// A hint near the walk's answer m (the common case: the next step of a ramp), or anywhere.
int64_t pick_hint(std::mt19937_64& rng, int64_t m) {
  switch (rng() % 6) {
    case 0: return m;
    case 1: return std::max<int64_t>(1, m - pick(rng, 1, 3));
    case 2: return m + pick(rng, 1, 3);
    case 3: return pick(rng, 1, kHintedMost);
    case 4: return kHintedMost + pick(rng, 1, 100);  // beyond: the root's guess
    default: return pick(rng, 0, 3);                 // 0: none
  }
}

TEST(RampWalkHint, AnyHintGivesTheLevelWalksAnswer) {
  // The profiles' grids (walk_check::random_profile_walk): solves_in_64() holds, as where
  // the generator solves.
  std::mt19937_64 rng(44714);
  int spanning = 0, short_of_it = 0;
  for (int i = 0; i < 200'000 && !::testing::Test::HasFailure(); ++i) {
    const walk_check::ProfileWalk r = walk_check::random_profile_walk(rng);
    const IntervalGrid& g = r.g;
    const RampWalk& start = r.start;
    const int64_t dir = r.dir, room = r.room, after = r.after;
    const double z =
        static_cast<double>(g.q) + static_cast<double>(g.rho) / static_cast<double>(g.den);
    if (after <= 0 || room < 1) continue;  // the step in this interval, or no room: the caller's
    ASSERT_TRUE(solves_in_64(after, start.level, g));
    RampWalk walked = start;
    const bool found = walk_levels(walked, g, dir, room);
    const int64_t m = walked.passed;
    RampWalk solved = start;
    const int64_t hint = pick_hint(rng, m);
    EXPECT_EQ(found, solve_to_step(solved, g, z, dir, room, after, hint))
        << "q " << g.q << " rho " << g.rho << " den " << g.den << " L " << start.level << " left "
        << start.left << " dir " << dir << " hint " << hint << " m " << m;
    expect_same(walked, solved);
    if (m >= 4) ++spanning;
    if (!found) ++short_of_it;
  }
  EXPECT_GT(spanning, 20'000);    // steps several levels on, where the generator solves
  EXPECT_GT(short_of_it, 1'000);  // and the room's end before the step
}

}  // namespace
}  // namespace stepnode::motion
