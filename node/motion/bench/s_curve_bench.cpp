// Instructions per step of the jerk-limited profile (6086h = 3): run under
// `valgrind --tool=callgrind build/node/s_curve_bench [moves]`, divide the total by the steps
// it prints. Each move: 20 000 steps at up to 10 000 steps/s, 100 000 steps/s^2, 1e6 steps/s^3.
#include <cstdio>
#include <cstdlib>

#include "node/motion/ramp.hpp"
#include "node/motion/step_generator.hpp"

int main(int argc, char** argv) {
  using namespace stepnode::motion;
  const int moves = argc > 1 ? std::atoi(argv[1]) : 50;
  RampSpec r = profile_ramp(10'000, 100'000, 100'000, profile_levels_per_hz(100'000));
  r.s_curve = true;
  for (uint32_t& j : r.jerk) j = 1'000'000;
  StepGenerator g;
  int64_t steps = 0;
  Tick t = 0, sum = 0;
  for (int m = 0; m < moves; ++m) {
    g.start(r, t, m % 2 ? -1 : +1, 20'000);
    Step s;
    while (g.peek() && g.next(s)) {
      ++steps;
      sum += s.time;
      t = s.time;
    }
  }
  std::printf("%lld steps in %d moves (checksum %lld)\n", static_cast<long long>(steps), moves,
              static_cast<long long>(sum % 1000003));
  return 0;
}
