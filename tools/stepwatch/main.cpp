// stepwatch: a supervisor-side subscriber to stepbridge's DDS topics.
//
//   stepwatch [--domain N] [--ros2 [--ros2-prefix P]] [--profiles FILE.xml] [--security-config
//   FILE.toml]
//             [--once [--wait-ms MS]] [--json] [--csv FILE] [--count N] [--duration-ms MS]
//
// Live (default): a table of every node and axis, redrawn every --interval-ms; with
// --json one JSON line per received sample instead. --once: waits until the bridge's
// writers are matched (at most --wait-ms), takes what TRANSIENT_LOCAL delivers (status and
// health of every node and axis), prints it (table, or --json one line per node and
// axis) and exits: 0 with data, 1 with none. --csv FILE logs every sample in either mode.
// Readers are polled with take() from this one thread: no listeners, no locks.
#include <spdlog/spdlog.h>
#include <unistd.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>

#include <CLI/CLI.hpp>
#include <array>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <thread>

#include "bridge/dds/participant.hpp"
#include "bridge/dds/publisher.hpp"
#include "bridge/dds/qos.hpp"
#include "bridge/dds/security.hpp"
#include "bridge/dds/types.hpp"
#include "tools/stepwatch/watch_model.hpp"

using namespace stepnode;
namespace efd = eprosima::fastdds::dds;
using bridge::dds::TopicKind;
using eprosima::fastrtps::types::ReturnCode_t;
using Clock = std::chrono::steady_clock;

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

struct Options {
  uint32_t domain = 0;
  bool ros2 = false;
  std::string ros2_prefix = "stepnode";
  std::string profiles;
  bridge::dds::SecurityFiles security;  // the [dds.security] table of --security-config
  bool once = false;
  bool json = false;
  std::string csv;
  uint32_t wait_ms = 3000;
  uint32_t interval_ms = 500;
  uint64_t count = 0;
  uint32_t duration_ms = 0;
  std::string log_level = "warn";
};

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Watcher {
 public:
  explicit Watcher(const Options& o) : options_(o) {
    naming_.ros2 = o.ros2;
    naming_.ros2_prefix = o.ros2_prefix;
    if (o.ros2) bridge::dds::validate_ros2_prefix(o.ros2_prefix);
    bridge::dds::ParticipantOptions p;
    p.domain = o.domain;
    p.profiles_file = o.profiles;
    p.name = "stepwatch";
    p.security = o.security;
    participant_ = bridge::dds::create_participant(p);
    subscriber_ = participant_->create_subscriber(efd::SUBSCRIBER_QOS_DEFAULT);
    if (!subscriber_) throw std::runtime_error("Fast DDS could not create a subscriber");
    const std::array<int32_t, bridge::dds::kTopicCount> depth{
        64, 16, 8, 32, 64};  // status, position, health, emergency, drive
    for (TopicKind kind : bridge::dds::kAllTopics) {
      size_t i = static_cast<size_t>(kind);
      std::string type = bridge::dds::type_name(kind, naming_);
      bridge::dds::make_type_support(kind, naming_).register_type(participant_, type);
      std::string name = bridge::dds::topic_name(kind, naming_);
      auto* topic = participant_->create_topic(name, type, efd::TOPIC_QOS_DEFAULT);
      if (!topic) throw std::runtime_error("topic " + name + ": Fast DDS could not create it");
      readers_[i] = subscriber_->create_datareader(
          topic,
          bridge::dds::reader_qos(kind, naming_.ros2, *subscriber_, naming_.ros2 ? 0 : depth[i]));
      // With DDS Security the usual cause is the permissions: no subscribe grant for the topic.
      if (!readers_[i] && o.security.enabled())
        throw std::invalid_argument(
            "topic " + name + ": Fast DDS refused the reader (does dds.security.permissions " +
            o.security.permissions + " grant this identity subscribe?)");
      if (!readers_[i])
        throw std::runtime_error("topic " + name + ": Fast DDS refused the reader QoS");
    }
    if (!o.csv.empty()) {
      csv_.open(o.csv, std::ios::out | std::ios::trunc);
      if (!csv_) throw UsageError("csv " + o.csv + ": cannot write file");
      csv_ << stepwatch::csv_header();
    }
  }
  ~Watcher() { bridge::dds::delete_participant(participant_); }

  // Takes every waiting sample of every reader; returns how many.
  size_t poll() {
    size_t n = 0;
    n += take<::stepnode::AxisStatus>(TopicKind::AxisStatus, [&](const auto& s, uint64_t now) {
      model_.on_status(s);
      emit(now, "axis_status", stepwatch::to_json(s), stepwatch::csv_row(now, s));
      return std::pair<uint8_t, uint8_t>{s.node(), s.axis()};
    });
    n += take<::stepnode::AxisPosition>(TopicKind::AxisPosition, [&](const auto& p, uint64_t now) {
      model_.on_position(p);
      emit(now, "axis_position", stepwatch::to_json(p), stepwatch::csv_row(now, p));
      return std::pair<uint8_t, uint8_t>{p.node(), p.axis()};
    });
    n += take<::stepnode::NodeHealth>(TopicKind::NodeHealth, [&](const auto& h, uint64_t now) {
      model_.on_health(h);
      emit(now, "node_health", stepwatch::to_json(h), stepwatch::csv_row(now, h));
      return std::pair<uint8_t, uint8_t>{h.node(), 0};
    });
    n += take<::stepnode::Emergency>(TopicKind::Emergency, [&](const auto& e, uint64_t now) {
      model_.on_emergency(e);
      emit(now, "emergency", stepwatch::to_json(e), stepwatch::csv_row(now, e));
      return std::pair<uint8_t, uint8_t>{e.node(), 0};
    });
    n += take<::stepnode::DriveStatus>(TopicKind::DriveStatus, [&](const auto& d, uint64_t now) {
      model_.on_drive(d);
      emit(now, "drive_status", stepwatch::to_json(d), stepwatch::csv_row(now, d));
      return std::pair<uint8_t, uint8_t>{d.node(), d.axis()};
    });
    if (csv_) csv_.flush();
    return n;
  }

  bool bridge_matched() const {
    for (TopicKind kind : {TopicKind::AxisStatus, TopicKind::NodeHealth}) {
      efd::SubscriptionMatchedStatus status;
      readers_[static_cast<size_t>(kind)]->get_subscription_matched_status(status);
      if (status.current_count == 0) return false;
    }
    return true;
  }
  const stepwatch::WatchModel& model() const { return model_; }
  uint64_t received() const { return received_; }

 private:
  template <class T, class OnData>
  size_t take(TopicKind kind, OnData on_data) {
    auto* reader = readers_[static_cast<size_t>(kind)];
    size_t n = 0;
    T data;
    efd::SampleInfo info;
    while (reader->take_next_sample(&data, &info) == ReturnCode_t::RETCODE_OK) {
      uint64_t now = bridge::dds::realtime_ns();
      if (info.valid_data) {
        ++n;
        ++received_;
        instances_[info.instance_handle] = on_data(data, now);
      } else if (info.instance_state != efd::ALIVE_INSTANCE_STATE) {
        auto it = instances_.find(info.instance_handle);
        if (it == instances_.end()) continue;
        auto [node, axis] = it->second;
        const char* topic = bridge::dds::idl_name(kind).data();
        // In ROS 2 mode the topics are unkeyed: one instance holds every axis, and its end
        // (the bridge left) says nothing about the last axis seen. Keyed: that axis is gone.
        if (naming_.ros2) continue;
        if (kind == TopicKind::AxisStatus || kind == TopicKind::AxisPosition ||
            kind == TopicKind::DriveStatus)
          model_.on_axis_disposed(node, axis);
        emit(now, "disposed", {{"topic", topic}, {"node", node}, {"axis", axis}},
             stepwatch::csv_disposed_row(now, topic, node, axis));
      }
    }
    return n;
  }

  void emit(uint64_t now, const char* type, nlohmann::json j, const std::string& csv_row) {
    if (csv_) csv_ << csv_row;
    if (!options_.once && options_.json) {
      j["type"] = type;
      j["recv_time_ns"] = now;
      std::cout << j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << '\n'
                << std::flush;
    }
  }

  Options options_;
  bridge::dds::Naming naming_;
  efd::DomainParticipant* participant_ = nullptr;
  efd::Subscriber* subscriber_ = nullptr;
  std::array<efd::DataReader*, bridge::dds::kTopicCount> readers_{};
  std::map<eprosima::fastrtps::rtps::InstanceHandle_t, std::pair<uint8_t, uint8_t>> instances_;
  stepwatch::WatchModel model_;
  std::ofstream csv_;
  uint64_t received_ = 0;
};

void print_snapshot(const stepwatch::WatchModel& model, bool json) {
  if (json) {
    for (const auto& j : model.snapshot())
      std::cout << j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)
                << '\n';  // names from other publishers may not be UTF-8
  } else {
    std::cout << model.table();
  }
  std::cout << std::flush;
}

int run_once(Watcher& w, const Options& o) {
  // Done when the bridge is matched, something arrived, and nothing more for longer than
  // the bridge's heartbeat period (500 ms): a historical sample whose first push was lost
  // comes with the next heartbeat. Nothing at all: wait up to --wait-ms.
  constexpr auto kQuiet = std::chrono::milliseconds(700);
  auto deadline = Clock::now() + std::chrono::milliseconds(o.wait_ms);
  auto last_data = Clock::now();
  bool matched_seen = false;
  while (Clock::now() < deadline && !g_stop) {
    if (w.poll() > 0) last_data = Clock::now();
    matched_seen = matched_seen || w.bridge_matched();
    if (matched_seen && !w.model().empty() && Clock::now() - last_data > kQuiet) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  w.poll();
  if (w.model().empty()) {
    std::fprintf(stderr, "stepwatch: no samples on DDS domain %u within %u ms (%s)\n", o.domain,
                 o.wait_ms,
                 matched_seen ? "a bridge matched but published nothing" : "no bridge found");
    return 1;
  }
  print_snapshot(w.model(), o.json);
  return 0;
}

int run_live(Watcher& w, const Options& o) {
  bool tty = isatty(STDOUT_FILENO);
  auto start = Clock::now();
  auto next_draw = start;
  while (!g_stop) {
    w.poll();
    auto now = Clock::now();
    if (o.count && w.received() >= o.count) break;
    if (o.duration_ms && now - start >= std::chrono::milliseconds(o.duration_ms)) break;
    if (!o.json && now >= next_draw) {
      if (tty) std::cout << "\033[H\033[2J";
      std::cout << "stepwatch: domain " << o.domain << ", " << w.model().samples() << " samples\n";
      print_snapshot(w.model(), false);
      if (!tty) std::cout << '\n';
      next_draw = now + std::chrono::milliseconds(o.interval_ms);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return 0;
}

Options parse(int argc, char** argv, bool& exit_now, int& exit_code) {
  Options o;
  CLI::App app{
      "stepwatch: shows stepbridge's DDS topics (axis status and position, node health, EMCY)"};
  app.add_option("--domain", o.domain, "DDS domain id 0..232 (default 0)");
  app.add_flag("--ros2", o.ros2,
               "ROS 2 names (rt/<prefix>/axis_status, stepnode::msg::dds_::AxisStatus_)");
  app.add_option("--ros2-prefix", o.ros2_prefix, "topic prefix in ROS 2 mode (default stepnode)");
  app.add_option("--profiles", o.profiles, "Fast DDS XML profiles file");
  std::string security_config;
  app.add_option("--security-config", security_config,
                 "TOML file with a [dds.security] table (DDS Security, as stepbridge's config; "
                 "other keys ignored)");
  app.add_flag("--once", o.once, "print the current status of every node and axis and exit");
  app.add_option("--wait-ms", o.wait_ms, "--once: how long to wait for the bridge (default 3000)");
  app.add_flag("--json", o.json, "JSON lines: per node and axis (--once) or per sample (live)");
  app.add_option("--csv", o.csv, "log every received sample to FILE (CSV)");
  app.add_option("--interval-ms", o.interval_ms, "live table redraw period (default 500)");
  app.add_option("--count", o.count, "live: exit after N samples")
      ->check(CLI::Range(0, 1'000'000'000));  // "-1" was taken as 2^64 - 1
  app.add_option("--duration-ms", o.duration_ms, "live: exit after MS milliseconds");
  app.add_option("--log-level", o.log_level, "trace, debug, info, warn, error, off (default warn)");
  exit_now = false;
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    exit_now = true;
    exit_code = app.exit(e);
    return o;
  } catch (const CLI::ParseError& e) {
    throw UsageError(e.what());
  }
  if (o.domain > bridge::dds::kMaxDomain)
    throw UsageError("domain " + std::to_string(o.domain) + ": must be 0..232");
  if (app.count("--ros2-prefix") && !o.ros2) throw UsageError("--ros2-prefix needs --ros2");
  if (app.count("--wait-ms") && !o.once) throw UsageError("--wait-ms needs --once");
  if (o.once && (app.count("--count") || app.count("--duration-ms")))
    throw UsageError("--count and --duration-ms are for the live mode, not --once");
  if (o.interval_ms < 10) throw UsageError("--interval-ms must be at least 10");
  // A bad argument is status 2; status 1 means "no samples" to a script running --once.
  if (!o.profiles.empty() && !std::filesystem::is_regular_file(o.profiles))
    throw UsageError("profiles " + o.profiles + ": cannot read file");
  // The bridge's own table and loader: a supervisor's file names the same six keys.
  if (!security_config.empty()) {
    o.security = bridge::dds::load_security_table(config::TomlFile(security_config));
    if (!o.security.enabled())
      throw UsageError("security config " + security_config + ": no [dds.security] table");
  }
  auto level = spdlog::level::from_str(o.log_level);
  if (level == spdlog::level::off && o.log_level != "off")
    throw UsageError("log level \"" + o.log_level + "\": unknown");
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  try {
    bool exit_now = false;
    int exit_code = 0;
    o = parse(argc, argv, exit_now, exit_code);
    if (exit_now) return exit_code;
    spdlog::set_level(spdlog::level::from_str(o.log_level));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stepwatch: %s\n", e.what());
    return 2;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  try {
    Watcher w(o);
    return o.once ? run_once(w, o) : run_live(w, o);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "stepwatch: %s\n", e.what());
    return 2;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "stepwatch: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stepwatch: %s\n", e.what());
    return 1;
  }
}
