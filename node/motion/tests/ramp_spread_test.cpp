// The spread of a ramp grid's residues (ramp_spread.hpp), which the bounded batch trusts
// to prove its steps: every partial sum of the residues from every start stays within it,
// and some reach it (it is the least such bound, not a loose one).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "node/motion/ramp_spread.hpp"

namespace stepnode::motion {
namespace {

int64_t pick(std::mt19937_64& rng, int64_t lo, int64_t hi) {
  return lo + static_cast<int64_t>(rng() % static_cast<uint64_t>(hi - lo + 1));
}

TEST(RampSpread, EveryPartialSumOfTheResiduesStaysWithinItAndOneReachesIt) {
  std::mt19937_64 rng(20261207);
  for (int grid = 0; grid < 400; ++grid) {
    // A period up to the longest counted, with a common factor now and then.
    const int64_t g = rng() % 3 == 0 ? pick(rng, 2, 50) : 1;
    const int64_t period = pick(rng, 1, grid % 4 == 0 ? 4096 : 300);
    int64_t step = pick(rng, 0, period - 1);
    while (std::gcd(step, period) != 1) step = (step + 1) % period;  // period 1: step 0
    const int64_t rho = step * g, den = period * g;
    const CarrySpread s = carry_spread(rho, den);
    ASSERT_GE(s.phase, 0) << rho << "/" << den;
    EXPECT_EQ(s.g, std::gcd(rho, den));
    double widest = 0;
    for (int start = 0; start < 6; ++start) {
      const int64_t rem = pick(rng, 0, den - 1);
      const double mu = static_cast<double>(rem % s.g) + static_cast<double>(den - s.g) / 2;
      double sum = 0;
      for (int64_t j = 0; j < 2 * period + 3; ++j) {
        sum += static_cast<double>((rem + j * rho) % den);
        const double off =
            std::abs(sum - static_cast<double>(j + 1) * mu) / static_cast<double>(den);
        ASSERT_LE(off, s.phase + 1e-9) << rho << "/" << den << " rem " << rem << " J " << j + 1;
        widest = std::max(widest, off);
      }
    }
    // From every start of a short period: the widest partial sum is the bound itself.
    if (period <= 300) {
      const int64_t rem = rng() % static_cast<uint64_t>(s.g);
      const double mu = static_cast<double>(rem) + static_cast<double>(den - s.g) / 2;
      double reach = 0;
      for (int64_t from = 0; from < period; ++from) {
        double sum = 0;
        for (int64_t j = 0; j < period; ++j) {
          sum += static_cast<double>((rem + (from + j) * rho) % den) - mu;
          reach = std::max(reach, std::abs(sum) / static_cast<double>(den));
        }
      }
      EXPECT_NEAR(reach, s.phase, 1e-9) << rho << "/" << den;
    }
    EXPECT_LE(widest, s.phase + 1e-9);
  }
}

TEST(RampSpread, APeriodBeyondTheLongestCountedHasNone) {
  EXPECT_LT(carry_spread(1, kSpreadPeriodMost + 1).phase, 0);
  EXPECT_GE(carry_spread(2, 2 * kSpreadPeriodMost).phase, 0);  // period kSpreadPeriodMost
  // The longest period, against the residues' sums over two periods from a few starts.
  const int64_t den = kSpreadPeriodMost, rho = 27'183;
  const CarrySpread s = carry_spread(rho, den);
  for (const int64_t rem : {int64_t{0}, int64_t{1}, den / 3, den - 1}) {
    double sum = 0;
    for (int64_t j = 0; j < 2 * den; ++j) {
      sum += static_cast<double>((rem + j * rho) % den) - static_cast<double>(den - 1) / 2;
      ASSERT_LE(std::abs(sum) / static_cast<double>(den), s.phase + 1e-9) << rem << " " << j;
    }
  }
  EXPECT_EQ(carry_spread(0, 7).phase, 0);  // a whole Z: one residue
}

}  // namespace
}  // namespace stepnode::motion
