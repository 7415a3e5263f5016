// What the ramp-walk tests share (ramp_step_test.cpp, ramp_step_steep_test.cpp): a random
// pick and the comparison of two walks' every field.
#pragma once
#include <gtest/gtest.h>

#include <cstdint>
#include <random>

#include "node/motion/ramp_step.hpp"

namespace stepnode::motion::walk_check {

// Uniform in lo..hi.
inline int64_t pick(std::mt19937_64& rng, int64_t lo, int64_t hi) {
  return lo + static_cast<int64_t>(rng() % static_cast<uint64_t>(hi - lo + 1));
}

// A walk to solve on one of the profiles' grids (Z of 1 to 200 ticks, a fraction of any
// size), a level up to 2^19 and a step up to 2^22 phase units: solves_in_64() holds, as
// where the generator solves. `after` the phase to come after the start's interval; a
// walk with after <= 0 or no room is the caller's to skip.
struct ProfileWalk {
  IntervalGrid g;
  int64_t dir = 1, room = 0, after = 0;
  RampWalk start;
};
inline ProfileWalk random_profile_walk(std::mt19937_64& rng) {
  ProfileWalk r;
  const int64_t den = pick(rng, 1, 1'000'000);
  const int64_t num = pick(rng, den, 200 * den);
  r.g = IntervalGrid{num / den, num % den, den};
  r.dir = rng() % 2 ? 1 : -1;
  r.start.level = pick(rng, 1, int64_t{1} << pick(rng, 0, 19));
  r.start.t = pick(rng, 0, 1'000'000);
  r.start.end = r.start.t + pick(rng, 0, r.g.q + 1);
  r.start.left = pick(rng, 1, int64_t{1} << pick(rng, 0, 22));
  r.start.rem = pick(rng, 0, den - 1);
  r.room = r.dir > 0 ? pick(rng, 1, 1'000'000) : pick(rng, 0, r.start.level - 1);
  r.after = r.start.left - r.start.level * (r.start.end - r.start.t);
  return r;
}

// The reference walk's state against the solve's, every field.
inline void expect_same(const RampWalk& walked, const RampWalk& solved) {
  EXPECT_EQ(walked.t, solved.t);
  EXPECT_EQ(walked.end, solved.end);
  EXPECT_EQ(walked.level, solved.level);
  EXPECT_EQ(walked.left, solved.left);
  EXPECT_EQ(walked.passed, solved.passed);
  EXPECT_EQ(walked.rem, solved.rem);
}

}  // namespace stepnode::motion::walk_check
