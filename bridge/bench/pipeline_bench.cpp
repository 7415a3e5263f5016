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
// the runs) reads AxisPosition with a RELIABLE KEEP_ALL reader and measures latency
// (now - can_time_ns) and loss (sequence numbers that never arrived); it reports over a
// pipe.
//
// Modes, per rate:
//   bridged  frame -> queue -> bridge thread -> BusObserver -> DdsPublisher -> subscriber
//   alone    frame -> queue -> the same thread -> the same AxisPosition sample written
//            straight to a DataWriter with the same QoS (no observer, no DdsPublisher):
//            Fast DDS alone, same pacing, same wake-ups, same subscriber.
// CPU: the publishing process's CPU time minus the generator thread's (so: bridge thread
// plus every Fast DDS thread), and the bridge thread alone, over the run's wall time. RSS
// is the process's VmRSS at the end of the run.
#include <fastdds/dds/core/LoanableSequence.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <pthread.h>
#include <spawn.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iostream>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <stepnodePubSubTypes.h>

#include "bridge/dds/participant.hpp"
#include "bridge/dds/publisher.hpp"
#include "bridge/dds/qos.hpp"
#include "bridge/dds/types.hpp"
#include "bridge/observer/bus_observer.hpp"
#include "bridge/observer/tests/fake_node.hpp"

extern char** environ;

using namespace stepnode;
namespace efd = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;
using Clock = std::chrono::steady_clock;

namespace {

constexpr uint32_t kTpdo2 = 0x280;
constexpr int32_t kFirstSeq = 1'000'000;  // below: discovery snapshots, never counted

uint64_t monotonic_us() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1'000'000u + static_cast<uint64_t>(ts.tv_nsec) / 1000u;
}

double clock_s(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

double process_cpu_s() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  auto tv = [](const timeval& t) { return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) * 1e-6; };
  return tv(ru.ru_utime) + tv(ru.ru_stime);
}

long status_kb(const char* key) {
  std::ifstream status("/proc/self/status");
  std::string line;
  const size_t n = std::strlen(key);
  while (std::getline(status, line))
    if (line.compare(0, n, key) == 0) return std::stol(line.substr(n));
  return 0;
}

int64_t percentile(std::vector<int64_t>& sorted, double p) {
  if (sorted.empty()) return 0;
  size_t i = static_cast<size_t>(p * static_cast<double>(sorted.size() - 1) + 0.5);
  return sorted[std::min(i, sorted.size() - 1)];
}

void register_axis_position(efd::DomainParticipant* participant, efd::Topic*& topic) {
  bridge::dds::Naming naming;
  const auto kind = bridge::dds::TopicKind::AxisPosition;
  std::string type = bridge::dds::type_name(kind, naming);
  if (bridge::dds::make_type_support(kind, naming).register_type(participant, type) != ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("type " + type + ": registration refused");
  topic = participant->create_topic(bridge::dds::topic_name(kind, naming), type, efd::TOPIC_QOS_DEFAULT);
  if (!topic) throw std::runtime_error("topic AxisPosition: Fast DDS could not create it");
}

// ------------------------------------------------------------------------ subscriber

// Everything the reader took since the last "begin": first arrival latency per sequence
// number of the announced range.
class PositionListener : public efd::DataReaderListener {
 public:
  void begin(int32_t first, int32_t end) {
    std::lock_guard<std::mutex> lock(mutex_);
    first_ = first;
    end_ = end;
    seen_.assign(static_cast<size_t>(end - first), 0);
    latencies_.clear();
    latencies_.reserve(seen_.size());
    duplicates_ = 0;
    in_range_ = 0;
  }
  void on_data_available(efd::DataReader* reader) override {
    efd::LoanableSequence<::stepnode::AxisPosition> data;
    efd::SampleInfoSeq infos;
    while (reader->take(data, infos) == ReturnCode_t::RETCODE_OK) {
      const auto now = static_cast<int64_t>(bridge::dds::realtime_ns());
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (efd::LoanableCollection::size_type i = 0; i < infos.length(); ++i) {
          if (!infos[i].valid_data) continue;
          const ::stepnode::AxisPosition& p = data[i];
          const int32_t seq = p.motor_position();
          ++taken_;
          if (seq < first_ || seq >= end_) continue;
          uint8_t& seen = seen_[static_cast<size_t>(seq - first_)];
          if (seen) {
            ++duplicates_;
            continue;
          }
          seen = 1;
          ++in_range_;
          latencies_.push_back(now - static_cast<int64_t>(p.can_time_ns()));
        }
      }
      reader->return_loan(data, infos);
    }
  }
  // Copies out under the lock.
  void snapshot(uint64_t& taken, uint64_t& in_range, uint64_t& duplicates, std::vector<int64_t>* latencies) {
    std::lock_guard<std::mutex> lock(mutex_);
    taken = taken_;
    in_range = in_range_;
    duplicates = duplicates_;
    if (latencies) *latencies = latencies_;
  }

 private:
  std::mutex mutex_;
  int32_t first_ = 0, end_ = 0;
  std::vector<uint8_t> seen_;
  std::vector<int64_t> latencies_;
  uint64_t taken_ = 0, in_range_ = 0, duplicates_ = 0;
};

// Commands on stdin, one answer line each on stdout:
//   begin FIRST END   -> "ok"            (a run of sequence numbers [FIRST, END) follows)
//   report            -> "result RECEIVED DUPLICATES P50_NS P99_NS MAX_NS CPU_S"
//                        once all arrived, or nothing new came for 500 ms
//   quit
int run_subscriber(uint32_t domain, const std::string& profiles, int32_t depth, uint32_t port_queue) {
  if (port_queue > 0) {
    // The reader side's shared-memory port: the ring of datagram descriptors the writers
    // push into (Fast DDS default 512, 0.5 MB segment). Full means dropped; a subscriber
    // descheduled for a few ms at 80,000 samples/s overflows the default.
    std::string xml = R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles"><profiles>
<transport_descriptors>
<transport_descriptor><transport_id>bench_shm</transport_id><type>SHM</type>
<segment_size>)" + std::to_string(std::max<uint32_t>(512 * 1024, port_queue * 512)) +
                      R"(</segment_size><port_queue_capacity>)" + std::to_string(port_queue) + R"(</port_queue_capacity>
</transport_descriptor>
<transport_descriptor><transport_id>bench_udp</transport_id><type>UDPv4</type></transport_descriptor>
</transport_descriptors>
<participant profile_name=")" + std::string(bridge::dds::kParticipantProfile) + R"("><rtps>
<userTransports><transport_id>bench_shm</transport_id><transport_id>bench_udp</transport_id></userTransports>
<useBuiltinTransports>false</useBuiltinTransports></rtps></participant>
</profiles></dds>)";
    if (efd::DomainParticipantFactory::get_instance()->load_XML_profiles_string(xml.c_str(), xml.size()) !=
        ReturnCode_t::RETCODE_OK)
      throw std::runtime_error("subscriber: Fast DDS rejected the port queue profile");
  }
  bridge::dds::ParticipantOptions po;
  po.domain = domain;
  po.profiles_file = profiles;
  po.name = "pipeline_bench subscriber";
  efd::DomainParticipant* participant = bridge::dds::create_participant(po);
  efd::Topic* topic = nullptr;
  register_axis_position(participant, topic);
  efd::Subscriber* subscriber = participant->create_subscriber(efd::SUBSCRIBER_QOS_DEFAULT);
  // RELIABLE; KEEP_ALL (depth 0) with room for more than the listener ever leaves
  // untaken, or KEEP_LAST depth per instance.
  efd::DataReaderQos qos = bridge::dds::builtin_reader_qos(bridge::dds::TopicKind::AxisPosition, false, 1);
  const int32_t per_instance = depth > 0 ? depth : 100'000;
  qos.history().kind = depth > 0 ? efd::KEEP_LAST_HISTORY_QOS : efd::KEEP_ALL_HISTORY_QOS;
  qos.history().depth = per_instance;
  qos.resource_limits().max_instances = 128;  // Fast DDS: max_samples >= instances x per instance
  qos.resource_limits().max_samples_per_instance = per_instance;
  qos.resource_limits().max_samples = 128 * per_instance;
  qos.resource_limits().allocated_samples = std::min(per_instance, 4096);
  PositionListener listener;
  efd::DataReader* reader = subscriber->create_datareader(topic, qos, &listener);
  if (!reader) throw std::runtime_error("subscriber: Fast DDS refused the reader QoS");
  std::cout << "ready" << std::endl;

  std::string line;
  int32_t first = 0, end = 0;
  double cpu_at_begin = 0;
  while (std::getline(std::cin, line)) {
    std::istringstream in(line);
    std::string cmd;
    in >> cmd;
    if (cmd == "begin") {
      in >> first >> end;
      listener.begin(first, end);
      cpu_at_begin = process_cpu_s();
      std::cout << "ok" << std::endl;
    } else if (cmd == "report") {
      const auto expected = static_cast<uint64_t>(end - first);
      uint64_t taken = 0, in_range = 0, dups = 0, last_taken = ~0ull;
      auto last_change = Clock::now();
      const auto give_up = Clock::now() + std::chrono::seconds(30);
      for (;;) {
        listener.snapshot(taken, in_range, dups, nullptr);
        if (in_range >= expected || Clock::now() > give_up) break;
        if (taken != last_taken) {
          last_taken = taken;
          last_change = Clock::now();
        } else if (Clock::now() - last_change > std::chrono::milliseconds(500)) {
          break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      std::vector<int64_t> lat;
      listener.snapshot(taken, in_range, dups, &lat);
      std::sort(lat.begin(), lat.end());
      std::cout << "result " << in_range << ' ' << dups << ' ' << percentile(lat, 0.5) << ' ' << percentile(lat, 0.99)
                << ' ' << (lat.empty() ? 0 : lat.back()) << ' ' << process_cpu_s() - cpu_at_begin << std::endl;
    } else if (cmd == "quit") {
      break;
    }
  }
  reader->set_listener(nullptr);
  bridge::dds::delete_participant(participant);
  return 0;
}

// ------------------------------------------------------------------------ publisher side

struct Item {
  od::CanFrame frame;
  uint64_t can_time_ns = 0;
};

// Generator -> bridge thread, like a socket: the bridge thread sleeps until something is
// queued (or its tick is due) and then takes everything waiting at once.
class FrameQueue {
 public:
  void push(std::vector<Item>& batch) {
    if (batch.empty()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      items_.insert(items_.end(), batch.begin(), batch.end());
      pushed_ += batch.size();
    }
    batch.clear();
    cv_.notify_one();
  }
  // False when stopped. `out` gets every queued item (may be none at the deadline).
  bool take(std::vector<Item>& out, Clock::time_point deadline) {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait_until(lock, deadline, [&] { return stop_ || !items_.empty(); });
    if (stop_) return false;
    max_backlog_ = std::max(max_backlog_, items_.size());
    out.swap(items_);
    return true;
  }
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    cv_.notify_one();
  }
  uint64_t pushed() {
    std::lock_guard<std::mutex> lock(mutex_);
    return pushed_;
  }
  size_t take_max_backlog() {
    std::lock_guard<std::mutex> lock(mutex_);
    return std::exchange(max_backlog_, 0);
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<Item> items_;
  uint64_t pushed_ = 0;
  size_t max_backlog_ = 0;
  bool stop_ = false;
};

enum class Mode : int { Bridged, Alone };

// A run the main thread asks the generator for.
struct RunRequest {
  std::atomic<int> phase{0};  // 0 idle, 1 requested, 2 running, 3 done
  int rate = 0;
  int64_t total = 0;
  int32_t first_seq = 0;
};

class Subscriber {
 public:
  Subscriber(const std::string& exe, uint32_t domain, const std::string& profiles, int32_t depth,
             uint32_t port_queue) {
    int to_child[2], from_child[2];
    if (pipe(to_child) != 0 || pipe(from_child) != 0) throw std::runtime_error("pipe failed");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, to_child[0], 0);
    posix_spawn_file_actions_adddup2(&actions, from_child[1], 1);
    posix_spawn_file_actions_addclose(&actions, to_child[1]);
    posix_spawn_file_actions_addclose(&actions, from_child[0]);
    std::vector<std::string> args{exe,           "--subscriber",        "--domain", std::to_string(domain),
                                  "--reader-depth", std::to_string(depth), "--sub-port-queue",
                                  std::to_string(port_queue)};
    if (!profiles.empty()) args.insert(args.end(), {"--profiles", profiles});
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    int rc = posix_spawn(&pid_, exe.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    close(to_child[0]);
    close(from_child[1]);
    if (rc != 0) throw std::runtime_error("cannot start the subscriber: " + std::string(std::strerror(rc)));
    out_ = fdopen(to_child[1], "w");
    in_ = fdopen(from_child[0], "r");
    if (expect_line() != "ready") throw std::runtime_error("subscriber did not start");
  }
  ~Subscriber() {
    std::fputs("quit\n", out_);
    std::fclose(out_);
    std::fclose(in_);
    int status = 0;
    waitpid(pid_, &status, 0);
  }
  Subscriber(const Subscriber&) = delete;
  Subscriber& operator=(const Subscriber&) = delete;

  void begin(int32_t first, int32_t end) {
    std::fprintf(out_, "begin %d %d\n", first, end);
    std::fflush(out_);
    expect_line();
  }
  struct Result {
    uint64_t received = 0, duplicates = 0;
    int64_t p50 = 0, p99 = 0, max = 0;
    double cpu_s = 0;
  };
  Result report() {
    std::fputs("report\n", out_);
    std::fflush(out_);
    std::istringstream in(expect_line());
    std::string word;
    Result r;
    in >> word >> r.received >> r.duplicates >> r.p50 >> r.p99 >> r.max >> r.cpu_s;
    if (word != "result") throw std::runtime_error("subscriber: unexpected answer");
    return r;
  }

 private:
  std::string expect_line() {
    char buf[512];
    if (!std::fgets(buf, sizeof buf, in_)) throw std::runtime_error("subscriber exited");
    std::string s(buf);
    while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
    return s;
  }
  pid_t pid_ = 0;
  FILE* out_ = nullptr;
  FILE* in_ = nullptr;
};

// Feeds the observer what a node would answer until it has nothing more to ask.
void answer_sdo(std::vector<std::unique_ptr<bridge::test::FakeNode>>& nodes, bridge::BusObserver& observer,
                std::vector<od::CanFrame>& out) {
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

int run_publisher(const Options& opt, const std::string& exe) {
  // The subscriber first: it is up (and discovering) while this side starts.
  Subscriber sub(exe, opt.domain, opt.profiles, opt.reader_depth, opt.sub_port_queue);

  bridge::dds::PublisherOptions po;
  po.participant.domain = opt.domain;
  po.participant.profiles_file = opt.profiles;
  po.participant.name = "pipeline_bench bridge";
  bridge::dds::DdsPublisher publisher(po);

  // Fast DDS alone: its own participant, one writer, the same QoS as the bridge's
  // AxisPosition writer (built-in, or the profile's when --profiles has one).
  bridge::dds::ParticipantOptions alone_po;
  alone_po.domain = opt.domain;
  alone_po.name = "pipeline_bench alone";
  efd::DomainParticipant* alone_participant = bridge::dds::create_participant(alone_po);
  efd::Topic* alone_topic = nullptr;
  register_axis_position(alone_participant, alone_topic);
  efd::Publisher* alone_publisher = alone_participant->create_publisher(efd::PUBLISHER_QOS_DEFAULT);
  efd::DataWriter* alone_writer = alone_publisher->create_datawriter(
      alone_topic, bridge::dds::writer_qos(bridge::dds::TopicKind::AxisPosition, false, *alone_publisher));
  if (!alone_writer) throw std::runtime_error("alone: Fast DDS refused the writer QoS");

  // Nodes 1..N, one axis each, discovered over SDO like on a bus.
  bridge::ObserverConfig oc;
  bridge::BusObserver observer(publisher, oc);
  std::vector<std::unique_ptr<bridge::test::FakeNode>> nodes;
  std::vector<od::CanFrame> out;
  for (int id = 1; id <= opt.nodes; ++id) {
    nodes.push_back(std::make_unique<bridge::test::FakeNode>(
        bridge::test::FakeNodeOptions{.id = static_cast<uint8_t>(id), .axes = 1}));
    auto& n = *nodes.back();
    bridge::ObservedFrame boot;
    boot.frame = n.boot_up();
    boot.can_time_ns = bridge::dds::realtime_ns();
    observer.on_frame(boot, monotonic_us(), out);
    answer_sdo(nodes, observer, out);
    if (!observer.node_health(n.id(), monotonic_us()).discovered)
      throw std::runtime_error("node " + std::to_string(id) + " was not discovered");
  }
  // TPDO2 of axis 1 must be motor position (bytes 0..3) then encoder position: check it
  // on the real dictionary, so the generator can write the sequence number into bytes 0..3.
  nodes[0]->set_position(0, 0x12345678, 0);
  od::CanFrame probe = nodes[0]->tpdo(1);
  if (probe.id != kTpdo2 + 1 || probe.dlc != 8 || od::get_u32(probe.data.data()) != 0x12345678u)
    throw std::runtime_error("TPDO2 is not motor position + encoder position on 0x281");

  FrameQueue queue;
  RunRequest run;
  std::atomic<int> mode{static_cast<int>(Mode::Bridged)};
  std::atomic<uint64_t> processed{0};
  std::atomic<uint64_t> alone_failures{0};
  std::atomic<bool> quit{false};

  // The bridge thread: stepbridge's loop with a queue in place of the socket.
  std::thread bridge_thread([&] {
    std::vector<Item> batch;
    std::vector<od::CanFrame> sdo_out;
    const auto tick = std::chrono::milliseconds(10);
    auto next_tick = Clock::now() + tick;
    while (true) {
      batch.clear();
      if (!queue.take(batch, next_tick)) break;
      const bool alone = mode.load(std::memory_order_relaxed) == static_cast<int>(Mode::Alone);
      for (const Item& it : batch) {
        if (alone && (it.frame.id & 0x780) == kTpdo2) {
          ::stepnode::AxisPosition d;
          d.node(static_cast<uint8_t>(it.frame.id & 0x7F));
          d.axis(1);
          d.motor_position(static_cast<int32_t>(od::get_u32(&it.frame.data[0])));
          d.encoder_position(static_cast<int32_t>(od::get_u32(&it.frame.data[4])));
          d.motor_user_units(d.motor_position());
          d.encoder_user_units(d.encoder_position());
          d.can_time_ns(it.can_time_ns);
          d.publish_time_ns(bridge::dds::realtime_ns());
          if (alone_writer->write(&d, efd::HANDLE_NIL) != ReturnCode_t::RETCODE_OK) ++alone_failures;
          continue;
        }
        bridge::ObservedFrame of;
        of.frame = it.frame;
        of.can_time_ns = it.can_time_ns;
        observer.on_frame(of, monotonic_us(), sdo_out);
        answer_sdo(nodes, observer, sdo_out);
      }
      processed.fetch_add(batch.size(), std::memory_order_release);
      if (Clock::now() >= next_tick) {
        observer.on_tick(monotonic_us(), bridge::dds::realtime_ns(), sdo_out);
        answer_sdo(nodes, observer, sdo_out);
        next_tick += tick;
        if (next_tick < Clock::now()) next_tick = Clock::now() + tick;
      }
    }
  });

  // The generator: heartbeats every 100 ms always, TPDO2 frames when a run is requested.
  std::thread generator([&] {
    std::vector<Item> batch;
    auto next_heartbeat = Clock::now();
    Clock::time_point start;
    int64_t sent = 0;
    int32_t seq = 0;
    const auto slice = std::chrono::microseconds(opt.slice_us);
    while (!quit.load()) {
      const auto now = Clock::now();
      if (now >= next_heartbeat) {
        for (auto& n : nodes) batch.push_back({n->heartbeat(0x05), bridge::dds::realtime_ns()});
        next_heartbeat += std::chrono::milliseconds(100);
      }
      int phase = run.phase.load(std::memory_order_acquire);
      if (phase == 1) {
        start = now;
        sent = 0;
        seq = run.first_seq;
        run.phase.store(phase = 2);
      }
      if (phase == 2) {
        const double elapsed = std::chrono::duration<double>(now - start).count();
        const int64_t due = std::min<int64_t>(run.total, static_cast<int64_t>(elapsed * run.rate) + 1);
        const uint64_t t = bridge::dds::realtime_ns();
        for (; sent < due; ++sent, ++seq) {
          const auto node = static_cast<uint32_t>(sent % static_cast<int64_t>(nodes.size())) + 1;
          Item it;
          it.frame.id = kTpdo2 + node;
          it.frame.dlc = 8;
          od::put_u32(&it.frame.data[0], static_cast<uint32_t>(seq));
          it.can_time_ns = t;
          batch.push_back(it);
        }
        if (sent == run.total) run.phase.store(3, std::memory_order_release);
      }
      queue.push(batch);
      std::this_thread::sleep_until(now + slice);
    }
  });

  // Both writers must see the subscriber before anything is measured.
  efd::PublicationMatchedStatus alone_matched;
  for (int i = 0; i < 1000; ++i) {
    alone_writer->get_publication_matched_status(alone_matched);
    if (publisher.matched_readers(bridge::dds::TopicKind::AxisPosition) > 0 && alone_matched.current_count > 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (publisher.matched_readers(bridge::dds::TopicKind::AxisPosition) == 0 || alone_matched.current_count == 0)
    throw std::runtime_error("the subscriber did not match both writers within 10 s");
  std::this_thread::sleep_for(std::chrono::milliseconds(300));

  clockid_t generator_clock{}, bridge_clock{};
  pthread_getcpuclockid(generator.native_handle(), &generator_clock);
  pthread_getcpuclockid(bridge_thread.native_handle(), &bridge_clock);

  std::printf("pipeline_bench --domain %u --seconds %.1f --nodes %d --slice-us %d --reader-depth %d --sub-port-queue %u%s%s\n",
              opt.domain, opt.seconds, opt.nodes, opt.slice_us, opt.reader_depth, opt.sub_port_queue,
              opt.profiles.empty() ? "" : " --profiles ", opt.profiles.c_str());
  std::printf("latency = CLOCK_REALTIME at the subscriber's take - can_time_ns (frame queued); CPU = %% of one core\n");
  std::printf("CPU: proc = publishing process minus the generator thread, thread = the bridge thread, sub = the\n"
              "subscriber process, gen = the generator thread; us/smp = CPU microseconds per sample; backlog = most\n"
              "frames waiting for the bridge thread at one wake-up\n");
  std::printf("%8s %-7s %8s %8s %7s | %9s %9s %9s | %6s %7s %6s %6s | %6s %6s | %6s %7s\n", "rate/s", "mode", "achieved",
              "sent", "lost", "p50 us", "p99 us", "max us", "proc %", "thread%", "sub %", "gen %", "proc", "sub",
              "RSS MB", "backlog");
  std::printf("%8s %-7s %8s %8s %7s | %9s %9s %9s | %6s %7s %6s %6s | %6s %6s | %6s %7s\n", "", "", "", "", "", "", "",
              "", "", "", "", "", "us/smp", "us/smp", "", "");
  std::fflush(stdout);

  struct Best {
    int bridged = 0, alone = 0;
  } best;
  int32_t next_seq = kFirstSeq;
  for (int rate : opt.rates) {
    for (const std::string& m : opt.modes) {
      const Mode md = m == "alone" ? Mode::Alone : Mode::Bridged;
      mode.store(static_cast<int>(md));
      const auto total = static_cast<int64_t>(rate * opt.seconds);
      run.rate = rate;
      run.total = total;
      run.first_seq = next_seq;
      sub.begin(next_seq, next_seq + static_cast<int32_t>(total));
      next_seq += static_cast<int32_t>(total);
      const uint64_t failures_before = publisher.write_failures() + alone_failures.load();
      queue.take_max_backlog();
      const double cpu0 = process_cpu_s(), gen0 = clock_s(generator_clock), br0 = clock_s(bridge_clock);
      const auto t0 = Clock::now();
      run.phase.store(1, std::memory_order_release);
      while (run.phase.load(std::memory_order_acquire) != 3) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      const double gen_wall = std::chrono::duration<double>(Clock::now() - t0).count();
      while (processed.load(std::memory_order_acquire) < queue.pushed())
        std::this_thread::sleep_for(std::chrono::microseconds(200));
      const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
      const double cpu1 = process_cpu_s(), gen1 = clock_s(generator_clock), br1 = clock_s(bridge_clock);
      const long rss_kb = status_kb("VmRSS:");
      const size_t backlog = queue.take_max_backlog();
      run.phase.store(0);
      const Subscriber::Result r = sub.report();
      const uint64_t failures = publisher.write_failures() + alone_failures.load() - failures_before;
      const int64_t lost = total - static_cast<int64_t>(r.received);
      const double proc_s = (cpu1 - cpu0) - (gen1 - gen0);
      const auto samples = static_cast<double>(total);
      std::printf("%8d %-7s %8.0f %8lld %7lld | %9.1f %9.1f %9.1f | %6.1f %7.1f %6.1f %6.1f | %6.2f %6.2f | %6.1f %7zu%s\n",
                  rate, m.c_str(), samples / gen_wall, static_cast<long long>(total), static_cast<long long>(lost),
                  static_cast<double>(r.p50) / 1e3, static_cast<double>(r.p99) / 1e3, static_cast<double>(r.max) / 1e3,
                  100.0 * proc_s / wall, 100.0 * (br1 - br0) / wall, 100.0 * r.cpu_s / wall,
                  100.0 * (gen1 - gen0) / wall, 1e6 * proc_s / samples, 1e6 * r.cpu_s / samples,
                  static_cast<double>(rss_kb) / 1024.0, backlog,
                  failures ? (" write failures " + std::to_string(failures)).c_str() : "");
      std::fflush(stdout);
      const bool ok = lost == 0 && static_cast<double>(r.p99) < opt.max_p99_ms * 1e6 &&
                      static_cast<double>(total) / gen_wall > 0.95 * rate;
      if (ok && md == Mode::Bridged) best.bridged = std::max(best.bridged, rate);
      if (ok && md == Mode::Alone) best.alone = std::max(best.alone, rate);
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  }
  auto says = [&](const char* m, int v) {
    if (std::find(opt.modes.begin(), opt.modes.end(), m) == opt.modes.end()) return;
    if (v) std::printf("highest rate with 0 lost and p99 < %.0f ms, %s: %d frames/s\n", opt.max_p99_ms, m, v);
    else std::printf("highest rate with 0 lost and p99 < %.0f ms, %s: none of the rates\n", opt.max_p99_ms, m);
  };
  says("bridged", best.bridged);
  says("alone", best.alone);

  quit = true;
  generator.join();
  queue.stop();
  bridge_thread.join();
  bridge::dds::delete_participant(alone_participant);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  opt.domain = 50 + static_cast<uint32_t>(getpid()) % 150;
  bool subscriber = false;
  std::string log_level = "warn";
  CLI::App app{"pipeline_bench: BusObserver + DdsPublisher natively, latency/loss/CPU/RSS per TPDO rate"};
  app.add_option("--rates", opt.rates, "TPDO frames per second, one run each")->delimiter(',');
  app.add_option("--seconds", opt.seconds, "seconds per run (default 3)");
  app.add_option("--nodes", opt.nodes, "stepnodes on the simulated bus, TPDOs round robin (default 10)")
      ->check(CLI::Range(1, 127));
  app.add_option("--modes", opt.modes, "bridged and/or alone (default both)")
      ->delimiter(',')
      ->check(CLI::IsMember({"bridged", "alone"}));
  app.add_option("--domain", opt.domain, "DDS domain (default 50 + pid % 150)");
  app.add_option("--profiles", opt.profiles, "Fast DDS XML profiles for every participant (QoS experiments)");
  app.add_option("--slice-us", opt.slice_us, "generator pacing slice (default 100 us)")->check(CLI::Range(10, 100000));
  app.add_option("--max-p99-ms", opt.max_p99_ms, "p99 limit for the 'highest rate' line (default 10)");
  app.add_option("--reader-depth", opt.reader_depth, "subscriber history: 0 KEEP_ALL (default), N KEEP_LAST N")
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
    if (subscriber) return run_subscriber(opt.domain, opt.profiles, opt.reader_depth, opt.sub_port_queue);
    return run_publisher(opt, "/proc/self/exe");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pipeline_bench: %s\n", e.what());
    return 1;
  }
}
