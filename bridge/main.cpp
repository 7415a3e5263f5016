// stepbridge: watches a CAN bus (SocketCAN, kernel receive timestamps) and republishes
// every node's axis status and position, node health and EMCYs on DDS topics.
//
// One thread: an epoll loop reads the socket on readable, at most kFramesPerTurn frames a
// wake-up (every frame to the observer, the SDO requests it answers with go out at once;
// the rest is read on the next turn, after the timers), and a timerfd tick drives the
// observer's timers. SIGINT/SIGTERM end the loop; then every known node's axes are
// disposed, the writers get a moment to deliver, and the participant is deleted.
#include <linux/can/error.h>
#include <spdlog/spdlog.h>

#include <pthread.h>

#include <csignal>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bridge/config.hpp"
#include "bridge/dds/publisher.hpp"
#include "bridge/dds/security.hpp"
#include "bridge/observer/bus_observer.hpp"
#include "bridge/observer/receive_budget.hpp"
#include "canio/event_loop.hpp"
#include "canio/sd_notify.hpp"
#include "canio/socketcan.hpp"

using namespace stepnode;

namespace {

// SIGINT/SIGTERM blocked before any thread exists: Fast DDS starts threads when the
// participant is created, and a thread that does not block them would take the default
// action (the process dies without disposing). The event loop reads them via signalfd.
void block_stop_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

// Frames the kernel dropped from the socket's full queue count in NodeHealth.bus_overruns;
// the log says so at most once a second (a flood would otherwise log every wake-up).
class OverrunLog {
 public:
  explicit OverrunLog(std::string iface) : iface_(std::move(iface)) {}
  void note(uint64_t lost, uint64_t now_us) {
    lost_ += lost;
    if (lost_ == 0 || now_us - last_us_ < 1'000'000) return;
    spdlog::warn("{}: {} frames dropped from the full receive queue (bus_overruns)", iface_, lost_);
    lost_ = 0;
    last_us_ = now_us;
  }

 private:
  std::string iface_;
  uint64_t lost_ = 0, last_us_ = 0;
};

int run(const bridge::BridgeConfig& cfg) {
  block_stop_signals();
  canio::SocketCan can(cfg.iface);  // throws: no such interface, not a CAN device
  // The bridge hears the whole bus: a full bus of 127 nodes sends 1,270 heartbeats a second
  // and, at an NMT start of all, hundreds of TPDOs at once. The kernel's default queue (about
  // 200 KiB, charged per frame's buffer) is asked to grow to 1 MiB so that such a burst waits
  // while DDS publishes; the size granted is logged.
  spdlog::info("{}: receive buffer {} bytes", cfg.iface, can.request_receive_buffer(1 << 20));

  bridge::dds::PublisherOptions options;
  options.participant.domain = cfg.domain;
  options.participant.profiles_file = cfg.profiles;
  options.participant.name = "stepbridge " + cfg.iface;
  options.participant.security = cfg.dds_security;
  options.naming.ros2 = cfg.ros2;
  options.naming.ros2_prefix = cfg.ros2_prefix;
  bridge::dds::DdsPublisher publisher(options);

  bridge::ObserverConfig observer_config;
  observer_config.heartbeat_timeout_ms = cfg.heartbeat_timeout_ms;
  observer_config.sdo_timeout_ms = cfg.sdo_timeout_ms;
  observer_config.sdo_channels = cfg.sdo_channels;
  observer_config.sdo_max_outstanding = cfg.sdo_max_outstanding;
  observer_config.sdo_rate_per_s = cfg.sdo_rate_per_s;
  observer_config.network_time = cfg.network_time;
  bridge::BusObserver observer(publisher, observer_config);

  std::vector<od::CanFrame> out;
  auto send_out = [&] {
    for (const auto& f : out) can.send(f);
    out.clear();
  };

  OverrunLog overruns(cfg.iface);
  canio::EventLoop loop;
  loop.stop_on_signals();
  loop.watch(can.fd(), [&] {
    // A burst of TPDOs is one wake-up, but a bounded one (bridge/observer/receive_budget.hpp):
    // under a flood the timers and SIGTERM still get their turn.
    bridge::handle_frames([&] { return can.receive(); },
                          [&](const canio::ReceivedFrame& r) {
                            bridge::ObservedFrame frame;
                            frame.frame = r.frame;
                            frame.can_time_ns = r.kernel_time_ns;
                            frame.error_frame = r.error_frame;
                            frame.error_class = r.error_class;
                            frame.controller_status = r.controller_status;
                            observer.on_frame(frame, canio::EventLoop::now_us(), out);
                            send_out();
                          });
    overruns.note(observer.on_socket_overruns(can.receive_overruns()), canio::EventLoop::now_us());
    can.flush();
  });
  loop.every(uint64_t{cfg.tick_ms} * 1000, [&] {
    observer.on_tick(canio::EventLoop::now_us(), bridge::dds::realtime_ns(), out);
    send_out();
    can.flush();
  });

  // The service manager (README "Running as a service"): the participant and the CAN
  // socket exist by now, so the bridge serves; the watchdog is a timer of this loop, so a
  // hung loop stops petting.
  canio::ServiceNotifier notifier;
  if (uint64_t period = notifier.watchdog_period_us())
    loop.every(period, [&] { notifier.watchdog(); });

  spdlog::info("stepbridge on {}, DDS domain {}{}{}", cfg.iface, cfg.domain,
               cfg.ros2 ? ", ROS 2 naming" : "",
               cfg.dds_security.enabled() ? ", DDS Security" : "");
  notifier.status("bridging " + cfg.iface + " to DDS domain " + std::to_string(cfg.domain));
  notifier.ready();
  loop.run();

  spdlog::info("stopping: disposing axis instances");
  notifier.stopping();
  observer.dispose_all();
  publisher.wait_acknowledged(500);
  spdlog::info("{} samples written, {} write failures", publisher.written(),
               publisher.write_failures());
  return 0;  // ~DdsPublisher deletes the participant
}

}  // namespace

int main(int argc, char** argv) {
  bridge::BridgeConfig cfg;
  try {
    bool exit_now = false;
    int exit_code = 0;
    cfg = bridge::parse_bridge_command_line(argc, argv, exit_now, exit_code);
    if (exit_now) return exit_code;
    spdlog::set_level(spdlog::level::from_str(cfg.log_level));
    // A wrong DDS Security file is bad input like a wrong option: said before the bus is opened.
    if (cfg.dds_security.enabled()) bridge::dds::check_security_files(cfg.dds_security);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stepbridge: %s\n", e.what());
    return 2;
  }
  try {
    return run(cfg);
  } catch (const canio::InterfaceError& e) {
    // The interface missing or not CAN: bad input as for stepnode, status 2, one line.
    std::fprintf(stderr, "stepbridge: %s\n", e.what());
    return 2;
  } catch (const std::invalid_argument& e) {
    // A ROS 2 prefix that is not a valid ROS 2 name (bridge/dds/naming.hpp), a DDS Security
    // file that is missing or wrong (bridge/dds/security.hpp): bad input.
    std::fprintf(stderr, "stepbridge: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    // A runtime failure (the DDS participant could not be created, a socket call): 1.
    std::fprintf(stderr, "stepbridge: %s\n", e.what());
    return 1;
  }
}
