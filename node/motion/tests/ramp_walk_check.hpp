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
