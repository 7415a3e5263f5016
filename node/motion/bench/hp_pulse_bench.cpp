// HP 44714A pulse-rate accuracy and jitter of the generated step times (appendix A
// specifies: pulse rate accuracy 0.01 %, jitter 1 us). Build and run:
//   cmake --build build --target hp_pulse_bench && build/node/hp_pulse_bench
//
// Each row drives one channel the way a master does (PROFILE FREQ 0 10000 SLOPE 1E-6, then
// SUSTAIN RATE), waits until DONE? says the rate is reached, and records the engine's step
// times (exact 4.9152 MHz ticks, as the step sink receives them) over a window of steady
// running. Against the ideal pulse train of the requested rate:
//   rate error   |N / (t_N - t_0) - RATE| / RATE over the window
//   period jitter  max |(t_k - t_k-1) - 1/RATE| (one period against the ideal period)
//   time error     max |t_k - (t_0 + k/RATE)| (drift of the train against the ideal grid)
// These are the generated times; a hardware backend adds its own output latency.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "node/motion/axis.hpp"
#include "node/motion/hp_channel.hpp"
#include "node/sim/machine.hpp"

using namespace stepnode;
using namespace stepnode::motion;

namespace {

// The simulated motor, keeping every step time.
class RecordingMotor : public sim::AxisMachine {
 public:
  using sim::AxisMachine::AxisMachine;
  void step(Tick time, int direction) override {
    sim::AxisMachine::step(time, direction);
    if (recording) times.push_back(time);
  }
  bool recording = false;
  std::vector<Tick> times;
};

struct Row {
  double rate, slope;
  double rate_error, period_jitter_ns, time_error_ns;
  size_t pulses;
};

Row measure(double rate, double slope) {
  sim::AxisMachineConfig m;
  m.encoder = sim::EncoderKind::None;
  RecordingMotor motor(m);
  Axis axis(AxisConfig{}, {&motor});
  hp::Channel ch(axis.core());
  Tick now = 0;
  ch.profile(hp::Profile{hp::ProfileMode::Freq, 0, 10'000, slope, 1e-6}, now);
  ch.sustain(rate, true, now);
  const Tick step = kClockHz / 100;  // advance 10 ms at a time, as a node tick would
  while (ch.done() != hp::Done::SustainRunning) ch.advance_to(now += step);
  // A window of at least 20,000 pulses or 100 s of steady running.
  const size_t want = static_cast<size_t>(std::max(20'000.0, std::min(rate * 100, 200'000.0)));
  motor.recording = true;
  while (motor.times.size() < want) ch.advance_to(now += step);
  const auto& t = motor.times;
  const double tick_ns = 1e9 / static_cast<double>(kClockHz);
  const double period_ns = 1e9 / rate;
  Row r{rate, slope, 0, 0, 0, t.size()};
  double span_ns = static_cast<double>(t.back() - t.front()) * tick_ns;
  double measured = static_cast<double>(t.size() - 1) / (span_ns * 1e-9);
  r.rate_error = std::fabs(measured - rate) / rate;
  for (size_t k = 1; k < t.size(); ++k) {
    double p = static_cast<double>(t[k] - t[k - 1]) * tick_ns;
    r.period_jitter_ns = std::max(r.period_jitter_ns, std::fabs(p - period_ns));
    double ideal = static_cast<double>(k) * period_ns;
    double actual = static_cast<double>(t[k] - t[0]) * tick_ns;
    r.time_error_ns = std::max(r.time_error_ns, std::fabs(actual - ideal));
  }
  return r;
}

}  // namespace

int main() {
  std::printf(
      "HP 44714A pulse output: generated step times vs the ideal train "
      "(build/node/hp_pulse_bench)\n");
  std::printf("spec (appendix A): rate accuracy 0.01 %% = 1.0e-04, jitter 1 us = 1000 ns\n\n");
  std::printf("%10s %10s %9s %12s %16s %14s  %s\n", "rate Hz", "slope Hz/s", "pulses", "rate error",
              "period jitter ns", "time error ns", "vs spec");
  double worst_rate = 0, worst_jitter = 0;
  for (double slope : {500.0, 100'000.0, 1'000'000.0})
    for (double rate : {1.0, 10.0, 99.99, 123.456, 1000.0, 2500.5, 7777.7, 9999.9}) {
      Row r = measure(rate, slope);
      worst_rate = std::max(worst_rate, r.rate_error);
      worst_jitter = std::max(worst_jitter, r.period_jitter_ns);
      bool ok = r.rate_error < 1e-4 && r.period_jitter_ns < 1000;
      std::printf("%10.3f %10.0f %9zu %12.3e %16.1f %14.1f  %s\n", r.rate, r.slope, r.pulses,
                  r.rate_error, r.period_jitter_ns, r.time_error_ns, ok ? "better" : "WORSE");
    }
  std::printf(
      "\nworst rate error %.3e (spec 1.0e-04), worst period jitter %.1f ns (spec 1000 ns)\n",
      worst_rate, worst_jitter);
  return worst_rate < 1e-4 && worst_jitter < 1000 ? 0 : 1;
}
