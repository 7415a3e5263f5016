// Instructions per step of each ramp the pulse engine runs (issue 13), a bench program for
// callgrind: it runs `moves` moves of one kind through StepGenerator (peek, then next, as
// AxisCore does) inside run_moves(), and prints the steps it took.
//   valgrind --tool=callgrind --toggle-collect='*run_moves*'
//   build/node/ramp_cost_bench <kind> [moves] [ramps|stop-early|stop-early-walked [ticks]]
// then Ir (the "Collected" total) / steps. `ramps` stops each move as soon as it runs at its
// velocity (a jog stopped at the top: the ramps alone, no cruise); `stop-early` see
// kStopAfter (then Ir / moves: the cost of a stop between two steps).
// Kinds (one trapezoid for the last three: 0 -> 10,000 steps/s at 100,000 steps/s^2, 20,000
// steps, so the ramps are 500 steps each way):
//   horner  SPM30 %AQ3..7 = 20 1 8191 100 0 (245,730 steps/s, 100 ms ramps), 40,000 steps
//   hp      HP 44714A PROFILE FREQ 0 10000 100000 (Hz, Hz/s), MOVE 20000
//   cia402  CiA 402 PP: 6081h 10,000, 6083h = 6084h 100,000, 6086h = 0
//   scurve  the same with 6086h = 3 and every 60A4h jerk 1,000,000 steps/s^3
//   slow    CiA 402 PP at 1,000 steps/s^2 to 1,000 steps/s, 2,000 steps (the finest grid,
//           64 levels per step/s: the first steps span thousands of levels)
//   steep   CiA 402 PP at 10,000,000 steps/s^2 to 10,000 steps/s, 4,000 steps (Z = 0.49
//           ticks per level: several levels at one tick, the first step 2,200 ticks away)
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "node/motion/bench/bench_ramps.hpp"
#include "node/motion/ramp.hpp"
#include "node/motion/step_generator.hpp"

namespace {

using namespace stepnode::motion;

struct Kind {
  RampSpec ramp;
  int64_t steps = 0;
};

bool kind_of(const char* name, Kind& k) {
  if (std::strcmp(name, "horner") == 0) {
    k = {horner_ramp(20, 1, 8191, 100, 0), 40'000};
  } else if (std::strcmp(name, "hp") == 0) {
    k = {bench::hp_ramp(), 20'000};
  } else if (std::strcmp(name, "cia402") == 0 || std::strcmp(name, "scurve") == 0) {
    k = {bench::cia402_ramp(), 20'000};
    if (name[0] == 's') {
      k.ramp.s_curve = true;
      for (uint32_t& j : k.ramp.jerk) j = 1'000'000;
    }
  } else if (std::strcmp(name, "slow") == 0) {
    k = {bench::slow_ramp(), 2'000};
  } else if (std::strcmp(name, "steep") == 0) {
    const int64_t a = 10'000'000;
    k = {profile_ramp(10'000, a, a, profile_levels_per_hz(a)), 4'000};
  } else {
    return false;
  }
  return true;
}

// `stop-early`: each move stopped this many ticks after its start (407 us; at 10^7
// steps/s^2 before its first step, 2,200 ticks from rest: a stop between two steps), or
// after the ticks a fifth argument gives (`slow` 300000: between its first two steps, at
// levels 2,862 and 4,048, a level every 77 ticks). `stop-early-walked`: the same with
// every ramp interval walked, nothing solved.
constexpr Tick kStopAfter = 2'000;

struct Totals {
  int64_t steps = 0;
  Tick checksum = 0;
};

// Not inlined: callgrind's --toggle-collect names it.
enum class Mode { Whole, Ramps, StopEarly, StopEarlyWalked };

[[gnu::noinline]] Totals run_moves(const Kind& k, int moves, Mode mode, Tick stop_after) {
  StepGenerator g;
  g.walk_ramps(mode == Mode::StopEarlyWalked);
  const bool ramps_only = mode == Mode::Ramps;
  Totals out;
  Tick t = 0;
  for (int m = 0; m < moves; ++m) {
    g.start(k.ramp, t, m % 2 ? -1 : +1, k.steps);
    const bool early = mode == Mode::StopEarly || mode == Mode::StopEarlyWalked;
    if (early) g.stop(t + stop_after);
    Step s;
    bool stopped = early;
    while (g.peek() && g.next(s)) {
      ++out.steps;
      out.checksum += s.time;
      t = s.time;
      if (ramps_only && !stopped && g.phase() == MotionPhase::Running) {
        g.stop(s.time);
        stopped = true;
      }
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  Kind k;
  if (argc < 2 || !kind_of(argv[1], k)) {
    std::fprintf(stderr,
                 "usage: ramp_cost_bench horner|hp|cia402|scurve|slow|steep [moves] "
                 "[ramps|stop-early|stop-early-walked [ticks]]\n");
    return 2;
  }
  const int moves = argc > 2 ? std::atoi(argv[2]) : 20;
  const char* how = argc > 3 ? argv[3] : "";
  Mode mode = Mode::Whole;
  if (std::strcmp(how, "ramps") == 0) mode = Mode::Ramps;
  if (std::strcmp(how, "stop-early") == 0) mode = Mode::StopEarly;
  if (std::strcmp(how, "stop-early-walked") == 0) mode = Mode::StopEarlyWalked;
  const Tick stop_after = argc > 4 ? std::atoll(argv[4]) : kStopAfter;
  const Totals t = run_moves(k, moves, mode, stop_after);
  std::printf("%s: %lld steps in %d moves%s%s (checksum %lld)\n", argv[1],
              static_cast<long long>(t.steps), moves, *how != 0 ? ", " : "", how,
              static_cast<long long>(t.checksum % 1'000'003));
  return 0;
}
