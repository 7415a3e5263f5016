// The lengths of a ramp's velocity intervals without a division per level (issue 13).
// With Z = num/den ticks per level, interval k of a ramp ends floor((k+1)·num/den) ticks
// after the ramp began (Bresenham over a fractional Z), so its length is
//   floor((k+1)·num/den) − floor(k·num/den).
// With num = q·den + rho and (k+1)·num = F·den + rem (0 <= rem < den), the next one is
//   floor((k+2)·num/den) − F = q + floor((rem + rho)/den), and rem + rho < 2·den,
// so each next length is q or q + 1 and the remainder moves by rho: two additions and a
// compare instead of two 128-bit divisions. Any other index or Z starts it again with the
// divisions, so every answer is the formula's, whatever order the generator asks in.
#pragma once
#include <cstdint>

#include "node/motion/ramp.hpp"
#include "node/motion/ramp_step.hpp"
#include "node/motion/timebase.hpp"

namespace stepnode::motion {

class IntervalCursor {
 public:
  // floor((k+1)·z.num/z.den) − floor(k·z.num/z.den); z.num >= 0, z.den > 0, k >= 0.
  Tick length(Rational z, int64_t k) {
    if (k == k_ + 1 && z.num == z_.num && z.den == z_.den) return next_length();
    return seek(z, k);
  }
  // Whether the last length given was that of interval k of z.
  bool at(Rational z, int64_t k) const { return k == k_ && z.num == z_.num && z.den == z_.den; }
  // The length of the interval after the last one given (same Z).
  Tick next_length() {
    ++k_;
    return grid().next_length(rem_);
  }
  // After a length of 0 (a slope steeper than one level per tick: Z < 1), how many of the
  // next intervals are 0 long too (their levels come at the same tick): the remainder may
  // grow by rho that many times before it carries.
  int64_t zeros_after() const { return q_ > 0 || rho_ == 0 ? 0 : (z_.den - 1 - rem_) / rho_; }
  // Whether Z < 1 (q = 0): runs of 0-long intervals, several levels at one tick.
  bool steep() const { return q_ == 0 && rho_ > 0; }
  // The lengths as q, q + 1 (ramp_step.hpp's walk) and the remainder after the last one.
  IntervalGrid grid() const { return {q_, rho_, z_.den}; }
  // Z = q + rho/den in a double, for the solve's guess (solve_to_step).
  double z() const { return z_real_; }
  int64_t remainder() const { return rem_; }
  // Passes `n` intervals a walk went through (walk_to_step), `rem` the remainder after them.
  void advance(int64_t n, int64_t rem) {
    k_ += n;
    rem_ = rem;
  }
  // Passes `m` (<= zeros_after()) intervals of length 0.
  void skip_zeros(int64_t m) {
    rem_ += m * rho_;
    k_ += m;
  }

 private:
  Tick seek(Rational z, int64_t k) {
    const __int128 n = z.num;  // k * num can pass 2^63 for long, fine-grained ramps
    const __int128 end = (k + 1) * n, begin = k * n;
    z_ = z;
    k_ = k;
    q_ = z.num / z.den;
    rho_ = z.num % z.den;
    rem_ = static_cast<int64_t>(end % z.den);
    z_real_ = static_cast<double>(q_) + static_cast<double>(rho_) / static_cast<double>(z.den);
    return static_cast<Tick>(end / z.den - begin / z.den);
  }

  Rational z_{0, 0};  // den 0: no Z yet, the first call seeks
  int64_t k_ = -2;
  int64_t q_ = 0, rho_ = 0, rem_ = 0;
  double z_real_ = 0;
};

}  // namespace stepnode::motion
