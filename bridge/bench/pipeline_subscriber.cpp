// pipeline_bench's subscriber process, and the publishing process's end of it
// (SubscriberProcess): a RELIABLE reader of AxisPosition that measures
// latency (now - can_time_ns) and loss (sequence numbers that never arrived) of each run
// the publishing process announces, and reports over a pipe (stdin, stdout).
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <fastdds/dds/core/LoanableSequence.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <stepnodePubSubTypes.h>

#include "bridge/bench/pipeline_bench.hpp"
#include "bridge/dds/participant.hpp"
#include "bridge/dds/publisher.hpp"
#include "bridge/dds/qos.hpp"
#include "bridge/dds/types.hpp"

namespace stepnode::bench {

namespace efd = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

// ---- shared with the publishing process (pipeline_bench.hpp)

double process_cpu_s() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  auto tv = [](const timeval& t) {
    return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) * 1e-6;
  };
  return tv(ru.ru_utime) + tv(ru.ru_stime);
}

double clock_s(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

long status_kb(const char* key) {
  std::ifstream status("/proc/self/status");
  std::string line;
  const size_t n = std::strlen(key);
  while (std::getline(status, line))
    if (line.compare(0, n, key) == 0) return std::stol(line.substr(n));
  return 0;
}

int64_t percentile(const std::vector<int64_t>& sorted, double p) {
  if (sorted.empty()) return 0;
  const auto i = static_cast<size_t>(std::llround(p * static_cast<double>(sorted.size() - 1)));
  return sorted[std::min(i, sorted.size() - 1)];
}

efd::Topic* register_axis_position(efd::DomainParticipant* participant) {
  bridge::dds::Naming naming;
  const auto kind = bridge::dds::TopicKind::AxisPosition;
  std::string type = bridge::dds::type_name(kind, naming);
  if (bridge::dds::make_type_support(kind, naming).register_type(participant, type) !=
      ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("type " + type + ": registration refused");
  efd::Topic* topic = participant->create_topic(bridge::dds::topic_name(kind, naming), type,
                                                efd::TOPIC_QOS_DEFAULT);
  if (!topic) throw std::runtime_error("topic AxisPosition: Fast DDS could not create it");
  return topic;
}

// ---- the subscriber process

namespace {

using Clock = std::chrono::steady_clock;

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
  void snapshot(uint64_t& taken, uint64_t& in_range, uint64_t& duplicates,
                std::vector<int64_t>* latencies) {
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

// The reader side's shared-memory port: the ring of datagram descriptors the writers push
// into (Fast DDS default 512, 0.5 MB segment). Full means dropped; a subscriber descheduled
// for a few ms at 80,000 samples/s overflows the default.
void load_port_queue_profile(uint32_t port_queue) {
  std::string xml = R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles"><profiles>
<transport_descriptors>
<transport_descriptor><transport_id>bench_shm</transport_id><type>SHM</type>
<segment_size>)" + std::to_string(std::max<uint32_t>(512 * 1024, port_queue * 512)) +
                    R"(</segment_size><port_queue_capacity>)" + std::to_string(port_queue) +
                    R"(</port_queue_capacity>
</transport_descriptor>
<transport_descriptor><transport_id>bench_udp</transport_id><type>UDPv4</type></transport_descriptor>
</transport_descriptors>
<participant profile_name=")" +
                    std::string(bridge::dds::kParticipantProfile) + R"("><rtps>
<userTransports><transport_id>bench_shm</transport_id><transport_id>bench_udp</transport_id></userTransports>
<useBuiltinTransports>false</useBuiltinTransports></rtps></participant>
</profiles></dds>)";
  if (efd::DomainParticipantFactory::get_instance()->load_XML_profiles_string(
          xml.c_str(), xml.size()) != ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("subscriber: Fast DDS rejected the port queue profile");
}

// RELIABLE; KEEP_ALL (depth 0) with room for more than the listener ever leaves untaken,
// or KEEP_LAST depth per instance.
efd::DataReader* create_reader(efd::DomainParticipant* participant, int32_t depth,
                               PositionListener& listener) {
  efd::Topic* topic = register_axis_position(participant);
  efd::Subscriber* subscriber = participant->create_subscriber(efd::SUBSCRIBER_QOS_DEFAULT);
  efd::DataReaderQos qos =
      bridge::dds::builtin_reader_qos(bridge::dds::TopicKind::AxisPosition, false, 1);
  const int32_t per_instance = depth > 0 ? depth : 100'000;
  qos.history().kind = depth > 0 ? efd::KEEP_LAST_HISTORY_QOS : efd::KEEP_ALL_HISTORY_QOS;
  qos.history().depth = per_instance;
  qos.resource_limits().max_instances = 128;  // Fast DDS: max_samples >= instances x per instance
  qos.resource_limits().max_samples_per_instance = per_instance;
  qos.resource_limits().max_samples = 128 * per_instance;
  qos.resource_limits().allocated_samples = std::min(per_instance, 4096);
  efd::DataReader* reader = subscriber->create_datareader(topic, qos, &listener);
  if (!reader) throw std::runtime_error("subscriber: Fast DDS refused the reader QoS");
  return reader;
}

// The "result" line of the run [first, end): once all arrived, or nothing new came for
// 500 ms (30 s at most).
void report(PositionListener& listener, int32_t first, int32_t end, double cpu_at_begin) {
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
  std::cout << "result " << in_range << ' ' << dups << ' ' << percentile(lat, 0.5) << ' '
            << percentile(lat, 0.99) << ' ' << (lat.empty() ? 0 : lat.back()) << ' '
            << process_cpu_s() - cpu_at_begin << std::endl;
}

}  // namespace

// Commands on stdin, one answer line each on stdout:
//   begin FIRST END   -> "ok"            (a run of sequence numbers [FIRST, END) follows)
//   report            -> "result RECEIVED DUPLICATES P50_NS P99_NS MAX_NS CPU_S"
//                        once all arrived, or nothing new came for 500 ms
//   quit
int run_subscriber(uint32_t domain, const std::string& profiles, int32_t depth,
                   uint32_t port_queue) {
  if (port_queue > 0) load_port_queue_profile(port_queue);
  bridge::dds::ParticipantOptions po;
  po.domain = domain;
  po.profiles_file = profiles;
  po.name = "pipeline_bench subscriber";
  efd::DomainParticipant* participant = bridge::dds::create_participant(po);
  PositionListener listener;
  efd::DataReader* reader = create_reader(participant, depth, listener);
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
      report(listener, first, end, cpu_at_begin);
    } else if (cmd == "quit") {
      break;
    }
  }
  reader->set_listener(nullptr);
  bridge::dds::delete_participant(participant);
  return 0;
}

SubscriberProcess::SubscriberProcess(const std::string& exe, uint32_t domain,
                                     const std::string& profiles, int32_t depth,
                                     uint32_t port_queue) {
  int to_child[2], from_child[2];
  if (pipe(to_child) != 0 || pipe(from_child) != 0) throw std::runtime_error("pipe failed");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, to_child[0], 0);
  posix_spawn_file_actions_adddup2(&actions, from_child[1], 1);
  posix_spawn_file_actions_addclose(&actions, to_child[1]);
  posix_spawn_file_actions_addclose(&actions, from_child[0]);
  std::vector<std::string> args{exe,
                                "--subscriber",
                                "--domain",
                                std::to_string(domain),
                                "--reader-depth",
                                std::to_string(depth),
                                "--sub-port-queue",
                                std::to_string(port_queue)};
  if (!profiles.empty()) args.insert(args.end(), {"--profiles", profiles});
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  int rc = posix_spawn(&pid_, exe.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(to_child[0]);
  close(from_child[1]);
  if (rc != 0)
    throw std::runtime_error("cannot start the subscriber: " + std::string(std::strerror(rc)));
  out_ = fdopen(to_child[1], "w");
  in_ = fdopen(from_child[0], "r");
  if (expect_line() != "ready") throw std::runtime_error("subscriber did not start");
}

SubscriberProcess::~SubscriberProcess() {
  std::fputs("quit\n", out_);
  std::fclose(out_);
  std::fclose(in_);
  int status = 0;
  waitpid(pid_, &status, 0);
}

void SubscriberProcess::begin(int32_t first, int32_t end) {
  std::fprintf(out_, "begin %d %d\n", first, end);
  std::fflush(out_);
  expect_line();
}

SubscriberProcess::Result SubscriberProcess::report() {
  std::fputs("report\n", out_);
  std::fflush(out_);
  std::istringstream in(expect_line());
  std::string word;
  Result r;
  in >> word >> r.received >> r.duplicates >> r.p50 >> r.p99 >> r.max >> r.cpu_s;
  if (word != "result") throw std::runtime_error("subscriber: unexpected answer");
  return r;
}

std::string SubscriberProcess::expect_line() {
  char buf[512];
  if (!std::fgets(buf, sizeof buf, in_)) throw std::runtime_error("subscriber exited");
  std::string s(buf);
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  return s;
}

}  // namespace stepnode::bench
