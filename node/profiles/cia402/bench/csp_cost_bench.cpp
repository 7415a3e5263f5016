// Instructions per step of CiA 402 cyclic synchronous position (CSP) interpolation (issue
// 13), a bench program for callgrind: a master's set-points at 1 kHz SYNC along a sine,
// the drive interpolating each SYNC interval (drive_cyclic.cpp), every step taken through
// the motion core into a motor that only counts, all inside run_cycles().
//   valgrind --tool=callgrind --toggle-collect='*run_cycles*'
//   build/node/csp_cost_bench [cycles] [amplitude]
// then Ir (the "Collected" total) / steps. The Ir include the drive's SYNC and advance work,
// spread over the steps of each cycle (a sine of `amplitude` steps and a 2 s period: up to
// amplitude * pi steps/s).
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "node/profiles/cia402/drive.hpp"
#include "node/sim/machine.hpp"

namespace {

using stepnode::motion::kClockHz;
using stepnode::motion::Tick;

struct Counting : stepnode::sim::AxisMachine {
  using stepnode::sim::AxisMachine::step;
  int64_t steps = 0;
  void step(Tick time, int direction) override {
    ++steps;
    stepnode::sim::AxisMachine::step(time, direction);
  }
};

// Not inlined: callgrind's --toggle-collect names it.
[[gnu::noinline]] int64_t run_cycles(stepnode::cia402::Drive& drive, int cycles, double amplitude) {
  constexpr int kHz = 1000;
  constexpr double kPeriodS = 2;
  const Tick cycle = kClockHz / kHz;
  for (int k = 1; k <= cycles; ++k) {
    const Tick t = cycle * k;
    drive.advance(t);
    drive.set_target_position(
        static_cast<int32_t>(std::lround(amplitude * std::sin(2 * M_PI * k / (kHz * kPeriodS)))));
    drive.sync(t, t);
  }
  drive.advance(cycle * (cycles + 10));
  return drive.position_actual();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace stepnode;
  const int cycles = argc > 1 ? std::atoi(argv[1]) : 4000;
  const double amplitude = argc > 2 ? std::atof(argv[2]) : 20'000;
  Counting motor;
  motion::AxisCore core({&motor});
  cia402::Drive drive(core);
  drive.parameters().max_velocity = 10'000'000;
  drive.parameters().interpolation_period = kClockHz / 1000;
  drive.set_mode(cia402::Mode::CyclicSyncPosition, 0);
  for (uint16_t cw : {0x06, 0x07, 0x0F}) drive.controlword(cw, 0);
  const int64_t end = run_cycles(drive, cycles, amplitude);
  std::printf("csp: %lld steps in %d SYNC cycles of 1 ms (sine of %.0f steps), end at %lld\n",
              static_cast<long long>(motor.steps), cycles, amplitude, static_cast<long long>(end));
  return 0;
}
