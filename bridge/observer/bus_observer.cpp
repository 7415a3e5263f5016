// BusObserver: routes each frame to the part that understands it and keeps one record
// per node (heartbeat, SDO channel, discovery cursor, health). Routing order matters:
// TPDO COB-IDs are looked up first (a remapped TPDO may use any free identifier), then
// the pre-defined connection set (CiA 301 7.3.3).
#include "bridge/observer/bus_observer.hpp"

#include <array>
#include <cstdint>

#include "bridge/observer/bus_error_counter.hpp"
#include "bridge/observer/discovery_plan.hpp"
#include "bridge/observer/emcy_decoder.hpp"
#include "bridge/observer/heartbeat_monitor.hpp"
#include "bridge/observer/network_time.hpp"
#include "bridge/observer/retry_backoff.hpp"
#include "bridge/observer/sdo_channel.hpp"
#include "bridge/observer/tpdo_decoder.hpp"
#include "bridge/observer/transfer_pacer.hpp"
#include "node/profiles/cia402/objects.hpp"

namespace stepnode::bridge {
namespace {

constexpr uint16_t kHeartbeatProducerTime = 0x1017;
constexpr uint16_t kPdoParamsFirst = 0x1800;  // TPDO communication 0x1800.., mapping 0x1A00..
constexpr uint16_t kPdoParamsLast = 0x1BFF;

NodeSdoChannel channel_of(uint8_t id, const ObserverConfig& c) {
  for (const NodeSdoChannel& ch : c.sdo_channels)
    if (ch.node == id) return ch;
  return NodeSdoChannel{id, 0, 0};  // 0: SdoChannel takes the default channel
}

struct Node {
  Node(uint8_t id, const ObserverConfig& c, NodeSdoChannel ch = {})
      : sdo(id, uint64_t{c.sdo_timeout_ms} * 1000, uint64_t{c.sdo_quiet_ms} * 1000,
            c.own_frames_echoed, ch.client_to_server, ch.server_to_client),
        backoff(c.retry_initial_ms, c.retry_max_ms) {
    health.node = id;
  }
  HeartbeatMonitor heartbeat;
  SdoChannel sdo;
  DiscoveryPlan plan;
  RetryBackoff backoff;
  NodeHealthSample health;     // counters and last EMCY live here between publications
  uint8_t published_axes = 0;  // axis instances the sink may hold (disposed on loss)
  uint64_t last_health_us = 0;
  // After discovery: CiA 402 axes (bit per 0-based axis) whose 603Fh is to be read again
  // (TpdoDecoder::take_stale_error_codes), and the one being read.
  uint8_t error_code_reads = 0;
  bool refreshing = false;
  uint8_t refresh_axis = 0;
  bool paced = false;       // its transfer in flight is counted by the pacer
  uint32_t read_epoch = 0;  // the plan's epoch when its read in flight was started
};

bool sdo_allowed(NodeState s) {
  // CiA 301 7.3.2.2.1: SDO works in pre-operational and operational. The boot-up message
  // is sent on entering pre-operational.
  return s == NodeState::BootUp || s == NodeState::PreOperational || s == NodeState::Operational;
}

}  // namespace

struct BusObserver::Impl {
  Impl(SampleSink& s, const ObserverConfig& c)
      : sink(s), config(c), tpdo(s), pacer(c.sdo_max_outstanding, c.sdo_rate_per_s) {
    // No clock and no global RNG in here; ASLR makes the address differ between two
    // bridge processes, which is all the jitter needs.
    random = c.random_seed ? c.random_seed
                           : static_cast<uint32_t>(reinterpret_cast<uintptr_t>(this) >> 4) | 1u;
    for (const NodeSdoChannel& ch : c.sdo_channels)
      for (uint32_t cob_id : {ch.client_to_server, ch.server_to_client})
        if (cob_id <= 0x7FF) sdo_channel_node[cob_id] = ch.node;
  }

  SampleSink& sink;
  ObserverConfig config;
  TpdoDecoder tpdo;
  BusCounters counters;
  std::array<std::unique_ptr<Node>, kNodeIds> nodes;
  // SDO traffic to nodes not known yet: the quiet wait must count it when they appear.
  std::array<uint64_t, kNodeIds> early_sdo_us{};
  // CAN-ID -> node, for the SDO channels of the bridge's own (config.sdo_channels).
  std::array<uint8_t, 0x800> sdo_channel_node{};
  uint32_t random = 1;           // xorshift32 state for the collision jitter
  TransferPacer pacer;           // the bridge's transfers on the whole bus (issue 13)
  NetworkTime network_time;      // used with config.network_time
  unsigned next_first = 1;       // the node the next round of starts begins with
  uint32_t socket_overruns = 0;  // the socket's running total when last told

  uint32_t next_random() {
    random ^= random << 13;
    random ^= random >> 17;
    random ^= random << 5;
    return random;
  }

  Node* find(uint8_t id) { return id > 0 && id < kNodeIds ? nodes[id].get() : nullptr; }
  Node& get(uint8_t id) {
    if (!nodes[id]) {
      nodes[id] = std::make_unique<Node>(id, config, channel_of(id, config));
      if (early_sdo_us[id]) nodes[id]->sdo.note_foreign(early_sdo_us[id]);
    }
    return *nodes[id];
  }

  void on_heartbeat(uint8_t id, const od::CanFrame& f, uint64_t now,
                    std::vector<od::CanFrame>& out);
  void on_emcy(uint8_t id, const ObservedFrame& f, uint64_t now);
  void on_sdo(uint8_t id, const ObservedFrame& of, uint64_t now, std::vector<od::CanFrame>& out);
  void bad(Node* n) {
    ++counters.bad_frames;
    if (n) ++n->health.bad_frames;
  }

  void begin_discovery(Node& n);
  void read_done(uint8_t id, Node& n, uint64_t now, uint64_t can_time_ns,
                 std::vector<od::CanFrame>& out);
  void refresh_done(uint8_t id, Node& n, uint64_t now, uint64_t can_time_ns,
                    std::vector<od::CanFrame>& out);
  void sdo_failed(Node& n, uint64_t now);
  void pump(Node& n, uint64_t now, std::vector<od::CanFrame>& out);
  void pump_round(uint64_t now, std::vector<od::CanFrame>& out);
  // The pacer counts a node's transfer from its start until whatever ended it (answer,
  // abort, timeout, collision, cancel): checked after every call that can end one.
  void settle(Node& n) {
    if (!n.paced || !n.sdo.idle()) return;
    n.paced = false;
    pacer.ended();
  }
  void lose(uint8_t id, Node& n, uint64_t now);
  void publish_health(Node& n, uint64_t now);
  NodeHealthSample health_now(const Node& n, uint64_t now) const;
};

BusObserver::BusObserver(SampleSink& sink, const ObserverConfig& config)
    : impl_(std::make_unique<Impl>(sink, config)) {}
BusObserver::~BusObserver() = default;

const BusCounters& BusObserver::counters() const { return impl_->counters; }

std::optional<int64_t> BusObserver::network_time_offset_ns() const {
  if (!impl_->network_time.known()) return std::nullopt;
  return impl_->network_time.offset_ns();
}

NodeHealthSample BusObserver::node_health(uint8_t node, uint64_t now_us) const {
  if (node == 0 || node >= kNodeIds || !impl_->nodes[node]) {
    NodeHealthSample s;
    s.node = node;
    s.bus = impl_->counters;
    return s;
  }
  return impl_->health_now(*impl_->nodes[node], now_us);
}

void BusObserver::on_frame(const ObservedFrame& received, uint64_t now_us,
                           std::vector<od::CanFrame>& out) {
  Impl& m = *impl_;
  ++m.counters.frames;
  if (received.error_frame)
    return count_error_frame(m.counters, received.error_class, received.controller_status);
  const od::CanFrame& f = received.frame;
  if (f.id > 0x7FF || f.dlc > 8) return m.bad(nullptr);
  // The frame with its timestamp on the network's clock, when that is asked for and known.
  ObservedFrame on_network_clock;
  const bool remap = m.config.network_time && m.network_time.known();
  if (remap) {
    on_network_clock = received;
    on_network_clock.can_time_ns = m.network_time.to_network(received.can_time_ns);
  }
  const ObservedFrame& of = remap ? on_network_clock : received;

  uint8_t tpdo_node = 0;
  if (!f.rtr) {
    switch (m.tpdo.on_frame(of, tpdo_node)) {
      case TpdoDecoder::Result::Decoded:
        if (Node* n = m.find(tpdo_node)) {
          ++n->health.frames;
          // A CiA 402 fault came or went: its error code is read (unless a TPDO carries it).
          if (const uint8_t stale = m.tpdo.take_stale_error_codes(tpdo_node)) {
            n->error_code_reads |= stale;
            m.pump(*n, now_us, out);
          }
        }
        return;
      case TpdoDecoder::Result::TooShort: return m.bad(m.find(tpdo_node));
      case TpdoDecoder::Result::NotATpdo: break;
    }
  }
  // Remote frames (node guarding, TPDO requests) carry nothing to decode.
  if (f.rtr) {
    ++m.counters.undecoded;
    return;
  }
  if (uint8_t owner = m.sdo_channel_node[f.id]) return m.on_sdo(owner, of, now_us, out);
  if (f.id == od::cob::kTimeStamp && m.config.network_time) {
    // The stamp names the instant the frame was on the bus: its own kernel timestamp.
    if (!m.network_time.on_time(f, received.can_time_ns)) m.bad(nullptr);
    return;
  }
  const auto id = static_cast<uint8_t>(f.id & 0x7F);
  const uint32_t function = f.id & 0x780;
  if (f.id == od::cob::kNmt) return;  // NMT commands: the heartbeats that follow tell the state
  if (f.id == od::cob::kSync) {
    if (f.dlc > 1) return m.bad(nullptr);  // CiA 301 7.2.5.3: no data, or the counter
    m.tpdo.on_sync(f.dlc == 1 ? f.data[0] : 0);
    return;
  }
  if (id != 0) {
    if (function == od::cob::kEmcyBase) return m.on_emcy(id, of, now_us);
    if (function == od::cob::kSdoTx || function == od::cob::kSdoRx)
      return m.on_sdo(id, of, now_us, out);
    if (function == od::cob::kHeartbeat) return m.on_heartbeat(id, f, now_us, out);
  }
  ++m.counters.undecoded;
}

void BusObserver::Impl::on_heartbeat(uint8_t id, const od::CanFrame& f, uint64_t now,
                                     std::vector<od::CanFrame>& out) {
  const auto state = f.dlc == 1 ? nmt_state_from_byte(f.data[0]) : std::nullopt;
  if (!state) return bad(find(id));
  const bool is_new = !nodes[id];
  Node& n = get(id);
  ++n.health.frames;
  const HeartbeatMonitor::Change c = n.heartbeat.on_heartbeat(*state, now);
  if (is_new || c.boot_up || c.was_lost) {
    // Everything the node had may be different now (stored values back after a reset,
    // another firmware after a loss): read it all again, and decode nothing until then.
    if (!is_new) tpdo.forget(id);
    begin_discovery(n);
  }
  if (*state == NodeState::Stopped) {  // a stopped node answers no SDO
    n.sdo.cancel();
    n.refreshing = false;  // (a refresh read is made again once it may)
  }
  if (is_new || c.state_changed) publish_health(n, now);
  pump(n, now, out);
}

void BusObserver::Impl::on_emcy(uint8_t id, const ObservedFrame& of, uint64_t now) {
  Node* n = find(id);
  auto sample = decode_emcy(id, of.frame, of.can_time_ns, n && n->plan.info().is_stepnode());
  if (!sample) return bad(n);
  sink.emergency(*sample);
  if (!n) return;  // an EMCY alone does not make a node known (no state to publish)
  ++n->health.frames;
  n->health.last_emcy_code = sample->code;
  n->health.error_register = sample->error_register;
  publish_health(*n, now);
}

void BusObserver::Impl::on_sdo(uint8_t id, const ObservedFrame& of, uint64_t now,
                               std::vector<od::CanFrame>& out) {
  const od::CanFrame& f = of.frame;
  Node* n = find(id);
  if (!n) {
    ++counters.undecoded;  // SDO with a node we never heard a heartbeat from
    early_sdo_us[id] = now;
    return;
  }
  if (f.id == od::cob::kSdoTx + id) ++n->health.frames;
  const SdoChannel::FrameEvent ev = n->sdo.on_frame(f, now, out);
  settle(*n);
  if (ev.collision) {
    n->refreshing = false;  // the transfer was dropped; a refresh read is made again
    sdo_failed(*n, now);
  }
  if (ev.foreign_download && *ev.foreign_download >= kPdoParamsFirst &&
      *ev.foreign_download <= kPdoParamsLast) {
    // A master is remapping a TPDO: stop decoding it now (its next frames may already
    // use the new layout) and read the TPDO parameters again once the channel is quiet.
    tpdo.suspend(id, static_cast<uint16_t>(*ev.foreign_download & 0x1FF));
    n->plan.restart_tpdos();  // a read of ours in flight is answered for the old cursor
  }
  if (ev.foreign_download && *ev.foreign_download == kHeartbeatProducerTime) {
    // A master changed the node's heartbeat period (or switched it off): the measured
    // interval no longer holds, so a longer period would look like a loss. Forget it and
    // read 0x1017 again; until then the timeout is the default one. The node is the same:
    // its identity, axes and mapping stay as they were read.
    n->heartbeat.forget_interval();
    n->plan.reread_heartbeat_time();
  }
  if (ev.completed) read_done(id, *n, now, of.can_time_ns, out);
  else pump(*n, now, out);
  // A transfer ended and this node did not take its place (finished, or waiting): the
  // next node waiting for a start gets it now rather than at the next tick.
  if (n->sdo.idle() && pacer.may_start(now)) pump_round(now, out);
}

void BusObserver::Impl::begin_discovery(Node& n) {
  n.sdo.cancel();
  settle(n);
  n.error_code_reads = 0;  // the snapshot reads them
  n.refreshing = false;
  n.plan.restart_all();
  n.backoff.reset();
  n.health.discovered = false;
}

void BusObserver::Impl::read_done(uint8_t id, Node& n, uint64_t now, uint64_t can_time_ns,
                                  std::vector<od::CanFrame>& out) {
  if (n.refreshing) return refresh_done(id, n, now, can_time_ns, out);
  // A master's write moved the plan's cursor while the read was in flight on a channel
  // of the bridge's own: the answer is another object's. The plan reads again.
  if (n.read_epoch != n.plan.epoch()) return pump(n, now, out);
  const bool had_mapping = n.plan.mapping_read(), was_finished = n.plan.finished();
  const ReadOutcome r = n.plan.on_result(n.sdo.result());
  if (r == ReadOutcome::Failed) {
    sdo_failed(n, now);
    return;
  }
  n.backoff.reset();
  const NodeInfo& info = n.plan.info();
  // TPDOs are decoded from the moment their mapping is known, before the snapshot of
  // the axes is read: a TPDO during the snapshot is newer than the snapshot.
  if (!had_mapping && n.plan.mapping_read()) {
    if (info.device_axes() < n.published_axes) {
      // The node came back with fewer axes (reconfigured): the sink can only dispose a
      // node's axes 1..n together, so all go, and the live ones are published again by
      // the snapshot and the TPDOs that follow.
      sink.dispose_axes(id, n.published_axes);
    }
    n.published_axes = info.device_axes();
    tpdo.install(id, info);
  }
  if (!was_finished && n.plan.finished()) {
    tpdo.seed(id, info, can_time_ns);
    n.health.discovered = true;
    publish_health(n, now);
  }
  pump(n, now, out);
}

void BusObserver::Impl::sdo_failed(Node& n, uint64_t now) {
  ++n.health.sdo_failures;
  n.backoff.failed(now);
  // Two masters that failed together would otherwise try again together.
  if (config.collision_jitter_ms)
    n.sdo.add_quiet(uint64_t{next_random() % (config.collision_jitter_ms + 1)} * 1000);
  publish_health(n, now);
}

void BusObserver::Impl::refresh_done(uint8_t id, Node& n, uint64_t now, uint64_t can_time_ns,
                                     std::vector<od::CanFrame>& out) {
  n.refreshing = false;
  const od::SdoResult& result = n.sdo.result();
  const ReadOutcome r = classify(result);
  if (r == ReadOutcome::Failed) {
    sdo_failed(n, now);  // the axis stays marked: read again after the backoff
    return;
  }
  n.backoff.reset();
  n.error_code_reads &= static_cast<uint8_t>(~(1u << n.refresh_axis));
  if (r == ReadOutcome::Value)
    tpdo.apply_read(id, cia402::obj::index(n.refresh_axis, cia402::obj::kErrorCode), 0,
                    result.value_of_size(2), can_time_ns);  // 603Fh: UNSIGNED16
  pump(n, now, out);
}

void BusObserver::Impl::pump(Node& n, uint64_t now, std::vector<od::CanFrame>& out) {
  settle(n);
  if (!sdo_allowed(n.heartbeat.state())) return;
  const bool refresh = !n.plan.wants_read() && n.error_code_reads != 0 && !n.refreshing;
  if (!n.plan.wants_read() && !refresh) return;
  if (!n.backoff.ready(now) || !n.sdo.can_start(now) || !pacer.may_start(now)) return;
  if (refresh) {
    n.refresh_axis = static_cast<uint8_t>(__builtin_ctz(n.error_code_reads));
    n.refreshing = true;
    n.sdo.start_upload(cia402::obj::index(n.refresh_axis, cia402::obj::kErrorCode), 0, now, out);
  } else {
    const SdoRead r = n.plan.next();
    n.read_epoch = n.plan.epoch();
    n.sdo.start_upload(r.index, r.sub, now, out);
  }
  if (n.sdo.idle()) return;
  n.paced = true;
  pacer.started(now);
}

// One chance to start for every node, beginning one further each round so that no node
// is always last when starts are scarce.
void BusObserver::Impl::pump_round(uint64_t now, std::vector<od::CanFrame>& out) {
  const unsigned first = next_first;
  next_first = next_first % (kNodeIds - 1) + 1;
  for (unsigned k = 0; k < kNodeIds - 1 && pacer.may_start(now); ++k) {
    const unsigned id = (first - 1 + k) % (kNodeIds - 1) + 1;
    if (Node* n = nodes[id].get()) pump(*n, now, out);
  }
}

void BusObserver::Impl::lose(uint8_t id, Node& n, uint64_t now) {
  n.sdo.cancel();
  settle(n);
  n.error_code_reads = 0;
  n.refreshing = false;
  tpdo.forget(id);
  publish_health(n, now);
  if (n.published_axes) sink.dispose_axes(id, n.published_axes);
  n.published_axes = 0;
}

NodeHealthSample BusObserver::Impl::health_now(const Node& n, uint64_t now) const {
  NodeHealthSample s = n.health;
  const NodeInfo& info = n.plan.info();
  s.state = n.heartbeat.state();
  s.is_stepnode = info.is_stepnode();
  s.device_name = info.device_name;
  s.vendor_id = info.vendor_id;
  s.product_code = info.product_code;
  s.revision = info.revision;
  s.serial = info.serial;
  s.axes = info.device_axes();
  s.heartbeat_age_ms = n.heartbeat.age_ms(now);
  s.bus = counters;
  return s;
}

void BusObserver::Impl::publish_health(Node& n, uint64_t now) {
  n.last_health_us = now;
  sink.node_health(health_now(n, now));
}

void BusObserver::on_tick(uint64_t now_us, uint64_t /*realtime_ns*/,
                          std::vector<od::CanFrame>& out) {
  Impl& m = *impl_;
  const uint64_t health_period_us = uint64_t{m.config.health_period_ms} * 1000;
  for (unsigned id = 1; id < kNodeIds; ++id) {
    Node* n = m.nodes[id].get();
    if (!n) continue;
    const auto node = static_cast<uint8_t>(id);
    if (n->sdo.on_tick(now_us, out)) {
      m.settle(*n);
      m.read_done(node, *n, now_us, 0, out);
    }
    const NodeInfo& info = n->plan.info();
    if (n->heartbeat.check_lost(now_us, m.config.heartbeat_timeout_ms, info.heartbeat_period_ms,
                                info.heartbeat_period_read)) {
      m.lose(node, *n, now_us);
      continue;
    }
    if (now_us - n->last_health_us >= health_period_us) m.publish_health(*n, now_us);
  }
  // After every timeout of this tick has freed its place.
  m.pump_round(now_us, out);
}

uint32_t BusObserver::on_socket_overruns(uint32_t socket_total) {
  Impl& m = *impl_;
  const uint32_t grown = socket_total - m.socket_overruns;  // the kernel's u32 wraps too
  m.socket_overruns = socket_total;
  m.counters.overruns += grown;
  return grown;
}

void BusObserver::dispose_all() {
  Impl& m = *impl_;
  for (unsigned id = 1; id < kNodeIds; ++id) {
    Node* n = m.nodes[id].get();
    if (!n || !n->published_axes) continue;
    m.sink.dispose_axes(static_cast<uint8_t>(id), n->published_axes);
    n->published_axes = 0;
  }
}

}  // namespace stepnode::bridge
