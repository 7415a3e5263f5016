// Pulse-engine figures (Google Benchmark). Build and run:
//   cmake --build build --target motion_bench && build/node/motion_bench
//   --benchmark_counters_tabular=true
//
// BM_StepsPerSecond: steps the StepGenerator computes per second of CPU time on one core
//   (counter steps_per_s), for the 245,730 steps/s profile (AQ3=20, AQ4=1, AQ5=8191,
//   AQ6=100): a 2,000,000-step move (mostly running), and its ramps alone (a jog stopped as
//   soon as it runs: a velocity level change every 61 ticks).
// BM_MaxDeviation_QuantisedStaircase: the largest |engine step time - ideal| in ns, where the
//   ideal is the module's own quantised ramp (one velocity level per Z_A / Z_D ticks, B1.3.1)
//   with every step at the exact, unrounded instant its phase reaches k*D. The engine puts
//   each step on the next 4.9152 MHz tick, so this must stay below one tick (203.45 ns).
// BM_MaxDeviation_ContinuousTrapezoid: the same against the closed-form continuous
//   trapezoid: velocity rising linearly at Rate_A from Vel_B to Vel_R, running, falling at
//   Rate_D to Vel_B, covering exactly TOTAL pulses (a true triangle when the ramps do not
//   fit); step k at the instant the integral reaches k (the quadratic inverted per phase).
//   The module's quantised ramp differs from it by design: each ramp interval runs at the
//   level it rises to (base+1 first, B1.3.7), so the staircase is half a level ahead of the
//   line. max_dev_pulses gives the same gap as a position: |k - ideal position at the
//   engine's time of step k|; the time gap is largest where the velocity is lowest. For
//   triangular moves the engine also holds STPCALC's peak (B1.3.6) rather than
//   turning at once, which shows here as a large deviation.
// Every iteration is bounded: at most 2,000,000 steps.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "node/motion/step_generator.hpp"
#include "node/motion/stpcalc.hpp"

using namespace stepnode::motion;

namespace {

constexpr double kTickNs = 1e9 / static_cast<double>(kClockHz);  // 203.45 ns

StpcalcInput input_of(const benchmark::State& state) {
  return StpcalcInput{state.range(0), state.range(1), state.range(2),
                      state.range(3), state.range(4), state.range(5)};
}

std::vector<Tick> engine_steps(const StpcalcInput& in) {
  StepGenerator g;
  g.start(horner_ramp(in.aq3, in.aq4, in.aq5, in.aq6, in.aq7), 0, +1, *in.total);
  std::vector<Tick> times;
  times.reserve(static_cast<size_t>(*in.total));
  Step s;
  while (g.next(s)) times.push_back(s.time);
  return times;
}

// --- (a) throughput -------------------------------------------------------------------

void BM_StepsPerSecond_Move(benchmark::State& state) {
  RampSpec ramp = horner_ramp(20, 1, 8191, 100, 0);  // 245,730 steps/s
  int64_t steps = 0;
  for (auto _ : state) {
    StepGenerator g;
    g.start(ramp, 0, +1, 2'000'000);
    Step s;
    while (g.next(s)) ++steps;
    benchmark::DoNotOptimize(s.time);
  }
  state.counters["steps_per_s"] =
      benchmark::Counter(static_cast<double>(steps), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_StepsPerSecond_Move)->Unit(benchmark::kMillisecond);

void BM_StepsPerSecond_RampsOnly(benchmark::State& state) {
  RampSpec ramp = horner_ramp(20, 1, 8191, 100, 0);
  int64_t steps = 0;
  for (auto _ : state) {
    StepGenerator g;
    g.start(ramp, 0, +1, std::nullopt);
    Step s;
    while (g.next(s)) {
      ++steps;
      if (g.phase() == MotionPhase::Running) g.stop(s.time);
    }
    benchmark::DoNotOptimize(s.time);
  }
  state.counters["steps_per_s"] =
      benchmark::Counter(static_cast<double>(steps), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_StepsPerSecond_RampsOnly)->Unit(benchmark::kMillisecond);

// --- (b) deviations ---------------------------------------------------------------------

struct Deviation {
  double max_ticks = 0;
  int64_t worst_step = 0;  // 1-based
  double max_pulses = 0;   // |k - ideal position at the engine's time of step k|
  void add(int64_t k, double engine_ticks, double ideal_ticks) {
    double dev = std::fabs(engine_ticks - ideal_ticks);
    if (dev > max_ticks) max_ticks = dev, worst_step = k;
  }
};

// The module's quantised ramp, computed here from the registers alone (not from the
// engine's marks): levels base+1..peak for Z_A ticks each from tick 0; the peak by the
// STPCALC triangle rule (B1.3.6/B1.3.8: base + R_T*(run-base), whole levels); running at
// the peak until the first tick on which the phase still to come is no more than the ramp
// down adds (the module's counters act on clock ticks); levels peak..base+1 for Z_D ticks
// each; then the base velocity. Step k at the exact instant the phase reaches k*D.
Deviation staircase_deviation(const StpcalcInput& in, const std::vector<Tick>& engine) {
  const StpcalcResult s = stpcalc(in);
  const double d = 8192.0 * static_cast<double>(in.aq3);
  const int64_t base = in.aq4, run = in.aq5, za = s.z_a, zd = s.z_d;
  auto level_sum = [&](int64_t level) {  // sum(base+1 .. level)
    return static_cast<double>(level - base) * static_cast<double>(level + base + 1) / 2;
  };
  const double total_phase = static_cast<double>(*in.total) * d;
  const double both = static_cast<double>(za + zd) * level_sum(run);
  const int64_t peak = total_phase >= both
                           ? run
                           : base + static_cast<int64_t>(std::floor(
                                        total_phase * static_cast<double>(run - base) / both));

  struct Segment {
    double t0, t1, level;
  };
  std::vector<Segment> segs;
  double t = 0;
  for (int64_t l = base + 1; l <= peak; ++l, t += static_cast<double>(za))
    segs.push_back({t, t + static_cast<double>(za), double(l)});
  const double accel_phase = static_cast<double>(za) * level_sum(peak);
  const double decel_phase = static_cast<double>(zd) * level_sum(peak);
  if (peak > base) {
    double run_ticks = std::max(
        0.0, std::ceil((total_phase - decel_phase - accel_phase) / static_cast<double>(peak)));
    segs.push_back({t, t + run_ticks, double(peak)});
    t += run_ticks;
    for (int64_t l = peak; l > base; --l, t += static_cast<double>(zd))
      segs.push_back({t, t + static_cast<double>(zd), double(l)});
  }
  segs.push_back({t, 1e300, double(std::max<int64_t>(base, 1))});

  Deviation dev;
  double phase = 0;
  size_t k = 0;
  for (const Segment& sg : segs) {
    double end_phase = phase + sg.level * (sg.t1 - sg.t0);
    while (k < engine.size() && static_cast<double>(k + 1) * d <= end_phase) {
      double ideal = sg.t0 + (static_cast<double>(k + 1) * d - phase) / sg.level;
      dev.add(static_cast<int64_t>(k + 1), static_cast<double>(engine[k]), ideal);
      ++k;
    }
    phase = end_phase;
    if (k == engine.size()) break;
  }
  return dev;
}

// The continuous trapezoid (or triangle) with STPCALC's rates and velocities over exactly
// TOTAL pulses, inverted in closed form per phase. Times in ticks.
Deviation trapezoid_deviation(const StpcalcInput& in, const std::vector<Tick>& engine) {
  const StpcalcResult s = stpcalc(in);
  const double vb = s.base_velocity, a = s.acceleration_rate, dr = s.deceleration_rate;
  const double total = static_cast<double>(*in.total);
  double vc = s.running_velocity;
  auto ramp_pulses = [&](double v, double rate) { return (v * v - vb * vb) / (2 * rate); };
  if (ramp_pulses(vc, a) + ramp_pulses(vc, dr) > total)
    vc = std::sqrt(vb * vb + total / (1 / (2 * a) + 1 / (2 * dr)));  // a true triangle
  const double ta = (vc - vb) / a, xa = ramp_pulses(vc, a), xd = ramp_pulses(vc, dr);
  const double xr = std::max(0.0, total - xa - xd), tr = xr / vc, td = (vc - vb) / dr;
  auto position = [&](double t) {  // the ideal's integral at t seconds
    if (t <= ta) return vb * t + a * t * t / 2;
    if (t <= ta + tr) return xa + vc * (t - ta);
    if (t <= ta + tr + td) {
      double u = t - ta - tr;
      return xa + xr + vc * u - dr * u * u / 2;
    }
    return total + vb * (t - ta - tr - td);
  };
  Deviation dev;
  for (size_t i = 0; i < engine.size(); ++i) {
    const double x = static_cast<double>(i + 1);
    double secs;
    if (x <= xa) {
      secs = 2 * x / (vb + std::sqrt(vb * vb + 2 * a * x));  // stable root of vb t + a t^2/2 = x
    } else if (x <= xa + xr) {
      secs = ta + (x - xa) / vc;
    } else {
      double y = std::min(x - xa - xr, xd);
      secs = ta + tr + 2 * y / (vc + std::sqrt(std::max(0.0, vc * vc - 2 * dr * y)));
    }
    dev.add(static_cast<int64_t>(i + 1), static_cast<double>(engine[i]),
            secs * static_cast<double>(kClockHz));
    dev.max_pulses = std::max(dev.max_pulses,
                              std::fabs(x - position(static_cast<double>(engine[i]) / kClockHz)));
  }
  return dev;
}

void report(benchmark::State& state, const Deviation& dev) {
  state.counters["max_dev_ns"] = dev.max_ticks * kTickNs;
  state.counters["max_dev_ticks"] = dev.max_ticks;
  state.counters["worst_step"] = static_cast<double>(dev.worst_step);
  if (dev.max_pulses > 0) state.counters["max_dev_pulses"] = dev.max_pulses;
}

void BM_MaxDeviation_QuantisedStaircase(benchmark::State& state) {
  const StpcalcInput in = input_of(state);
  Deviation dev;
  for (auto _ : state) dev = staircase_deviation(in, engine_steps(in));
  report(state, dev);
}

void BM_MaxDeviation_ContinuousTrapezoid(benchmark::State& state) {
  const StpcalcInput in = input_of(state);
  Deviation dev;
  for (auto _ : state) dev = trapezoid_deviation(in, engine_steps(in));
  report(state, dev);
}

void profiles(benchmark::internal::Benchmark* b) {
  b->ArgNames({"total", "aq3", "aq4", "aq5", "aq6", "aq7"});
  b->Args({2'000'000, 20, 1, 8191, 100, 0});   // 245,730 steps/s, 12,491-pulse ramps
  b->Args({200'000, 60, 10, 8000, 500, 250});  // 80,000 steps/s, decel twice as steep
  b->Args({20'000, 600, 100, 1000, 500, 0});   // 1,000 steps/s from 100
  b->Args({10'000, 1200, 2, 8191, 2000, 0});   // 4,095.5 steps/s from 1 step/s
  b->Args({300, 600, 100, 1000, 500, 250});    // triangular (STPCALC's peak 753.8 steps/s)
  b->Iterations(1)->Unit(benchmark::kMillisecond);
}
BENCHMARK(BM_MaxDeviation_QuantisedStaircase)->Apply(profiles);
BENCHMARK(BM_MaxDeviation_ContinuousTrapezoid)->Apply(profiles);

}  // namespace

BENCHMARK_MAIN();
