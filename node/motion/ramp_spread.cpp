// The spread of a ramp grid's residues (ramp_spread.hpp), counted over one period.
#include "node/motion/ramp_spread.hpp"

#include <algorithm>
#include <numeric>

namespace stepnode::motion {

CarrySpread carry_spread(int64_t rho, int64_t den) {
  CarrySpread out;
  out.rho = rho, out.den = den;
  out.g = std::gcd(rho, den);  // rho 0: den, one residue
  const int64_t period = den / out.g, step = rho / out.g;
  if (period > kSpreadPeriodMost) return out;
  // 2·T(k), to keep (P - 1)/2 whole.
  int64_t s = 0, t2 = 0, high = 0, low = 0;
  for (int64_t k = 0; k < period; ++k) {
    t2 += 2 * s - (period - 1);
    high = std::max(high, t2);
    low = std::min(low, t2);
    s += step;
    if (s >= period) s -= period;
  }
  out.phase = static_cast<double>(high - low) / 2 / static_cast<double>(period);
  return out;
}

}  // namespace stepnode::motion
