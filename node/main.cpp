// stepnode: the node process. Connects the CANopen node to a SocketCAN interface and to
// CLOCK_MONOTONIC through an epoll loop with one timerfd, armed after every frame and tick
// for the node's earliest deadline (issue 13: an idle node sleeps), never longer than
// --tick-us.
#include <linux/can/error.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <string>

#include "canio/event_loop.hpp"
#include "canio/link_info.hpp"
#include "canio/sd_notify.hpp"
#include "canio/socketcan.hpp"
#include "node/config.hpp"
#include "node/device.hpp"
#include "od/eds.hpp"

using namespace stepnode;

namespace {

// SocketCAN error frames in CANopen terms (linux/can/error.h).
std::vector<node::BusEvent> bus_events(const canio::ReceivedFrame& r) {
  std::vector<node::BusEvent> out;
  if (r.error_class & CAN_ERR_BUSOFF) out.push_back(node::BusEvent::BusOff);
  if (r.error_class & CAN_ERR_RESTARTED) out.push_back(node::BusEvent::Restarted);
  if (r.error_class & CAN_ERR_CRTL) {
    uint8_t s = r.controller_status;
    if (s & (CAN_ERR_CRTL_RX_OVERFLOW)) out.push_back(node::BusEvent::RxOverflow);
    if (s & (CAN_ERR_CRTL_TX_OVERFLOW)) out.push_back(node::BusEvent::TxOverflow);
    if (s & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE))
      out.push_back(node::BusEvent::ErrorPassive);
    else if (s & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING))
      out.push_back(node::BusEvent::ErrorWarning);
    if (s & CAN_ERR_CRTL_ACTIVE) out.push_back(node::BusEvent::ErrorActive);
  }
  return out;
}

// When the frame reached the socket, on CLOCK_MONOTONIC (`now`): the kernel stamps it on
// CLOCK_REALTIME, so its age is measured on that clock. Without a usable stamp: now.
uint64_t arrival_us(const canio::ReceivedFrame& r, uint64_t now) {
  if (!r.kernel_time_ns) return now;
  timespec real{};
  clock_gettime(CLOCK_REALTIME, &real);
  int64_t real_now_ns = static_cast<int64_t>(real.tv_sec) * 1'000'000'000 + real.tv_nsec;
  int64_t age_us = (real_now_ns - static_cast<int64_t>(r.kernel_time_ns)) / 1000;
  if (age_us < 0 || age_us > 100'000 || static_cast<uint64_t>(age_us) > now)
    return now;  // clock stepped
  return now - static_cast<uint64_t>(age_us);
}

// CiA 305's stored bit timing against the interface's bit rate: stepnode never sets it (root
// does, with ip link; tools/lss-bit-timing is the hook), but it says when they differ.
void report_bit_timing(node::Device& device, const node::NodeConfig& cfg) {
  const auto index = device.canopen().lss().active_bit_timing();
  const auto link = index ? canio::link_info(cfg.iface) : std::nullopt;
  if (!link) return;
  const unsigned kbit = node::lss::bit_rate_kbit(*index).value_or(0);
  const std::string hook =
      "tools/lss-bit-timing " + cfg.options.state_dir.string() + " " + cfg.iface + " --apply";
  if (link->kind == "vcan")
    spdlog::warn(
        "LSS: the stored bit timing {} kbit/s cannot be applied: {} is a virtual CAN interface "
        "without a "
        "bit rate",
        kbit, cfg.iface);
  else if (!link->bit_rate)
    spdlog::warn("LSS: stored bit timing {} kbit/s; {}'s bit rate is not known (kind \"{}\")", kbit,
                 cfg.iface, link->kind);
  else if (*link->bit_rate != kbit * 1000)
    spdlog::warn(
        "LSS: the stored bit timing {} kbit/s differs from {}'s {} bit/s; apply it with `{}` "
        "(root)",
        kbit, cfg.iface, *link->bit_rate, hook);
  else spdlog::info("LSS: {} runs at the stored bit timing, {} kbit/s", cfg.iface, kbit);
}

// The node's filters as the socket takes them; error frames only of the classes the node
// turns into bus events (a bus with protocol errors would wake it for every one).
void filter_socket(canio::SocketCan& can, node::Device& device) {
  can.set_error_filter(CAN_ERR_BUSOFF | CAN_ERR_RESTARTED | CAN_ERR_CRTL);
  device.set_receive_filter_sink([&can](const std::vector<node::ReceiveFilter>& filters) {
    std::vector<canio::Filter> out;
    out.reserve(filters.size());
    for (const auto& f : filters)
      out.push_back({f.id, 0x7FF, f.frames == node::ReceiveFilter::Frames::DataAndRemote});
    can.set_filters(out);
    spdlog::debug("{}: kernel receive filters for {} CAN-IDs", can.iface(), filters.size());
  });
}

uint64_t wall_clock_us() {
  timespec real{};
  clock_gettime(CLOCK_REALTIME, &real);
  return static_cast<uint64_t>(real.tv_sec) * 1'000'000 +
         static_cast<uint64_t>(real.tv_nsec) / 1000;
}

int run(node::NodeConfig cfg) {
  canio::SocketCan can(cfg.iface);
  cfg.options.wall_clock = wall_clock_us;  // a TIME producer sends this host's time
  node::Device device(cfg.options, cfg.object_defaults,
                      [&can](const od::CanFrame& f) { can.send(f); });
  filter_socket(can, device);

  canio::EventLoop loop;
  loop.stop_on_signals();
  // The service manager (README "Running as a service"): READY once the node serves, the
  // watchdog petted by a timer of this loop, so a loop that hangs stops petting and the
  // manager restarts the node.
  canio::ServiceNotifier notifier;
  bool ready_sent = false;
  auto tell_ready_once_sent = [&] {
    // The boot-up frame must be on the bus first: a master that waits for READY and then
    // for the boot-up would miss it otherwise. A full controller queue delays it to a tick.
    if (ready_sent || can.has_pending()) return;
    ready_sent = true;
    notifier.status(device.canopen().configured()
                        ? "node " + std::to_string(device.canopen().node_id()) + " on " + cfg.iface
                        : "waiting for an LSS master on " + cfg.iface);
    notifier.ready();
  };
  if (uint64_t period = notifier.watchdog_period_us())
    loop.every(period, [&] { notifier.watchdog(); });
  // The node's timed work: one absolute timer for its earliest deadline. A frame the
  // controller could not take yet is retried within a poll period, as the tick did.
  int timer = -1;
  auto arm_for_next_deadline = [&] {
    const uint64_t now = canio::EventLoop::now_us();
    uint64_t at = std::min(device.next_deadline_us(now), now + cfg.tick_us);
    if (can.has_pending() || !ready_sent) at = std::min(at, node::poll_deadline(now));
    loop.arm_at(timer, at);
  };
  timer = loop.add_timer([&] {
    device.on_tick(canio::EventLoop::now_us());
    can.flush();
    tell_ready_once_sent();
    arm_for_next_deadline();
  });
  loop.watch(can.fd(), [&] {
    while (auto r = can.receive()) {
      uint64_t now = canio::EventLoop::now_us();
      if (r->error_frame) {
        spdlog::warn("{}: CAN error frame, class 0x{:08x} controller 0x{:02x}", cfg.iface,
                     r->error_class, r->controller_status);
        for (auto e : bus_events(*r)) device.on_bus_event(e, now);
        continue;
      }
      device.on_frame(r->frame, now, arrival_us(*r, now));
    }
    device.on_receive_overruns(can.receive_overruns(), canio::EventLoop::now_us());
    arm_for_next_deadline();  // a frame may have started a motion, a transfer, a timer
  });
  if (device.canopen().configured())
    spdlog::info("node {} on {}, {} axes, parameters in {}", device.canopen().node_id(), cfg.iface,
                 cfg.options.layout.axes, device.canopen().parameter_file().string());
  else
    spdlog::info(
        "node without a node-ID on {} (LSS-unconfigured), {} axes, LSS configuration in {}",
        cfg.iface, cfg.options.layout.axes, device.canopen().lss_file().string());
  report_bit_timing(device, cfg);
  device.start(canio::EventLoop::now_us());
  can.flush();
  tell_ready_once_sent();
  arm_for_next_deadline();
  loop.run();
  spdlog::info("stopping after {} wake-ups", loop.wakeups());
  notifier.stopping();
  can.flush();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  node::NodeConfig cfg;
  try {
    bool exit_now = false;
    int exit_code = 0;
    cfg = node::parse_command_line(argc, argv, exit_now, exit_code);
    if (exit_now) return exit_code;
    spdlog::set_level(spdlog::level::from_str(cfg.log_level));
    if (cfg.print_eds) {
      // The EDS of the device as configured (a refused mapping: its built-in record). The
      // log would land in the EDS on stdout.
      spdlog::set_level(spdlog::level::off);
      node::Device device(cfg.options, cfg.object_defaults, [](const od::CanFrame&) {});
      std::cout << od::write_eds(device.dictionary(), device.canopen().device_info());
      return 0;
    }
    return run(cfg);
  } catch (const node::UsageError& e) {
    std::fprintf(stderr, "stepnode: %s\n", node::one_line(e.what()).c_str());
    return 2;
  } catch (const canio::InterfaceError& e) {
    // The interface named is missing or not CAN: a bad argument too.
    std::fprintf(stderr, "stepnode: %s\n", node::one_line(e.what()).c_str());
    return 2;
  } catch (const std::exception& e) {
    // A runtime failure (no SocketCAN in the kernel, a socket or epoll call refused): one
    // line, status 1.
    std::fprintf(stderr, "stepnode: %s\n", node::one_line(e.what()).c_str());
    return 1;
  }
}
