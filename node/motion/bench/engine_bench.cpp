// Pulse-engine figures (Google Benchmark):
//   build/node/motion_bench --benchmark_counters_tabular=true
// steps_per_s: steps computed per second on one core for a 245,730 steps/s profile.
// max_dev_staircase_ns: largest deviation of a step time from the exact (unrounded) time of
//   the module's quantised ramp: what the 4.9152 MHz tick rounding costs (< 1 tick, 203 ns).
// max_dev_trapezoid_ns: largest deviation from the closed-form continuous trapezoid with
//   STPCALC's rates and times: the module's velocity staircase by design (not an error).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>

#include "node/motion/step_generator.hpp"
#include "node/motion/stpcalc.hpp"

using namespace stepnode::motion;

namespace {

void BM_StepsPerSecondAtTopRate(benchmark::State& state) {
  RampSpec ramp = horner_ramp(20, 1, 8191, 100, 0);  // 245,730 steps/s
  int64_t steps = 0;
  for (auto _ : state) {
    StepGenerator g;
    g.start(ramp, 0, +1, 2'000'000);
    Step s;
    while (g.next(s)) ++steps;
    benchmark::DoNotOptimize(s.time);
  }
  state.counters["steps_per_s"] = benchmark::Counter(static_cast<double>(steps), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_StepsPerSecondAtTopRate)->Unit(benchmark::kMillisecond);

// Walks the ramp's constant-velocity intervals exactly as the module defines them, in
// floating point without tick rounding, and returns the largest |engine - ideal| in ns.
double staircase_deviation_ns(const RampSpec& ramp, int64_t total) {
  StepGenerator g;
  g.start(ramp, 0, +1, total);
  std::vector<Tick> times;
  Step s;
  while (g.next(s)) times.push_back(s.time);
  const auto& m = g.marks();
  const double d = static_cast<double>(ramp.phase_per_step);
  // Intervals: accel levels base+1..peak (Z_A each), run to decel_start, decel levels
  // peak..base+1 (Z_D each), then base.
  struct Seg { double t0, t1; double level; };
  std::vector<Seg> segs;
  double t = 0;
  double za = static_cast<double>(ramp.accel_ticks_per_level.num) / static_cast<double>(ramp.accel_ticks_per_level.den);
  double zd = static_cast<double>(ramp.decel_ticks_per_level.num) / static_cast<double>(ramp.decel_ticks_per_level.den);
  for (int64_t l = ramp.base_level + 1; l <= m.peak_level; ++l, t += za) segs.push_back({t, t + za, double(l)});
  double dstart = static_cast<double>(m.decel_start);
  if (dstart > t) segs.push_back({t, dstart, double(m.peak_level)}), t = dstart;
  for (int64_t l = m.peak_level; l > ramp.base_level; --l, t += zd) segs.push_back({t, t + zd, double(l)});
  segs.push_back({t, 1e18, double(std::max<int64_t>(ramp.base_level, 1))});
  double phase = 0, worst = 0;
  size_t k = 0;
  for (const Seg& sg : segs) {
    double end_phase = phase + sg.level * (sg.t1 - sg.t0);
    while (k < times.size() && (k + 1) * d <= end_phase) {
      double ideal = sg.t0 + ((k + 1) * d - phase) / sg.level;
      worst = std::max(worst, std::fabs(static_cast<double>(times[k]) - ideal));
      ++k;
    }
    phase = end_phase;
    if (k == times.size()) break;
  }
  return worst * 1e9 / kClockHz;
}

// Deviation from STPCALC's continuous trapezoid: x(t) integrated in closed form per phase.
double trapezoid_deviation_ns(const StpcalcInput& in) {
  StpcalcResult s = stpcalc(in);
  RampSpec ramp = horner_ramp(in.aq3, in.aq4, in.aq5, in.aq6, in.aq7);
  StepGenerator g;
  g.start(ramp, 0, +1, *in.total);
  double vb = s.base_velocity, vr = s.running_velocity, a = s.acceleration_rate, dr = s.deceleration_rate;
  double ta = s.acceleration_time_ms / 1000, tr = s.running_time_ms / 1000;
  double xa = vb * ta + a * ta * ta / 2, xr = xa + vr * tr;
  double worst = 0;
  Step st;
  int64_t n = 0;
  while (g.next(st)) {
    double x = static_cast<double>(++n);
    double ideal;
    if (x <= xa) ideal = (-vb + std::sqrt(vb * vb + 2 * a * x)) / a;
    else if (x <= xr) ideal = ta + (x - xa) / vr;
    else {
      double q = vr * vr - 2 * dr * (x - xr);
      ideal = ta + tr + (vr - std::sqrt(std::max(q, 0.0))) / dr;
    }
    worst = std::max(worst, std::fabs(static_cast<double>(st.time) / kClockHz - ideal));
  }
  return worst * 1e9;
}

void BM_Deviation(benchmark::State& state) {
  StpcalcInput in{state.range(0), state.range(1), state.range(2), state.range(3), state.range(4), 0};
  double stair = 0, trap = 0;
  for (auto _ : state) {
    stair = staircase_deviation_ns(horner_ramp(in.aq3, in.aq4, in.aq5, in.aq6, 0), *in.total);
    trap = trapezoid_deviation_ns(in);
  }
  state.counters["max_dev_staircase_ns"] = stair;
  state.counters["max_dev_trapezoid_ns"] = trap;
}
BENCHMARK(BM_Deviation)
    ->Args({2'000'000, 20, 1, 8191, 100})   // 245,730 steps/s
    ->Args({200'000, 60, 10, 8000, 500})    // 80,000 steps/s
    ->Args({20'000, 600, 100, 1000, 500})   // 1,000 steps/s
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
