// What a continuous-slope ramp step costs in the exact solve alone (issue 13, the floor
// under StepGenerator's ramp steps): a ramp up from rest walked step to step by
// solve_to_step (ramp_step.hpp) with the last step's span as its guess, the state in
// locals, none of the generator's peek set-up, hand-over (Ahead) or step bookkeeping.
// The first ramp's every step tick is checked against StepGenerator's own for the same
// move (the others start a few ticks later), so the figure is for the same steps. For callgrind:
//   valgrind --tool=callgrind --toggle-collect='*solve_ramps*'
//   build/node/ramp_solve_floor_bench hp|cia402|slow [moves]
// then Ir (the "Collected" total) / steps.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "node/motion/bench/bench_ramps.hpp"
#include "node/motion/ramp.hpp"
#include "node/motion/ramp_intervals.hpp"
#include "node/motion/ramp_step.hpp"
#include "node/motion/step_generator.hpp"

namespace {

using namespace stepnode::motion;

// The ramps of ramp_cost_bench: to their run level from rest.
bool ramp_of(const char* name, RampSpec& r) {
  if (std::strcmp(name, "hp") == 0) {
    r = bench::hp_ramp();
  } else if (std::strcmp(name, "cia402") == 0) {
    r = bench::cia402_ramp();
  } else if (std::strcmp(name, "slow") == 0) {
    r = bench::slow_ramp();
  } else {
    return false;
  }
  return true;
}

struct Totals {
  int64_t steps = 0;
  Tick checksum = 0;
};

// The steps of each ramp up to its run level (those before the step that would fall
// beyond the run level's interval), into `ticks` if given.
[[gnu::always_inline]] inline Totals ramps_up(const RampSpec& r, int moves,
                                              std::vector<Tick>* ticks) {
  const Rational z = r.accel_ticks_per_level;
  const int64_t d = r.phase_per_step, top = r.run_level;
  Totals out;
  for (int move = 0; move < moves; ++move) {
    IntervalCursor cursor;
    const Tick start = out.checksum % 1'000;  // moves differ, as the generator's do
    RampWalk w{start, start + cursor.length(z, 0), r.base_level + 1, 0, 0, cursor.remainder()};
    const IntervalGrid g = cursor.grid();
    int64_t acc = 0, hint = 0;
    for (;;) {
      const int64_t left = d - acc, phase = w.level * (w.end - w.t);
      if (phase < left) {  // beyond this interval: solved
        const int64_t level = w.level;
        if (level >= top) break;                                  // the run level's interval
        if (!solves_in_64(left - phase, level, g)) std::abort();  // not on these grids
        if (!solve_to_step(w, g, cursor.z(), +1, top - level, left - phase, hint)) break;
        hint = w.passed;
        w.passed = 0;
      } else {
        w.left = left;
      }
      const Tick at = w.t + (w.left + w.level - 1) / w.level;
      acc = w.level * (at - w.t) - w.left;
      w.t = at;
      ++out.steps;
      out.checksum += at;
      if (ticks) ticks->push_back(at);
    }
  }
  return out;
}

// Measured (callgrind's --toggle-collect names it): without the ticks' vector.
[[gnu::noinline]] Totals solve_ramps(const RampSpec& r, int moves) {
  return ramps_up(r, moves, nullptr);
}

// StepGenerator's first `n` steps of the same move from `start`.
std::vector<Tick> generator_ticks(const RampSpec& r, Tick start, size_t n) {
  StepGenerator gen;
  gen.start(r, start, +1, std::nullopt);
  std::vector<Tick> out;
  Step s;
  while (out.size() < n && gen.peek() && gen.next(s)) out.push_back(s.time);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  RampSpec r;
  if (argc < 2 || !ramp_of(argv[1], r)) {
    std::fprintf(stderr, "usage: ramp_solve_floor_bench hp|cia402|slow [moves]\n");
    return 2;
  }
  const int moves = argc > 2 ? std::atoi(argv[2]) : 20;
  std::vector<Tick> solved;
  ramps_up(r, 1, &solved);
  if (generator_ticks(r, 0, solved.size()) != solved) {
    std::fprintf(stderr, "%s: the solve's steps differ from StepGenerator's\n", argv[1]);
    return 1;
  }
  const Totals t = solve_ramps(r, moves);
  std::printf(
      "%s: %lld steps in %d ramps up (the first checked tick by tick against "
      "StepGenerator's, %zu steps; checksum %lld)\n",
      argv[1], static_cast<long long>(t.steps), moves, solved.size(),
      static_cast<long long>(t.checksum % 1'000'003));
  return 0;
}
