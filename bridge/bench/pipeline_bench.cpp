// pipeline_bench: the bridge's own capacity natively, without a CAN bus.
//
//   pipeline_bench [--rates 1000,10000,20000,40000,80000,160000] [--seconds 3]
//                  [--nodes 10] [--modes bridged,alone] [--domain N] [--profiles FILE]
//
// In this process, the code stepbridge runs: a BusObserver and the real DdsPublisher
// (bridge/dds/publisher.hpp), driven by a "bridge thread" like stepbridge's event loop.
// A generator thread feeds it in real time, paced in short slices (--slice-us), through a
// queue that wakes the bridge thread the way the CAN socket does: TPDO2 frames (motor
// position = a sequence number) of NODES stepnodes, round robin, can_time_ns =
// CLOCK_REALTIME when the frame is queued, and every node's heartbeat each 100 ms. The
// nodes were discovered by the observer beforehand over SDO, answered in-process by od's
// SdoServer on real stepnode dictionaries (bridge/observer/tests/fake_node.hpp); later SDO
// requests are answered the same way, inside the bridge thread.
//
// A subscriber in a separate process (this program again, --subscriber, started before
// the runs; bridge/bench/pipeline_subscriber.cpp) reads AxisPosition with a RELIABLE KEEP_ALL
// reader and measures latency (now - can_time_ns) and loss (sequence numbers that never arrived);
// it reports over a pipe.
//
// Modes, per rate:
//   bridged  frame -> queue -> bridge thread -> BusObserver -> DdsPublisher -> subscriber
//   alone    frame -> queue -> the same thread -> the same AxisPosition sample written
//            straight to a DataWriter with the same QoS (no observer, no DdsPublisher):
//            Fast DDS alone, same pacing, same wake-ups, same subscriber.
// CPU: the publishing process's CPU time minus the generator thread's (so: bridge thread
// plus every Fast DDS thread), and the bridge thread alone, over the run's wall time. RSS
// is the process's VmRSS at the end of the run.
#include <pthread.h>
#include <spdlog/spdlog.h>
#include <unistd.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/topic/Topic.hpp>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <stepnodePubSubTypes.h>

#include "bridge/bench/pipeline_bench.hpp"
#include "bridge/bench/pipeline_queue.hpp"
#include "bridge/dds/participant.hpp"
#include "bridge/dds/publisher.hpp"
#include "bridge/dds/qos.hpp"
#include "bridge/dds/types.hpp"
#include "bridge/observer/bus_observer.hpp"
#include "bridge/observer/tests/fake_node.hpp"

using namespace stepnode;
namespace efd = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;
using Clock = std::chrono::steady_clock;

namespace {

using bench::clock_s;
using bench::FrameQueue;
using bench::Item;
using bench::process_cpu_s;
using bench::RunRequest;
using bench::status_kb;

constexpr uint32_t kTpdo2 = 0x280;
constexpr int32_t kFirstSeq = 1'000'000;  // below: discovery snapshots, never counted

uint64_t monotonic_us() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1'000'000u + static_cast<uint64_t>(ts.tv_nsec) / 1000u;
}

enum class Mode : int { Bridged, Alone };

// Feeds the observer what a node would answer until it has nothing more to ask.
void answer_sdo(std::vector<std::unique_ptr<bridge::test::FakeNode>>& nodes,
                bridge::BusObserver& observer, std::vector<od::CanFrame>& out) {
  while (!out.empty()) {
    std::vector<od::CanFrame> replies, next;
    for (const auto& f : out)
      for (auto& n : nodes) n->on_frame(f, monotonic_us(), replies);
    out.clear();
    for (const auto& r : replies) {
      bridge::ObservedFrame of;
      of.frame = r;
      of.can_time_ns = bridge::dds::realtime_ns();
      observer.on_frame(of, monotonic_us(), next);
    }
    out.swap(next);
  }
}

struct Options {
  std::vector<int> rates{1000, 10000, 20000, 40000, 80000, 160000};
  double seconds = 3;
  int nodes = 10;
  std::vector<std::string> modes{"bridged", "alone"};
  uint32_t domain = 0;
  std::string profiles;
  int slice_us = 100;
  double max_p99_ms = 10;
  int32_t reader_depth = 0;
  uint32_t sub_port_queue = 0;
};

// One run's figures, as the table prints them.
struct Measured {
  int64_t total = 0, lost = 0;
  double gen_wall = 0, wall = 0;  // s: the generator's run, until the bridge thread caught up
  double proc_s = 0, bridge_s = 0,
         gen_s = 0;  // CPU s: process minus generator, bridge thread, generator
  long rss_kb = 0;
  size_t backlog = 0;
  uint64_t write_failures = 0;
  bench::SubscriberProcess::Result sub;
};

// The publishing side: the bridge (BusObserver + DdsPublisher) and Fast DDS alone, the
// nodes it discovered, the bridge thread and the generator thread.
class Pipeline {
 public:
  explicit Pipeline(const Options& opt)
      : opt_(opt), publisher_(publisher_options(opt)), observer_(publisher_, {}) {
    create_alone_writer();
    discover_nodes();
    bridge_thread_ = std::thread([this] { bridge_loop(); });
    generator_ = std::thread([this] { generator_loop(); });
    pthread_getcpuclockid(generator_.native_handle(), &generator_clock_);
    pthread_getcpuclockid(bridge_thread_.native_handle(), &bridge_clock_);
  }
  ~Pipeline() {
    quit_ = true;
    generator_.join();
    queue_.stop();
    bridge_thread_.join();
    bridge::dds::delete_participant(alone_participant_);
  }
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // Both writers must see the subscriber before anything is measured.
  void wait_for_subscriber() {
    efd::PublicationMatchedStatus alone_matched;
    for (int i = 0; i < 1000; ++i) {
      alone_writer_->get_publication_matched_status(alone_matched);
      if (publisher_.matched_readers(bridge::dds::TopicKind::AxisPosition) > 0 &&
          alone_matched.current_count > 0)
        break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (publisher_.matched_readers(bridge::dds::TopicKind::AxisPosition) == 0 ||
        alone_matched.current_count == 0)
      throw std::runtime_error("the subscriber did not match both writers within 10 s");
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
  }

  // One run of `rate` frames a second in mode `md`, sequence numbers from `next_seq` on.
  Measured measure(int rate, Mode md, bench::SubscriberProcess& sub, int32_t& next_seq) {
    Measured m;
    mode_.store(static_cast<int>(md));
    m.total = static_cast<int64_t>(rate * opt_.seconds);
    run_.rate = rate;
    run_.total = m.total;
    run_.first_seq = next_seq;
    sub.begin(next_seq, next_seq + static_cast<int32_t>(m.total));
    next_seq += static_cast<int32_t>(m.total);
    const uint64_t failures_before = publisher_.write_failures() + alone_failures_.load();
    queue_.take_max_backlog();
    const double cpu0 = process_cpu_s(), gen0 = clock_s(generator_clock_),
                 br0 = clock_s(bridge_clock_);
    const auto t0 = Clock::now();
    run_.phase.store(1, std::memory_order_release);
    while (run_.phase.load(std::memory_order_acquire) != 3)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    m.gen_wall = std::chrono::duration<double>(Clock::now() - t0).count();
    while (processed_.load(std::memory_order_acquire) < queue_.pushed())
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    m.wall = std::chrono::duration<double>(Clock::now() - t0).count();
    const double cpu1 = process_cpu_s(), gen1 = clock_s(generator_clock_),
                 br1 = clock_s(bridge_clock_);
    m.rss_kb = status_kb("VmRSS:");
    m.backlog = queue_.take_max_backlog();
    run_.phase.store(0);
    m.sub = sub.report();
    m.write_failures = publisher_.write_failures() + alone_failures_.load() - failures_before;
    m.lost = m.total - static_cast<int64_t>(m.sub.received);
    m.gen_s = gen1 - gen0;
    m.proc_s = (cpu1 - cpu0) - m.gen_s;
    m.bridge_s = br1 - br0;
    return m;
  }

 private:
  static bridge::dds::PublisherOptions publisher_options(const Options& opt) {
    bridge::dds::PublisherOptions po;
    po.participant.domain = opt.domain;
    po.participant.profiles_file = opt.profiles;
    po.participant.name = "pipeline_bench bridge";
    return po;
  }

  // Fast DDS alone: its own participant, one writer, the same QoS as the bridge's
  // AxisPosition writer (built-in, or the profile's when --profiles has one).
  void create_alone_writer() {
    bridge::dds::ParticipantOptions alone_po;
    alone_po.domain = opt_.domain;
    alone_po.name = "pipeline_bench alone";
    alone_participant_ = bridge::dds::create_participant(alone_po);
    efd::Topic* alone_topic = bench::register_axis_position(alone_participant_);
    efd::Publisher* alone_publisher =
        alone_participant_->create_publisher(efd::PUBLISHER_QOS_DEFAULT);
    alone_writer_ = alone_publisher->create_datawriter(
        alone_topic,
        bridge::dds::writer_qos(bridge::dds::TopicKind::AxisPosition, false, *alone_publisher));
    if (!alone_writer_) throw std::runtime_error("alone: Fast DDS refused the writer QoS");
  }

  // Nodes 1..N, one axis each, discovered over SDO like on a bus.
  void discover_nodes() {
    std::vector<od::CanFrame> out;
    for (int id = 1; id <= opt_.nodes; ++id) {
      nodes_.push_back(std::make_unique<bridge::test::FakeNode>(
          bridge::test::FakeNodeOptions{.id = static_cast<uint8_t>(id), .axes = 1}));
      auto& n = *nodes_.back();
      bridge::ObservedFrame boot;
      boot.frame = n.boot_up();
      boot.can_time_ns = bridge::dds::realtime_ns();
      observer_.on_frame(boot, monotonic_us(), out);
      answer_sdo(nodes_, observer_, out);
      if (!observer_.node_health(n.id(), monotonic_us()).discovered)
        throw std::runtime_error("node " + std::to_string(id) + " was not discovered");
    }
    // TPDO2 of axis 1 must be motor position (bytes 0..3) then encoder position: check it
    // on the real dictionary, so the generator can write the sequence number into bytes 0..3.
    nodes_[0]->set_position(0, 0x12345678, 0);
    od::CanFrame probe = nodes_[0]->tpdo(1);
    if (probe.id != kTpdo2 + 1 || probe.dlc != 8 || od::get_u32(probe.data.data()) != 0x12345678u)
      throw std::runtime_error("TPDO2 is not motor position + encoder position on 0x281");
  }

  // Mode alone: the AxisPosition sample the bridge would publish for a TPDO2, written
  // straight to the alone writer.
  void write_alone(const Item& it) {
    ::stepnode::AxisPosition d;
    d.node(static_cast<uint8_t>(it.frame.id & 0x7F));
    d.axis(1);
    d.motor_position(static_cast<int32_t>(od::get_u32(it.frame.data.data())));
    d.encoder_position(static_cast<int32_t>(od::get_u32(&it.frame.data[4])));
    d.motor_user_units(d.motor_position());
    d.encoder_user_units(d.encoder_position());
    d.can_time_ns(it.can_time_ns);
    d.publish_time_ns(bridge::dds::realtime_ns());
    if (alone_writer_->write(&d, efd::HANDLE_NIL) != ReturnCode_t::RETCODE_OK) ++alone_failures_;
  }

  // The bridge thread: stepbridge's loop with a queue in place of the socket.
  void bridge_loop() {
    std::vector<Item> batch;
    std::vector<od::CanFrame> sdo_out;
    const auto tick = std::chrono::milliseconds(10);
    auto next_tick = Clock::now() + tick;
    while (true) {
      batch.clear();
      if (!queue_.take(batch, next_tick)) break;
      const bool alone = mode_.load(std::memory_order_relaxed) == static_cast<int>(Mode::Alone);
      for (const Item& it : batch) {
        if (alone && (it.frame.id & 0x780) == kTpdo2) {
          write_alone(it);
          continue;
        }
        bridge::ObservedFrame of;
        of.frame = it.frame;
        of.can_time_ns = it.can_time_ns;
        observer_.on_frame(of, monotonic_us(), sdo_out);
        answer_sdo(nodes_, observer_, sdo_out);
      }
      processed_.fetch_add(batch.size(), std::memory_order_release);
      if (Clock::now() >= next_tick) {
        observer_.on_tick(monotonic_us(), bridge::dds::realtime_ns(), sdo_out);
        answer_sdo(nodes_, observer_, sdo_out);
        next_tick += tick;
        if (next_tick < Clock::now()) next_tick = Clock::now() + tick;
      }
    }
  }

  // The generator: heartbeats every 100 ms always, TPDO2 frames when a run is requested.
  void generator_loop() {
    std::vector<Item> batch;
    auto next_heartbeat = Clock::now();
    Clock::time_point start;
    int64_t sent = 0;
    int32_t seq = 0;
    const auto slice = std::chrono::microseconds(opt_.slice_us);
    while (!quit_.load()) {
      const auto now = Clock::now();
      if (now >= next_heartbeat) {
        for (auto& n : nodes_) batch.push_back({n->heartbeat(0x05), bridge::dds::realtime_ns()});
        next_heartbeat += std::chrono::milliseconds(100);
      }
      int phase = run_.phase.load(std::memory_order_acquire);
      if (phase == 1) {
        start = now;
        sent = 0;
        seq = run_.first_seq;
        run_.phase.store(phase = 2);
      }
      if (phase == 2) {
        const double elapsed = std::chrono::duration<double>(now - start).count();
        const int64_t due =
            std::min<int64_t>(run_.total, static_cast<int64_t>(elapsed * run_.rate) + 1);
        append_tpdos(batch, sent, due, seq);
        if (sent == run_.total) run_.phase.store(3, std::memory_order_release);
      }
      queue_.push(batch);
      std::this_thread::sleep_until(now + slice);
    }
  }

  // TPDO2 frames `sent` up to `due`, round robin over the nodes, stamped now.
  void append_tpdos(std::vector<Item>& batch, int64_t& sent, int64_t due, int32_t& seq) const {
    const uint64_t t = bridge::dds::realtime_ns();
    for (; sent < due; ++sent, ++seq) {
      const auto node = static_cast<uint32_t>(sent % static_cast<int64_t>(nodes_.size())) + 1;
      Item it;
      it.frame.id = kTpdo2 + node;
      it.frame.dlc = 8;
      od::put_u32(it.frame.data.data(), static_cast<uint32_t>(seq));
      it.can_time_ns = t;
      batch.push_back(it);
    }
  }

  const Options& opt_;
  bridge::dds::DdsPublisher publisher_;
  bridge::BusObserver observer_;
  efd::DomainParticipant* alone_participant_ = nullptr;
  efd::DataWriter* alone_writer_ = nullptr;
  std::vector<std::unique_ptr<bridge::test::FakeNode>> nodes_;
  FrameQueue queue_;
  RunRequest run_;
  std::atomic<int> mode_{static_cast<int>(Mode::Bridged)};
  std::atomic<uint64_t> processed_{0};
  std::atomic<uint64_t> alone_failures_{0};
  std::atomic<bool> quit_{false};
  std::thread bridge_thread_, generator_;
  clockid_t generator_clock_{}, bridge_clock_{};
};

void print_table_head(const Options& opt) {
  std::printf(
      "pipeline_bench --domain %u --seconds %.1f --nodes %d --slice-us %d --reader-depth %d "
      "--sub-port-queue %u%s%s\n",
      opt.domain, opt.seconds, opt.nodes, opt.slice_us, opt.reader_depth, opt.sub_port_queue,
      opt.profiles.empty() ? "" : " --profiles ", opt.profiles.c_str());
  std::printf(
      "latency = CLOCK_REALTIME at the subscriber's take - can_time_ns (frame queued); CPU = %% of "
      "one core\n");
  std::printf(
      "CPU: proc = publishing process minus the generator thread, thread = the bridge thread, sub "
      "= the\n"
      "subscriber process, gen = the generator thread; us/smp = CPU microseconds per sample; "
      "backlog = most\n"
      "frames waiting for the bridge thread at one wake-up\n");
  std::printf("%8s %-7s %8s %8s %7s | %9s %9s %9s | %6s %7s %6s %6s | %6s %6s | %6s %7s\n",
              "rate/s", "mode", "achieved", "sent", "lost", "p50 us", "p99 us", "max us", "proc %",
              "thread%", "sub %", "gen %", "proc", "sub", "RSS MB", "backlog");
  std::printf("%8s %-7s %8s %8s %7s | %9s %9s %9s | %6s %7s %6s %6s | %6s %6s | %6s %7s\n", "", "",
              "", "", "", "", "", "", "", "", "", "", "us/smp", "us/smp", "", "");
  std::fflush(stdout);
}

void print_row(int rate, const std::string& mode, const Measured& m) {
  const bench::SubscriberProcess::Result& r = m.sub;
  const auto samples = static_cast<double>(m.total);
  std::printf(
      "%8d %-7s %8.0f %8lld %7lld | %9.1f %9.1f %9.1f | %6.1f %7.1f %6.1f %6.1f | %6.2f %6.2f | "
      "%6.1f %7zu%s\n",
      rate, mode.c_str(), samples / m.gen_wall, static_cast<long long>(m.total),
      static_cast<long long>(m.lost), static_cast<double>(r.p50) / 1e3,
      static_cast<double>(r.p99) / 1e3, static_cast<double>(r.max) / 1e3, 100.0 * m.proc_s / m.wall,
      100.0 * m.bridge_s / m.wall, 100.0 * r.cpu_s / m.wall, 100.0 * m.gen_s / m.wall,
      1e6 * m.proc_s / samples, 1e6 * r.cpu_s / samples, static_cast<double>(m.rss_kb) / 1024.0,
      m.backlog,
      m.write_failures ? (" write failures " + std::to_string(m.write_failures)).c_str() : "");
  std::fflush(stdout);
}

int run_publisher(const Options& opt, const std::string& exe) {
  // The subscriber first: it is up (and discovering) while this side starts.
  bench::SubscriberProcess sub(exe, opt.domain, opt.profiles, opt.reader_depth, opt.sub_port_queue);
  Pipeline pipeline(opt);
  pipeline.wait_for_subscriber();
  print_table_head(opt);
  struct Best {
    int bridged = 0, alone = 0;
  } best;
  int32_t next_seq = kFirstSeq;
  for (int rate : opt.rates) {
    for (const std::string& m : opt.modes) {
      const Mode md = m == "alone" ? Mode::Alone : Mode::Bridged;
      const Measured r = pipeline.measure(rate, md, sub, next_seq);
      print_row(rate, m, r);
      const bool ok = r.lost == 0 && static_cast<double>(r.sub.p99) < opt.max_p99_ms * 1e6 &&
                      static_cast<double>(r.total) / r.gen_wall > 0.95 * rate;
      if (ok && md == Mode::Bridged) best.bridged = std::max(best.bridged, rate);
      if (ok && md == Mode::Alone) best.alone = std::max(best.alone, rate);
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  }
  auto says = [&](const char* m, int v) {
    if (std::find(opt.modes.begin(), opt.modes.end(), m) == opt.modes.end()) return;
    if (v)
      std::printf("highest rate with 0 lost and p99 < %.0f ms, %s: %d frames/s\n", opt.max_p99_ms,
                  m, v);
    else
      std::printf("highest rate with 0 lost and p99 < %.0f ms, %s: none of the rates\n",
                  opt.max_p99_ms, m);
  };
  says("bridged", best.bridged);
  says("alone", best.alone);
  return 0;
}

int pipeline_bench(int argc, char** argv) {
  Options opt;
  opt.domain = 50 + static_cast<uint32_t>(getpid()) % 150;
  bool subscriber = false;
  std::string log_level = "warn";
  CLI::App app{
      "pipeline_bench: BusObserver + DdsPublisher natively, latency/loss/CPU/RSS per TPDO rate"};
  app.add_option("--rates", opt.rates, "TPDO frames per second, one run each")->delimiter(',');
  app.add_option("--seconds", opt.seconds, "seconds per run (default 3)");
  app.add_option("--nodes", opt.nodes,
                 "stepnodes on the simulated bus, TPDOs round robin (default 10)")
      ->check(CLI::Range(1, 127));
  app.add_option("--modes", opt.modes, "bridged and/or alone (default both)")
      ->delimiter(',')
      ->check(CLI::IsMember({"bridged", "alone"}));
  app.add_option("--domain", opt.domain, "DDS domain (default 50 + pid % 150)");
  app.add_option("--profiles", opt.profiles,
                 "Fast DDS XML profiles for every participant (QoS experiments)");
  app.add_option("--slice-us", opt.slice_us, "generator pacing slice (default 100 us)")
      ->check(CLI::Range(10, 100000));
  app.add_option("--max-p99-ms", opt.max_p99_ms,
                 "p99 limit for the 'highest rate' line (default 10)");
  app.add_option("--reader-depth", opt.reader_depth,
                 "subscriber history: 0 KEEP_ALL (default), N KEEP_LAST N")
      ->check(CLI::Range(0, 100'000));
  app.add_option("--sub-port-queue", opt.sub_port_queue,
                 "subscriber's shared-memory port queue (datagrams; 0: Fast DDS default 512)")
      ->check(CLI::Range(0u, 1'000'000u));
  app.add_option("--log-level", log_level, "spdlog level (default warn)");
  app.add_flag("--subscriber", subscriber, "internal: run as the subscriber process");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "pipeline_bench: %s\n", e.what());
    return 2;
  }
  spdlog::set_level(spdlog::level::from_str(log_level));
  try {
    if (subscriber)
      return bench::run_subscriber(opt.domain, opt.profiles, opt.reader_depth, opt.sub_port_queue);
    return run_publisher(opt, "/proc/self/exe");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pipeline_bench: %s\n", e.what());
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return pipeline_bench(argc, argv);
  } catch (const std::exception& e) {  // the command line itself could not be built
    std::fprintf(stderr, "pipeline_bench: %s\n", e.what());
    return 1;
  }
}
