#include "node/node_process.hpp"

#include <linux/can/error.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <ctime>
#include <optional>
#include <string>

#include "canio/arrival_clock.hpp"
#include "canio/event_loop.hpp"
#include "canio/link_config.hpp"
#include "canio/link_info.hpp"
#include "canio/sd_notify.hpp"
#include "canio/send_drain.hpp"
#include "canio/socketcan.hpp"
#include "node/bit_timing_switch.hpp"
#include "node/node_id_list.hpp"
#include "node/node_set.hpp"

namespace stepnode::node {
namespace {

// SocketCAN error frames in CANopen terms (linux/can/error.h).
std::vector<BusEvent> bus_events(const canio::ReceivedFrame& r) {
  std::vector<BusEvent> out;
  if (r.error_class & CAN_ERR_BUSOFF) out.push_back(BusEvent::BusOff);
  if (r.error_class & CAN_ERR_RESTARTED) out.push_back(BusEvent::Restarted);
  if (r.error_class & CAN_ERR_CRTL) {
    uint8_t s = r.controller_status;
    if (s & (CAN_ERR_CRTL_RX_OVERFLOW)) out.push_back(BusEvent::RxOverflow);
    if (s & (CAN_ERR_CRTL_TX_OVERFLOW)) out.push_back(BusEvent::TxOverflow);
    if (s & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE))
      out.push_back(BusEvent::ErrorPassive);
    else if (s & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING))
      out.push_back(BusEvent::ErrorWarning);
    if (s & CAN_ERR_CRTL_ACTIVE) out.push_back(BusEvent::ErrorActive);
  }
  return out;
}

// CiA 305's stored bit timing against the interface's bit rate. With --apply-bit-timing the
// node sets a CAN controller to it; otherwise root does (ip link; tools/lss-bit-timing is
// the hook) and the node says when they differ.
void report_bit_timing(Device& device, const NodeConfig& cfg) {
  const auto index = device.canopen().lss().active_bit_timing();
  const auto link = index ? canio::link_info(cfg.iface) : std::nullopt;
  if (!link) return;
  const unsigned kbit = lss::bit_rate_kbit(*index).value_or(0);
  const std::string hook =
      "tools/lss-bit-timing " + cfg.options.state_dir.string() + " " + cfg.iface + " --apply";
  if (link->kind == "vcan") {
    spdlog::warn(
        "LSS: the stored bit timing {} kbit/s cannot be applied: {} is a virtual CAN interface "
        "without a bit rate",
        kbit, cfg.iface);
  } else if (link->bit_rate == kbit * 1000) {
    spdlog::info("LSS: {} runs at the stored bit timing, {} kbit/s", cfg.iface, kbit);
  } else if (cfg.apply_bit_timing) {
    const std::string error = canio::set_can_bit_rate(cfg.iface, kbit * 1000);
    if (error.empty())
      spdlog::info("LSS: {} set to the stored bit timing, {} kbit/s", cfg.iface, kbit);
    else spdlog::error("LSS: the stored bit timing {} kbit/s was not applied: {}", kbit, error);
  } else if (!link->bit_rate) {
    spdlog::warn("LSS: stored bit timing {} kbit/s; {}'s bit rate is not known (kind \"{}\")", kbit,
                 cfg.iface, link->kind);
  } else {
    spdlog::warn(
        "LSS: the stored bit timing {} kbit/s differs from {}'s {} bit/s; apply it with `{}` "
        "(root) or run the node with --apply-bit-timing",
        kbit, cfg.iface, *link->bit_rate, hook);
  }
}

uint64_t wall_clock_us() {
  timespec real{};
  clock_gettime(CLOCK_REALTIME, &real);
  return static_cast<uint64_t>(real.tv_sec) * 1'000'000 +
         static_cast<uint64_t>(real.tv_nsec) / 1000;
}

class NodeProcess {
 public:
  explicit NodeProcess(const NodeConfig& cfg)
      : cfg_(cfg),
        can_(cfg.iface),
        bit_timing_([this](uint32_t rate) { return canio::set_can_bit_rate(cfg_.iface, rate); }),
        set_(
            options_per_node(with_process_hooks(cfg.options), cfg.node_ids), cfg.object_defaults,
            [this](const od::CanFrame& f) { return send(f); }, cfg.tick_us) {
    filter_socket();
    // With many nodes behind one socket a burst for all of them (a master's SDO round, NMT,
    // the answers it provokes) must queue as it would in their separate processes' sockets.
    // One node keeps the kernel's default. (Before, 8 KiB per node replaced the default,
    // so 2 to 12 nodes had less than one alone: found in review.)
    if (set_.size() > 1) {
      const size_t granted =
          can_.request_receive_buffer(receive_buffer_request(set_.size(), can_.receive_buffer()));
      spdlog::info("{}: receive buffer {} bytes for {} nodes", cfg.iface, granted, set_.size());
    }
  }

  int run();

 private:
  // The host's wall clock for TIME producers; the bit timing switch, when the node applies it.
  NodeOptions with_process_hooks(NodeOptions o) {
    o.wall_clock = wall_clock_us;
    if (cfg_.apply_bit_timing)
      o.activate_bit_timing = [this](unsigned kbit, uint16_t delay_ms, uint64_t now_us) {
        bit_timing_.activate(kbit, delay_ms, now_us);
        arm_for_next_deadline();
      };
    return o;
  }
  // Every frame of every node; none while a bit timing switch keeps the node silent (false:
  // the other nodes of the process do not hear it either).
  bool send(const od::CanFrame& f) {
    if (bit_timing_.active() && bit_timing_.silent(canio::EventLoop::now_us())) {
      bit_timing_.dropped_one();
      return false;
    }
    can_.send(f);
    return true;
  }
  void filter_socket();
  void tell_ready_once_sent();
  void arm_for_next_deadline();
  void on_readable();
  void log_nodes();

  const NodeConfig& cfg_;
  canio::SocketCan can_;
  BitTimingSwitch bit_timing_;  // before set_: the nodes' hooks reach it
  NodeSet set_;
  canio::EventLoop loop_;
  // The service manager (README "Running as a service"): READY once the nodes serve, the
  // watchdog petted by a timer of this loop, so a loop that hangs stops petting and the
  // manager restarts the process.
  canio::ServiceNotifier notifier_;
  // Frames the controller could not take yet go out when the socket is writable again.
  canio::SendDrain drain_{loop_, can_.fd(), [this] { return can_.flush(); },
                          [this] {
                            tell_ready_once_sent();
                            arm_for_next_deadline();
                          }};
  bool ready_sent_ = false;
  int timer_ = -1;
};

// The set's filters as the socket takes them; error frames only of the classes the nodes
// turn into bus events (a bus with protocol errors would wake the process for every one).
// Above the kernel's 512 filters (127 nodes have more) the socket takes every frame and
// the set routes them in software.
void NodeProcess::filter_socket() {
  can_.set_error_filter(CAN_ERR_BUSOFF | CAN_ERR_RESTARTED | CAN_ERR_CRTL);
  set_.set_receive_filter_sink([this](const std::vector<ReceiveFilter>& filters) {
    std::vector<canio::Filter> out;
    out.reserve(filters.size());
    for (const auto& f : filters)
      out.push_back({f.id, 0x7FF, f.frames == ReceiveFilter::Frames::DataAndRemote});
    can_.set_filters(out);
    if (filters.empty()) spdlog::debug("{}: no kernel receive filter (every frame)", can_.iface());
    else spdlog::debug("{}: kernel receive filters for {} CAN-IDs", can_.iface(), filters.size());
  });
}

void NodeProcess::tell_ready_once_sent() {
  // The boot-up frames must be on the bus first: a master that waits for READY and then
  // for a boot-up would miss it otherwise. A full controller queue delays it to a tick.
  if (ready_sent_ || can_.has_pending()) return;
  ready_sent_ = true;
  Device& first = set_.device(0);
  if (set_.size() > 1) notifier_.status(std::to_string(set_.size()) + " nodes on " + cfg_.iface);
  else
    notifier_.status(first.canopen().configured()
                         ? "node " + std::to_string(first.canopen().node_id()) + " on " + cfg_.iface
                         : "waiting for an LSS master on " + cfg_.iface);
  notifier_.ready();
}

// The nodes' timed work: one absolute timer for the earliest deadline of all. A frame the
// controller could not take yet waits for the socket's writability (SendDrain), or, when
// a queue below the socket refuses it, is retried within a poll period as the tick did.
void NodeProcess::arm_for_next_deadline() {
  const uint64_t now = canio::EventLoop::now_us();
  uint64_t at =
      std::min({set_.next_deadline_us(), now + cfg_.tick_us, bit_timing_.next_deadline_us()});
  drain_.update(can_.has_pending());
  if (drain_.needs_poll()) at = std::min(at, poll_deadline(now));
  loop_.arm_at(timer_, at);
}

void NodeProcess::on_readable() {
  // The clocks tied once a batch, at its first stamped frame (canio/arrival_clock.hpp).
  std::optional<int64_t> realtime_offset;
  while (auto r = can_.receive()) {
    uint64_t now = canio::EventLoop::now_us();
    if (r->error_frame) {
      spdlog::warn("{}: CAN error frame, class 0x{:08x} controller 0x{:02x}", cfg_.iface,
                   r->error_class, r->controller_status);
      for (auto e : bus_events(*r)) set_.on_bus_event(e, now);
      continue;
    }
    if (r->kernel_time_ns && !realtime_offset) realtime_offset = canio::realtime_offset_ns();
    set_.on_frame(r->frame, now,
                  canio::arrival_us(r->kernel_time_ns, realtime_offset.value_or(0), now));
  }
  set_.on_receive_overruns(can_.receive_overruns(), canio::EventLoop::now_us());
  arm_for_next_deadline();  // a frame may have started a motion, a transfer, a timer
}

void NodeProcess::log_nodes() {
  for (size_t i = 0; i < set_.size(); ++i) {
    CanopenNode& n = set_.device(i).canopen();
    // Many nodes: one line for the set, the nodes' own at debug.
    const auto level = set_.size() > 1 ? spdlog::level::debug : spdlog::level::info;
    if (n.configured())
      spdlog::log(level, "node {} on {}, {} axes, parameters in {}", n.node_id(), cfg_.iface,
                  cfg_.options.layout.axes, n.parameter_file().string());
    else
      spdlog::log(
          level,
          "node without a node-ID on {} (LSS-unconfigured), {} axes, LSS configuration in {}",
          cfg_.iface, cfg_.options.layout.axes, n.lss_file().string());
    report_bit_timing(set_.device(i), cfg_);
  }
  if (set_.size() > 1)
    spdlog::info("{} nodes ({}..{}) on {}, {} axes each, parameters in {}", set_.size(),
                 set_.device(0).canopen().node_id(),
                 set_.device(set_.size() - 1).canopen().node_id(), cfg_.iface,
                 cfg_.options.layout.axes, cfg_.options.state_dir.string());
}

int NodeProcess::run() {
  loop_.stop_on_signals();
  if (uint64_t period = notifier_.watchdog_period_us())
    loop_.every(period, [this] { notifier_.watchdog(); });
  timer_ = loop_.add_timer([this] {
    bit_timing_.on_tick(canio::EventLoop::now_us());
    set_.on_tick(canio::EventLoop::now_us());
    can_.flush();
    tell_ready_once_sent();
    arm_for_next_deadline();
  });
  loop_.watch(can_.fd(), [this] { on_readable(); });
  log_nodes();
  set_.start(canio::EventLoop::now_us());
  can_.flush();
  tell_ready_once_sent();
  arm_for_next_deadline();
  loop_.run();
  spdlog::info("stopping after {} wake-ups", loop_.wakeups());
  notifier_.stopping();
  can_.flush();
  return 0;
}

}  // namespace

int run_node_process(const NodeConfig& cfg) { return NodeProcess(cfg).run(); }

}  // namespace stepnode::node
