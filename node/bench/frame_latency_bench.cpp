// Frame -> frame latency of the node in-process: the real device (node/device.*, as
// node/main.cpp builds it) handed frames on CLOCK_MONOTONIC, no socket and no vcan.
//   SYNC -> synchronous TPDO      (TPDO1 of axis 1 made synchronous, type 1)
//   RPDO -> first step            (RPDO1 of axis 1: Move Relative by one step)
//   SDO request -> response       (expedited upload of 0x1000 on 0x600+id)
//   foreign frame                 (frames for another node that reach the process)
// and, with --cia402, a CiA 402 drive (issue 10) on its default PDOs:
//   SYNC -> TPDO2 {6064h, 606Ch}  (TPDO1 {6041h, 6061h} and TPDO2 made synchronous)
//   controlword in RPDO1 -> first step (PP, new set-point, relative)
// Prints median and p99 in us and, where the CPU lets a process count them (perf events),
// the median instructions per frame. Asserts nothing.
//   build/node/frame_latency_bench [--iterations N] [--cia402]
//   valgrind --tool=callgrind build/node/frame_latency_bench --foreign-only N   (instructions
//   per foreign frame: the difference of N and 0, divided by N)
#include <linux/perf_event.h>
#include <sys/ioctl.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <optional>
#include <vector>

#include "node/device.hpp"
#include "node/profiles/cia402/objects.hpp"
#include "node/profiles/horner/bits.hpp"
#include "node/profiles/horner/objects.hpp"
#include "node/profiles/sim/objects.hpp"

using namespace stepnode;

namespace {

constexpr uint8_t kId = 5;

uint64_t clock_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1'000'000'000u + static_cast<uint64_t>(ts.tv_nsec);
}

// The device's time: the same monotonic clock, in the microseconds its services take.
uint64_t now_us() { return clock_ns() / 1000; }

// User-space instructions of this thread (perf events); absent where the CPU or the
// container gives none.
class InstructionCounter {
 public:
  InstructionCounter() {
    perf_event_attr a{};
    a.type = PERF_TYPE_HARDWARE;
    a.size = sizeof a;
    a.config = PERF_COUNT_HW_INSTRUCTIONS;
    a.exclude_kernel = 1;
    a.exclude_hv = 1;
    fd_ = static_cast<int>(syscall(SYS_perf_event_open, &a, 0, -1, -1, 0));
    if (fd_ >= 0) ioctl(fd_, PERF_EVENT_IOC_ENABLE, 0);
  }
  ~InstructionCounter() {
    if (fd_ >= 0) close(fd_);
  }
  bool works() const { return fd_ >= 0; }
  uint64_t read_now() const {
    uint64_t v = 0;
    if (fd_ < 0 || ::read(fd_, &v, sizeof v) != sizeof v) return 0;
    return v;
  }

 private:
  int fd_ = -1;
};

struct Bench {
  node::Device device;
  uint32_t watch_id = 0;     // the answer being timed
  uint64_t answered_ns = 0;  // when it was sent (0: not yet)
  uint64_t frames_sent = 0;
  std::vector<sim::TracedStep> steps;

  explicit Bench(const node::NodeOptions& options)
      : device(options, {}, [this](const od::CanFrame& f) {
          ++frames_sent;
          if (f.id == watch_id && !answered_ns) answered_ns = clock_ns();
        }) {}
  void tick() { device.on_tick(now_us()); }
  void write(uint16_t index, uint8_t sub, od::Bytes v) {
    if (device.dictionary().write(index, sub, v) != od::SdoAbort::None) {
      std::fprintf(stderr, "write %04X:%02X refused\n", index, sub);
      std::exit(1);
    }
  }
};

struct Figures {
  std::vector<double> us;
  std::vector<uint64_t> instructions;
};

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1,
                    static_cast<size_t>(std::llround(p * static_cast<double>(v.size() - 1))))];
}

// One timed frame: from the device being handed it to the watched answer leaving (or the
// handler's end when `answer` is 0).
void timed(Bench& b, const InstructionCounter& ic, const od::CanFrame& f, uint32_t answer,
           Figures& out) {
  b.watch_id = answer;
  b.answered_ns = 0;
  const uint64_t i0 = ic.read_now();
  const uint64_t t0 = clock_ns();
  b.device.on_frame(f, t0 / 1000, t0 / 1000);
  const uint64_t t1 = answer ? b.answered_ns : clock_ns();
  const uint64_t i1 = ic.read_now();
  if (answer && !t1) return;  // no answer this time: not counted
  out.us.push_back(static_cast<double>(t1 - t0) / 1000.0);
  out.instructions.push_back(i1 - i0);
}

void print(const char* what, const Figures& f, bool instructions) {
  std::vector<double> ins(f.instructions.begin(), f.instructions.end());
  std::printf("%-28s n=%-6zu median %7.2f us  p99 %7.2f us", what, f.us.size(),
              percentile(f.us, 0.5), percentile(f.us, 0.99));
  if (instructions) std::printf("  median %8.0f instructions", percentile(ins, 0.5));
  std::printf("\n");
}

void pause_ticking(Bench& b, uint64_t us) {
  const uint64_t end = now_us() + us;
  while (now_us() < end) b.tick();
}

node::NodeOptions options() {
  node::NodeOptions o;
  o.device.node_id = kId;
  o.layout.axes = 3;
  o.state_dir = std::filesystem::temp_directory_path() / "stepnode-latency-bench";
  return o;
}

// Axis 1 of the simulated machine without limit switches: the moves run anywhere.
void limit_switches_off(Bench& b) {
  b.write(sim::obj::index(0, sim::obj::kSwitches), sim::switches_sub::kLowerLimitEnabled, {0});
  b.write(sim::obj::index(0, sim::obj::kSwitches), sim::switches_sub::kUpperLimitEnabled, {0});
}

void prepare_axis(Bench& b) {
  using namespace horner::obj;
  limit_switches_off(b);
  b.write(index(0, kCommandBits), 0, od::encode<uint16_t>(horner::command::kClearErrors));
  b.write(index(0, kCommandBits), 0, od::encode<uint16_t>(0));
}

}  // namespace

namespace {

// Frames for node 6: an NMT command (it passes the kernel filters: every node hears NMT),
// an SDO request, an RPDO and a heartbeat (in-process only: the filters keep them out of
// the socket).
std::vector<od::CanFrame> foreign_frames() {
  return {od::CanFrame(0x000, {0x80, 6}), od::CanFrame(0x606, {0x40, 0x00, 0x10, 0, 0, 0, 0, 0}),
          od::CanFrame(0x206, {1, 2, 3, 4, 5, 6}), od::CanFrame(0x706, {0x7F})};
}

// Deterministic (virtual time, no clock): for callgrind, run with N and with 0.
int foreign_only(uint64_t n) {
  Bench b(options());
  uint64_t t = 1'000'000;
  b.device.start(t);
  b.device.on_frame(od::CanFrame(0, {0x01, kId}), t);
  const auto frames = foreign_frames();
  for (uint64_t i = 0; i < n; ++i) {
    t += 10;
    b.device.on_frame(frames[i % frames.size()], t, t);
  }
  std::printf("foreign frames %llu, frames sent %llu\n", static_cast<unsigned long long>(n),
              static_cast<unsigned long long>(b.frames_sent));
  return 0;
}

}  // namespace

namespace {

// CiA 402's default PDOs at the pre-defined COB-IDs of axis 1 (CiA 301): RPDO1 0x200+id
// {controlword U16, modes of operation I8}, RPDO2 0x300+id {target position I32, target
// velocity I32}.
od::CanFrame controlword_rpdo(uint16_t controlword, int8_t mode) {
  return od::CanFrame(0x200 + kId,
                      {static_cast<uint8_t>(controlword), static_cast<uint8_t>(controlword >> 8),
                       static_cast<uint8_t>(mode)});
}
od::CanFrame target_rpdo(int32_t position) {
  const auto p = static_cast<uint32_t>(position);
  return od::CanFrame(0x300 + kId,
                      {static_cast<uint8_t>(p), static_cast<uint8_t>(p >> 8),
                       static_cast<uint8_t>(p >> 16), static_cast<uint8_t>(p >> 24), 0, 0, 0, 0});
}

constexpr uint32_t kAcceleration = 10'000'000;  // steps/s^2, 6083h and 6084h

// A drive-only device of one axis, NMT operational, in Operation enabled (CiA 402 device
// control: shutdown 06h, switch on 07h, enable operation 0Fh), PP, both TPDOs synchronous.
void prepare_drive(Bench& b) {
  namespace o = cia402::obj;
  b.device.start(now_us());
  b.device.on_frame(od::CanFrame(0, {0x01, kId}), now_us());  // NMT start
  limit_switches_off(b);
  b.write(0x1800, 2, {1});
  b.write(0x1801, 2, {1});
  b.write(o::kProfileVelocity, 0, od::encode<uint32_t>(100'000));
  b.write(o::kProfileAcceleration, 0, od::encode<uint32_t>(kAcceleration));
  b.write(o::kProfileDeceleration, 0, od::encode<uint32_t>(kAcceleration));
  for (uint16_t cw : {0x06, 0x07, 0x0F}) {
    b.device.on_frame(controlword_rpdo(cw, 1), now_us());
    pause_ticking(b, 2000);
  }
  const auto sw = b.device.dictionary().get<uint16_t>(o::kStatusword, 0);
  if ((sw & 0x6F) != 0x27) {  // operation enabled
    std::fprintf(stderr, "the drive is not in operation enabled: 6041h = 0x%04X\n", sw);
    std::exit(1);
  }
}

int cia402_latency(unsigned iterations, const InstructionCounter& ic) {
  node::NodeOptions o = options();
  o.layout =
      node::DeviceLayout{.axes = 1, .horner = false, .hp = false, .user = false, .cia402 = true};
  Bench b(o);
  prepare_drive(b);
  b.device.machine().axes.at(0).trace_into(&b.steps);
  Figures sync, controlword, first_step;
  unsigned in_handler = 0;
  for (unsigned i = 0; i < iterations; ++i) {
    pause_ticking(b, 200);
    timed(b, ic, od::CanFrame(0x80, {}), 0x280 + kId, sync);
    b.device.on_frame(target_rpdo(10), now_us());  // 10 steps on
    pause_ticking(b, 200);
    const size_t before = b.steps.size();
    const uint64_t frame_us = now_us();
    // Enable operation + new set-point (bit 4) + relative (bit 6); then bit 4 released.
    timed(b, ic, controlword_rpdo(0x5F, 1), 0, controlword);
    if (b.steps.size() > before) ++in_handler;
    b.device.on_frame(controlword_rpdo(0x4F, 1), now_us());
    for (uint64_t end = now_us() + 100'000; b.steps.size() == before && now_us() < end;) b.tick();
    if (b.steps.size() > before)
      first_step.us.push_back(static_cast<double>(b.device.axes().micros(b.steps[before].time)) -
                              static_cast<double>(frame_us));
    pause_ticking(b, 5000);  // the 10 steps take 2 ms at this acceleration
  }
  const double ideal_us = std::sqrt(2.0 / kAcceleration) * 1e6;
  std::printf("CiA 402 drive, %u iterations, node %u operational, PP, default PDOs\n", iterations,
              kId);
  print("SYNC -> TPDO2 {6064h,606Ch}", sync, ic.works());
  print("controlword RPDO handled", controlword, ic.works());
  print("controlword -> first step", first_step, false);
  std::printf(
      "%-28s %.2f us from rest at 6083h = %u steps/s^2 (the first step's physics: "
      "sqrt(2/a)); %u of %zu taken within the RPDO's handler\n",
      "  ideal first step", ideal_us, kAcceleration, in_handler, controlword.us.size());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  unsigned iterations = 2000;
  bool cia402 = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--cia402")) cia402 = true;
    else if (!std::strcmp(argv[i], "--iterations") && i + 1 < argc)
      iterations = static_cast<unsigned>(std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--foreign-only") && i + 1 < argc)
      return foreign_only(std::strtoull(argv[++i], nullptr, 10));
  }
  const InstructionCounter ic;
  if (cia402) return cia402_latency(iterations, ic);
  Bench b(options());
  b.device.start(now_us());
  b.device.on_frame(od::CanFrame(0, {0x01, kId}), now_us());  // NMT start
  prepare_axis(b);
  b.write(0x1800, 2, {1});  // TPDO1 (axis 1 status and position): synchronous, every SYNC
  b.device.machine().axes.at(0).trace_into(&b.steps);

  Figures sync, rpdo, first_step, sdo, foreign;
  unsigned first_step_in_handler = 0;
  const auto others = foreign_frames();
  for (unsigned i = 0; i < iterations; ++i) {
    pause_ticking(b, 200);
    timed(b, ic, od::CanFrame(0x80, {}), 0x180 + kId, sync);
    pause_ticking(b, 200);
    // Move Relative by +1 (RPDO1: command bits, destination); the edge acts, then released.
    const size_t before = b.steps.size();
    const uint64_t frame_us = now_us();
    timed(b, ic, od::CanFrame(0x200 + kId, {0x80, 0x00, 1, 0, 0, 0}), 0, rpdo);
    if (b.steps.size() > before) ++first_step_in_handler;
    b.device.on_frame(od::CanFrame(0x200 + kId, {0x00, 0x00, 1, 0, 0, 0}), now_us());
    for (uint64_t end = now_us() + 100'000; b.steps.size() == before && now_us() < end;) b.tick();
    if (b.steps.size() >
        before)  // the step's own time on the node's clock, after the RPDO was handed over
      first_step.us.push_back(static_cast<double>(b.device.axes().micros(b.steps[before].time)) -
                              static_cast<double>(frame_us));
    pause_ticking(b, 200);
    timed(b, ic, od::CanFrame(0x600 + kId, {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0}), 0x580 + kId, sdo);
    pause_ticking(b, 200);
    timed(b, ic, others[i % others.size()], 0, foreign);
  }
  std::printf(
      "frame -> frame in-process, %u iterations, device of 3 axes (Horner, HP, user), node %u "
      "operational\n",
      iterations, kId);
  print("SYNC -> synchronous TPDO", sync, ic.works());
  print("RPDO handled (Move Rel +1)", rpdo, ic.works());
  print("RPDO -> first step's time", first_step,
        false);  // the module model: DIR setup, first period
  std::printf("%-28s %u of %zu taken within the RPDO's handler\n", "  first step",
              first_step_in_handler, rpdo.us.size());
  print("SDO request -> response", sdo, ic.works());
  print("foreign frame (handled)", foreign, ic.works());
  if (!ic.works())
    std::printf("instructions: no perf events here; see the callgrind command in the source\n");
  return 0;
}
