// bridge_bench: what stepbridge costs and how fast it is, on a real bus.
//
//   bridge_bench --iface vcan0 --node 7 --bridge-pid PID [--domain 0]
//                [--rates 1000,10000,...] [--seconds 3]
//
// Needs a running stepnode (NODE) the bridge has discovered, and the bridge (PID). For
// each rate it sends TPDO2 frames of NODE's axis 1 (motor position = a sequence number,
// encoder 0) paced in 1 ms slices, and a Fast DDS reader in this process (RELIABLE, deep
// history, listener) receives the AxisPosition samples. It prints, per rate:
//   sent / received / lost (sequence numbers that never arrived),
//   latency CAN receive timestamp -> sample at this subscriber (median, p99),
//   latency publish timestamp -> sample (Fast DDS alone, the same samples), median, p99,
//   the bridge's CPU share (utime+stime over wall time) and resident memory (VmRSS).
#include <unistd.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <unordered_set>
#include <vector>

#include <stepnodePubSubTypes.h>

#include "bridge/dds/participant.hpp"
#include "bridge/dds/publisher.hpp"
#include "bridge/dds/qos.hpp"
#include "bridge/dds/types.hpp"
#include "canio/socketcan.hpp"

using namespace stepnode;
namespace efd = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

namespace {

struct Received {
  int32_t seq;
  int64_t can_to_sub_ns;
  int64_t publish_to_sub_ns;
};

class PositionListener : public efd::DataReaderListener {
 public:
  void on_data_available(efd::DataReader* reader) override {
    ::stepnode::AxisPosition p;
    efd::SampleInfo info;
    while (reader->take_next_sample(&p, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      int64_t now = static_cast<int64_t>(bridge::dds::realtime_ns());
      std::lock_guard<std::mutex> lock(mutex_);
      samples_.push_back({p.motor_position(), now - static_cast<int64_t>(p.can_time_ns()),
                          now - static_cast<int64_t>(p.publish_time_ns())});
    }
  }
  std::vector<Received> drain() {
    std::lock_guard<std::mutex> lock(mutex_);
    return std::exchange(samples_, {});
  }

 private:
  std::mutex mutex_;
  std::vector<Received> samples_;
};

struct ProcStat {
  double cpu_s = 0;
  long rss_kb = 0;
};

ProcStat proc_stat(int pid) {
  ProcStat out;
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), {});
  auto close = text.rfind(')');
  if (close != std::string::npos) {
    std::istringstream rest(text.substr(close + 2));
    std::string field;
    std::vector<std::string> fields;
    while (rest >> field) fields.push_back(field);
    // fields[0] is state (stat field 3): utime is field 14, stime 15 -> index 11, 12.
    if (fields.size() > 12)
      out.cpu_s = (std::stod(fields[11]) + std::stod(fields[12])) /
                  static_cast<double>(sysconf(_SC_CLK_TCK));
  }
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) out.rss_kb = std::stol(line.substr(6));
  return out;
}

double percentile_us(std::vector<int64_t> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  size_t i = std::min(v.size() - 1,
                      static_cast<size_t>(std::llround(p * static_cast<double>(v.size() - 1))));
  return static_cast<double>(v[i]) / 1000.0;
}

struct Options {
  std::string iface = "vcan0";
  int node = 7, bridge_pid = 0;
  uint32_t domain = 0;
  std::vector<int> rates{1000, 10000};
  double seconds = 3;
};

// A reader of the bridge's AxisPosition samples into `listener`, once the bridge's writer
// is matched (or after 5 s).
efd::DataReader* subscribe(efd::DomainParticipant* participant, PositionListener& listener) {
  bridge::dds::Naming naming;
  std::string type = bridge::dds::type_name(bridge::dds::TopicKind::AxisPosition, naming);
  bridge::dds::make_type_support(bridge::dds::TopicKind::AxisPosition, naming)
      .register_type(participant, type);
  auto* topic = participant->create_topic("AxisPosition", type, efd::TOPIC_QOS_DEFAULT);
  auto* subscriber = participant->create_subscriber(efd::SUBSCRIBER_QOS_DEFAULT);
  auto qos = bridge::dds::builtin_reader_qos(bridge::dds::TopicKind::AxisPosition, false, 100000);
  qos.resource_limits().max_instances = 16;
  qos.resource_limits().max_samples = 16 * 100000;
  auto* reader = subscriber->create_datareader(topic, qos, &listener);
  for (int i = 0; i < 500; ++i) {  // wait for the bridge's writer
    efd::SubscriptionMatchedStatus status;
    reader->get_subscription_matched_status(status);
    if (status.current_count > 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return reader;
}

// Sends `rate` TPDO2 frames a second of `node`'s axis 1 for `seconds`, in 1 ms slices, the
// motor position a sequence number from `seq` on. Returns how many were sent.
int64_t send_paced(canio::SocketCan& can, int node, int rate, double seconds, int32_t& seq) {
  const auto start = std::chrono::steady_clock::now();
  const auto total = static_cast<int64_t>(rate * seconds);
  int64_t sent = 0;
  while (sent < total) {
    auto elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    auto due = std::min<int64_t>(total, static_cast<int64_t>(elapsed * rate) + 1);
    for (; sent < due; ++sent, ++seq) {
      uint8_t d[8] = {};
      for (int b = 0; b < 4; ++b)
        d[b] = static_cast<uint8_t>(static_cast<uint32_t>(seq) >> (8 * b));
      can.send(od::CanFrame(0x280 + static_cast<uint32_t>(node), std::span<const uint8_t>(d, 8)));
    }
    can.flush();
    std::this_thread::sleep_for(std::chrono::microseconds(1000));
  }
  while (can.has_pending()) {
    can.flush();
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return sent;
}

// One rate: sends, collects what arrived, prints the row.
void run_rate(const Options& o, int rate, canio::SocketCan& can, PositionListener& listener,
              int32_t& seq) {
  listener.drain();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  listener.drain();
  const int32_t first = seq;
  ProcStat before = proc_stat(o.bridge_pid);
  const auto start = std::chrono::steady_clock::now();
  const int64_t sent = send_paced(can, o.node, rate, o.seconds, seq);
  auto wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ProcStat after = proc_stat(o.bridge_pid);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // stragglers
  auto got = listener.drain();
  std::unordered_set<int32_t> seen;
  std::vector<int64_t> can_lat, dds_lat;
  for (const auto& r : got) {
    if (r.seq < first || r.seq >= seq) continue;
    seen.insert(r.seq);
    can_lat.push_back(r.can_to_sub_ns);
    dds_lat.push_back(r.publish_to_sub_ns);
  }
  std::printf("%9d %9lld %9zu %7lld | %12.1f %12.1f | %12.1f %12.1f | %7.1f %8ld\n", rate,
              static_cast<long long>(sent), seen.size(),
              static_cast<long long>(sent) - static_cast<long long>(seen.size()),
              percentile_us(can_lat, 0.5), percentile_us(can_lat, 0.99),
              percentile_us(dds_lat, 0.5), percentile_us(dds_lat, 0.99),
              100.0 * (after.cpu_s - before.cpu_s) / wall, after.rss_kb);
  std::fflush(stdout);
}

int bench(int argc, char** argv) {
  Options o;
  CLI::App app{"bridge_bench: stepbridge latency, sustained TPDO rate, CPU share and memory"};
  app.add_option("--iface", o.iface, "CAN interface (default vcan0)");
  app.add_option("--node", o.node, "a running stepnode the bridge has discovered (default 7)")
      ->check(CLI::Range(1, 127));
  app.add_option("--bridge-pid", o.bridge_pid, "the stepbridge process (for CPU and memory)")
      ->required();
  app.add_option("--domain", o.domain, "DDS domain of the bridge (default 0)");
  app.add_option("--rates", o.rates, "TPDO frames per second, one run each")->delimiter(',');
  app.add_option("--seconds", o.seconds, "seconds per rate (default 3)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "bridge_bench: %s\n", e.what());
    return 2;
  }

  bridge::dds::ParticipantOptions po;
  po.domain = o.domain;
  po.name = "bridge_bench";
  auto* participant = bridge::dds::create_participant(po);
  PositionListener listener;
  auto* reader = subscribe(participant, listener);
  canio::SocketCan can(o.iface);
  std::printf("bridge_bench --iface %s --node %d --bridge-pid %d --domain %u --seconds %.1f\n",
              o.iface.c_str(), o.node, o.bridge_pid, o.domain, o.seconds);
  std::printf("%9s %9s %9s %7s | %12s %12s | %12s %12s | %7s %8s\n", "rate/s", "sent", "received",
              "lost", "CAN->sub p50", "p99 (us)", "DDS only p50", "p99 (us)", "CPU %", "RSS kB");
  int32_t seq = 10'000'000;
  for (int rate : o.rates) run_rate(o, rate, can, listener, seq);
  std::printf("CAN dropped by the kernel (bench socket): %llu\n",
              static_cast<unsigned long long>(can.dropped()));
  reader->set_listener(nullptr);  // before deleting: the listener must not run during teardown
  bridge::dds::delete_participant(participant);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return bench(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bridge_bench: %s\n", e.what());
    return 1;
  }
}
