// CSP step-time error against the ideal interpolated trajectory (a bench program that prints
// figures, not a test): a master's set-points at 1 kHz and 100 Hz SYNC, with and without
// SYNC jitter; each step's tick against the instant the drive's linear interpolation
// (set-point k reached one cycle after SYNC k, at a constant rate) reaches its position.
//   build/node/csp_bench
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "node/profiles/cia402/drive.hpp"
#include "node/sim/machine.hpp"

namespace {

using stepnode::motion::kClockHz;
using stepnode::motion::Tick;

struct Recording : stepnode::sim::AxisMachine {
  std::vector<Tick> times;
  std::vector<int64_t> history;  // the position after each step
  void step(Tick time, int direction) override {
    times.push_back(time);
    stepnode::sim::AxisMachine::step(time, direction);
    history.push_back(position());
  }
};

struct Figures {
  size_t steps = 0;
  double worst_ns = 0, mean_ns = 0;
  double worst_steps = 0;  // position against the master's trajectory on its own clock
};

// `hz` SYNC, `cycles` set-points of a sine of `amplitude` steps and `period_s`; SYNC jitter
// uniform in +-jitter_us. The ideal is the master's: the set-point of SYNC k reached at
// SYNC k+1 as it arrived, linear in between, from where the axis was at SYNC k.
Figures run(int hz, int cycles, double amplitude, double period_s, double jitter_us) {
  using namespace stepnode;
  Recording motor;
  motion::AxisCore core({&motor});
  cia402::Drive drive(core);
  const Tick cycle = kClockHz / hz;
  drive.parameters().max_velocity = 10'000'000;
  drive.parameters().interpolation_period = cycle;
  drive.set_mode(cia402::Mode::CyclicSyncPosition, 0);
  for (uint16_t cw : {0x06, 0x07, 0x0F}) drive.controlword(cw, 0);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> jitter(-jitter_us, jitter_us);
  struct Segment {
    Tick start, length;
    int64_t from, to;
  };
  std::vector<Segment> segments;
  std::vector<int32_t> targets;
  int64_t at = 0;
  Tick last = 0;
  for (int k = 1; k <= cycles; ++k) {
    const Tick t = cycle * k + static_cast<Tick>(jitter(rng) * kClockHz / 1e6);
    drive.advance(t);
    const auto target =
        static_cast<int32_t>(std::lround(amplitude * std::sin(2 * M_PI * k / (hz * period_s))));
    drive.set_target_position(target);
    targets.push_back(target);
    drive.sync(t, t);
    // The segment the drive plans: from where the axis is to the target, over the cycle it
    // measured (the average of the SYNC intervals, as drive_cyclic.cpp does).
    at = drive.position_actual();
    segments.push_back({t, 0, at, target});
    last = t;
  }
  drive.advance(last + 10 * cycle);
  // Each step against its segment's ideal; a step after the next SYNC belongs to the next
  // segment (the drive folds it in).
  Figures f;
  size_t s = 0;
  double sum = 0;
  for (size_t k = 0; k < segments.size(); ++k) {
    const Segment& g = segments[k];
    const int64_t n = std::llabs(g.to - g.from);
    const Tick len = k + 1 < segments.size() ? segments[k + 1].start - g.start : cycle;
    for (int64_t i = 1; i <= n && s < motor.times.size(); ++i, ++s) {
      const double ideal = static_cast<double>(g.start) + static_cast<double>(i) *
                                                              static_cast<double>(len) /
                                                              static_cast<double>(n);
      if (motor.times[s] > (k + 1 < segments.size() ? segments[k + 1].start : INT64_MAX)) break;
      const double err = std::fabs(static_cast<double>(motor.times[s]) - ideal) * 1e9 / kClockHz;
      f.worst_ns = std::max(f.worst_ns, err);
      sum += err;
      ++f.steps;
    }
  }
  f.mean_ns = f.steps ? sum / static_cast<double>(f.steps) : 0;
  // The master's trajectory on its clock (set-point k at (k+1) cycles, one cycle behind,
  // linear in between) against the axis' position after each step.
  int64_t x = 0;
  for (size_t i = 0; i < motor.times.size(); ++i) {
    x = motor.history[i];
    const double c = static_cast<double>(motor.times[i]) / static_cast<double>(cycle) -
                     1;  // cycles since SYNC 1
    const auto k = static_cast<size_t>(
        std::clamp<double>(std::floor(c), 0, static_cast<double>(targets.size() - 1)));
    const double p0 = k == 0 ? 0 : targets[k - 1], p1 = targets[k];
    const double ideal = p0 + (p1 - p0) * std::clamp(c - static_cast<double>(k), 0.0, 1.0);
    f.worst_steps = std::max(f.worst_steps, std::fabs(ideal - static_cast<double>(x)));
  }
  return f;
}

}  // namespace

int main() {
  std::printf("CSP step-time error against the ideal linear interpolation (one tick = 203 ns)\n");
  std::printf("%-34s %8s %10s %9s %14s\n", "case", "steps", "worst ns", "mean ns", "worst steps*");
  struct Case {
    const char* name;
    int hz, cycles;
    double amplitude, period_s, jitter_us;
  };
  for (const Case c : {Case{"1 kHz SYNC, sine 20000 steps 2 s", 1000, 4000, 20000, 2, 0},
                       Case{"100 Hz SYNC, sine 20000 steps 2 s", 100, 400, 20000, 2, 0},
                       Case{"1 kHz SYNC, jitter +-50 us", 1000, 4000, 20000, 2, 50},
                       Case{"100 Hz SYNC, jitter +-500 us", 100, 400, 20000, 2, 500}}) {
    const Figures f = run(c.hz, c.cycles, c.amplitude, c.period_s, c.jitter_us);
    std::printf("%-34s %8zu %10.1f %9.1f %14.2f\n", c.name, f.steps, f.worst_ns, f.mean_ns,
                f.worst_steps);
  }
  std::printf(
      "ns: each step against the drive's interpolation between the SYNCs as they arrived\n"
      "*: the position after each step against the master's trajectory on its own clock\n");
  return 0;
}
