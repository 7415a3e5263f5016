#include "node/canopen_node.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>

#include "node/diagnostic_objects.hpp"
#include "node/error_behaviour.hpp"
#include "od/eds.hpp"
#include "od/pdo_mapping.hpp"

namespace stepnode::node {
namespace {

std::filesystem::path parameter_file_for(const NodeOptions& o) {
  return o.state_dir / ("node-" + std::to_string(o.device.node_id) + ".params");
}

NodeOptions described(NodeOptions o) {
  if (o.device.description.empty()) o.device.description = o.layout.description();
  return o;
}

lss::Identity identity_of(const od::DeviceInfo& d) {
  return {d.vendor_id, d.product_code, d.revision, d.serial_number};
}

// The precedence of the node-ID's sources: command line, then LSS-stored, then the
// configuration file; none of them: unconfigured (README, "LSS").
NodeOptions with_stored_node_id(NodeOptions o, const std::optional<LssStore::Contents>& stored) {
  if (stored && o.node_id_origin != NodeIdOrigin::CommandLine) {
    spdlog::info("LSS: node-ID {} as stored by an LSS master", stored->node_id);
    o.device.node_id = stored->node_id;
  }
  return o;
}

}  // namespace

CanopenNode::CanopenNode(NodeOptions options, Send send_frame)
    : lss_store_(options.state_dir, identity_of(options.device)),
      lss_stored_(lss_store_.load()),
      options_(described(with_stored_node_id(std::move(options), lss_stored_))),
      send_(std::move(send_frame)),
      store_((add_node_objects(dictionary_, options_.device, options_.layout), dictionary_),
             parameter_file_for(options_)),
      emcy_(dictionary_, [this](const od::CanFrame& f) { send(f); }),
      heartbeat_(dictionary_, options_.device.node_id, [this](const od::CanFrame& f) { send(f); }),
      consumer_(dictionary_,
                HeartbeatConsumer::Events{
                    .timeout =
                        [this](uint8_t node, uint64_t now) {
                          spdlog::warn("heartbeat of node {} lost", node);
                          emcy_.raise(emcy_code::kHeartbeatError, error_bits::kCommunication,
                                      {node}, now);
                          communication_error(CommunicationError::HeartbeatLost, node, now);
                        },
                    .recovered =
                        [this](uint8_t node, uint64_t now) {
                          spdlog::info("heartbeat of node {} is back (or no longer watched)", node);
                          if (!consumer_.any_timed_out() && !guarding_.lost())
                            emcy_.clear(emcy_code::kHeartbeatError, now);
                          if (app_) app_->heartbeat_recovered(node, now);
                        },
                    .remote_reset = nullptr}),
      guarding_(dictionary_, options_.device.node_id,
                NodeGuarding::Events{
                    .lost =
                        [this](uint64_t now) {
                          spdlog::warn(
                              "life guarding: no node guarding request within the node life time");
                          // CiA 301: 0x8130 is "life guard error or heartbeat error".
                          emcy_.raise(emcy_code::kHeartbeatError, error_bits::kCommunication, {},
                                      now);
                          communication_error(CommunicationError::LifeGuardingLost, 0, now);
                        },
                    .recovered =
                        [this](uint64_t now) {
                          spdlog::info(
                              "life guarding: the master's requests are back (or guarding is off)");
                          if (!consumer_.any_timed_out())
                            emcy_.clear(emcy_code::kHeartbeatError, now);
                          if (app_) app_->life_guarding_recovered(now);
                        }}),
      sync_(
          dictionary_, [this](const od::CanFrame& f) { send(f); },
          [this](uint8_t counter, uint64_t sync_us, uint64_t now) {
            pdo_.on_sync(counter, sync_us, now);
            if (app_) app_->sync(now);
          },
          [this](uint8_t dlc, uint64_t now) {
            emcy_.report(emcy_code::kSyncLength, error_bits::kCommunication, {dlc}, now);
          }),
      time_(
          dictionary_, [this](const od::CanFrame& f) { send(f); }, options_.wall_clock),
      pdo_(
          dictionary_, options_.layout.pdos(), [this](const od::CanFrame& f) { send(f); }, emcy_),
      sdo_(dictionary_, options_.sdo_timeout_us, [this](const od::CanFrame& f) { send(f); }),
      lss_(identity_of(options_.device), options_.device.node_id,
           lss_stored_ ? lss_stored_->bit_timing : std::nullopt,
           [this](uint8_t node_id, std::optional<uint8_t> bit_timing) {
             return lss_store_.save({node_id, bit_timing});
           }) {
  install_service_hooks();
}

CanopenNode::~CanopenNode() = default;

void CanopenNode::install_service_hooks() {
  od::Dictionary& od = dictionary_;
  emcy_cob_id_ = &od.at(0x1014, 0);  // entries stay where they are: the dictionary is built once
  // Store/restore: the signature check of the dictionary comes first, then the file.
  for (const auto& group : od::kParameterGroups) {
    // The signature was checked by the entry's validate (a wrong one is 0x08000020); the
    // command acts once written. "If the storing failed" the answer is 0x06060000, access
    // failed due to a hardware error (CiA 301 7.5.2.13), and so for restoring (7.5.2.14).
    od::react(od.at(0x1010, group.sub), [this, group] {
      spdlog::info("saving {} to {}", group.name, store_.file().string());
      return store_.save(group.first, group.last) ? od::SdoAbort::None : od::SdoAbort::Hardware;
    });
    od::react(od.at(0x1011, group.sub), [this, group] {
      spdlog::info("restoring defaults of {} (after the next reset)", group.name);
      return store_.forget(group.first, group.last) ? od::SdoAbort::None : od::SdoAbort::Hardware;
    });
  }
  for (const auto& [index, obj] : od.objects()) {
    (void)obj;
    if (index >= 0x1400 && index <= 0x1BFF)
      for (auto& [sub, e] : od.object(index)->entries) od::listen(e, [this] { pdo_.mark_dirty(); });
  }
  // Writing one consumer entry must not reset the others: a lost node's EMCY 0x8130 would
  // stay active for ever, as its slot no longer knew it had timed out.
  for (auto& [sub, e] : od.object(0x1016)->entries)
    od::listen(e, [this] { consumer_.reconfigure(); });
  for (uint16_t index : {0x1005, 0x1006, 0x1019})
    od::listen(od.at(index, 0), [this] { sync_.reset(0); });
  // The objects whose values decide which CAN-IDs the node receives.
  for (const auto& [index, obj] : od.objects()) {
    const bool filtered = index == 0x1005 || index == 0x1012 || index == 0x1014 ||
                          index == 0x1016 || (index >= 0x1200 && index <= 0x1203) ||
                          (index >= 0x1400 && index <= 0x1BFF);  // TPDOs: remote frames
    if (!filtered) continue;
    for (auto& [sub, e] : od.object(index)->entries)
      od::listen(e, [this] { filters_dirty_ = true; });
  }
  // 0x1021: the device's own EDS, generated from this dictionary when read.
  od.at(0x1021, 0).on_read = [this](od::Bytes& v) {
    v = od::encode_string(od::write_eds(dictionary_, options_.device));
  };
}

void CanopenNode::start(uint64_t now_us) {
  if (auto index = lss_.active_bit_timing()) {
    if (options_.activate_bit_timing)
      spdlog::info(
          "LSS: stored bit timing {} kbit/s (table index {}); the node applies it "
          "(--apply-bit-timing)",
          *lss::bit_rate_kbit(*index), *index);
    else
      spdlog::info(
          "LSS: stored bit timing {} kbit/s (table index {}); without --apply-bit-timing stepnode "
          "does not set the interface's bit rate: `tools/lss-bit-timing {} IFACE` compares it "
          "and applies it with ip link",
          *lss::bit_rate_kbit(*index), *index, options_.state_dir.string());
  }
  if (configured() && options_.boot_listen_us > 0) {
    spdlog::info("listening {} ms for another device with node-ID {} before the boot-up",
                 options_.boot_listen_us / 1000, node_id());
    conflict_.listen(node_id(), now_us, options_.boot_listen_us);
    update_receive_filters();  // 0x700+id, 0x580+id and the EMCY COB-ID are among them
    return;
  }
  initialise(true, now_us);
}

void CanopenNode::report_at_power_up(uint16_t code, std::array<uint8_t, 5> manufacturer) {
  power_up_errors_.push_back({code, manufacturer});
}

void CanopenNode::load_parameters(uint16_t first, uint16_t last, uint64_t now_us) {
  ParameterStore::LoadReport report = store_.load_into_dictionary(first, last);
  // Stored mappings skip the mapping procedure: one naming an object this device does not
  // have (saved with two axes, started with one) is put back to its default record.
  for (unsigned n = 0; n < options_.layout.pdos(); ++n)
    for (const uint16_t index : {od::rpdo_mapping(n), od::tpdo_mapping(n)}) {
      od::SdoAbort a = od::check_mapping_record(dictionary_, index);
      if (a == od::SdoAbort::None) continue;
      spdlog::warn("stored PDO mapping {:04X} is not valid ({}); default mapping kept", index,
                   od::abort_text(a));
      dictionary_.reset_to_defaults(index, index);
      report.refuse({index, 0});
    }
  // Reset node ends every condition (the application is reset too); reset communication
  // only the CiA 301 services' (emcy.hpp).
  if (last > 0x1FFF) emcy_.reset();
  else emcy_.reset_communication(now_us);
  if (!report.problem()) return;
  // Manufacturer bytes: the first refused entry (index little-endian, sub), how many were
  // refused (at most 255), and the file: 0 good, 1 damaged and set aside, 2 damaged and
  // it could not be renamed.
  ParameterStore::Key key = report.first_refused.value_or(ParameterStore::Key{0, 0});
  emcy_.report(emcy_code::kDataStorage, error_bits::kGeneric,
               {static_cast<uint8_t>(key.first), static_cast<uint8_t>(key.first >> 8), key.second,
                static_cast<uint8_t>(std::min(report.refused, 255u)),
                static_cast<uint8_t>(!report.damaged    ? 0
                                     : report.set_aside ? 1
                                                        : 2)},
               now_us);
}

void CanopenNode::initialise(bool reset_application, uint64_t now_us) {
  // Reset application: every parameter back to its stored value (or default); reset
  // communication: only 0x1000-0x1FFF (CiA 301 7.3.2.2.1).
  state_ = NmtState::Initialising;
  emcy_.set_enabled(false);  // nothing but the boot-up message before pre-operational
  pdo_.reset();
  sdo_.reset();
  // A node-ID configured over LSS takes effect here, at reset communication (CiA 305), and
  // the LSS slave is back in waiting: left in configuration state, a booted node answered
  // the master's next configure node-ID meant for the next device (found in review).
  lss_.enter_waiting();
  if (const uint8_t id = lss_.activate_pending_node_id(); id != node_id()) adopt_node_id(id);
  if (!configured()) {
    // CiA 305: without a node-ID the device stays in NMT initialisation, silent but for
    // the LSS slave, until a master configures one and switches it to waiting.
    spdlog::info("no node-ID: waiting for an LSS master (identity serial number 0x{:08X})",
                 options_.device.serial_number);
    // A running device that lost its node-ID (0xFF configured over LSS) can no longer be
    // reached by SDO or PDO: the application is told, as for NMT Stopped.
    if (booted_ && app_) app_->state_changed(NmtState::Initialising, now_us);
    update_receive_filters();  // LSS and NMT only; nothing is sent that would do it
    return;
  }
  if (!booted_) reset_application = true;  // the first boot powers the application up
  booted_ = true;
  if (reset_application) {
    load_parameters(0x1000, 0x9FFF, now_us);
    for (const auto& e : power_up_errors_)
      emcy_.report(e.code, error_bits::kGeneric, e.manufacturer, now_us);
    if (app_) app_->reset_application(now_us);
  } else {
    load_parameters(0x1000, 0x1FFF, now_us);
  }
  pdo_.mark_dirty();
  filters_dirty_ = true;  // stored COB-IDs; the boot-up below goes out with the filters set
  sdo_.reconfigure();     // 0x1201..0x1203 as stored (or configured)
  consumer_.reset();
  guarding_.reset();  // the toggle bit starts at 0 again only here (CiA 301 7.2.8.3.1)
  sync_.reset(now_us);
  time_.reset(now_us);
  // Boot-up message: the heartbeat COB-ID with state 0 (CiA 301 7.2.8.3.2.1).
  send(od::CanFrame(od::cob::kHeartbeat + node_id(), {0x00}));
  conflict_.booted(node_id(), now_us);
  enter(NmtState::PreOperational, now_us);
  // A self-starting device (CiA 302-2, 0x1F80 bit 2 = 0) enters operational by itself after
  // every boot-up, without an NMT master; NMT commands still move it after that.
  if (!(dictionary_.get<uint32_t>(od::kNmtStartup, 0) & od::kNmtStartupNoAutoStart)) {
    spdlog::info("NMT startup 0x1F80 bit 2 is 0: self-start");
    enter(NmtState::Operational, now_us);
  }
}

void CanopenNode::adopt_node_id(uint8_t id) {
  spdlog::info("LSS: node-ID {} is now {}", node_id(), id);
  options_.device.node_id = id;
  filters_dirty_ = true;
  // The COB-IDs that follow the node-ID, and the parameters stored for this one; both
  // reach the dictionary with the reset that follows.
  od::apply_node_id(dictionary_, id);
  heartbeat_.set_node_id(id);
  guarding_.set_node_id(id);
  store_.set_file(parameter_file_for(options_));
}

void CanopenNode::on_lss_frame(const od::CanFrame& frame, uint64_t now_us) {
  // The answer goes out before the next frame is read: back-to-back requests each get theirs.
  LssSlave::Result r = lss_.on_frame(frame);
  if (r.response) send(*r.response);
  if (r.activate_bit_timing_delay_ms) {
    const auto index = lss_.active_bit_timing();
    const unsigned kbit = index ? *lss::bit_rate_kbit(*index) : 0;
    const uint16_t delay_ms = *r.activate_bit_timing_delay_ms;
    if (options_.activate_bit_timing && kbit) options_.activate_bit_timing(kbit, delay_ms, now_us);
    else
      spdlog::warn(
          "LSS: activate bit timing {} kbit/s after {} ms: stepnode does not set the interface's "
          "bit rate without --apply-bit-timing; or apply it with `tools/lss-bit-timing {} IFACE "
          "--apply` (ip link, root)",
          kbit, delay_ms, options_.state_dir.string());
  }
  if (r.boot) {
    spdlog::info("LSS: node-ID {} configured: reset communication and boot-up",
                 lss_.pending_node_id());
    initialise(false, now_us);
  }
}

void CanopenNode::enter(NmtState next, uint64_t now_us) {
  NmtState previous = state_;
  state_ = next;
  emcy_.set_enabled(emcy_allowed(next));
  if (next == NmtState::Operational && previous != NmtState::Operational) pdo_.start(now_us);
  if (next != NmtState::Operational) pdo_.stop();
  if (!sdo_allowed(next)) sdo_.reset();
  // The SYNC counter restarts at 1 when the device leaves stopped (CiA 301 7.2.5, SYNC
  // counter); the producer was silent there, so its period restarts from now as well.
  if (previous == NmtState::Stopped && next != NmtState::Stopped) sync_.reset(now_us);
  if (previous != next) {
    spdlog::info("NMT: {} -> {}", state_name(previous), state_name(next));
    // Confirm the new state at once; the period restarts from here.
    heartbeat_.send_now(next, now_us);
    if (app_) app_->state_changed(next, now_us);
  }
  emcy_.on_tick(now_us);
}

void CanopenNode::handle_nmt(NmtCommand command, uint64_t now_us) {
  spdlog::debug("NMT command: {}", command_name(command));
  switch (command) {
    case NmtCommand::ResetNode: initialise(true, now_us); break;
    case NmtCommand::ResetCommunication: initialise(false, now_us); break;
    default: enter(next_state(state_, command), now_us); break;
  }
}

void CanopenNode::communication_error(CommunicationError error, uint8_t node, uint64_t now_us) {
  if (app_) app_->communication_error(error, node, now_us);
  const uint8_t behaviour =
      dictionary_.get<uint8_t>(od::kErrorBehaviour, od::kCommunicationErrorSub);
  if (auto next = state_after_communication_error(behaviour, state_)) {
    spdlog::warn("communication error: 0x1029 sub 1 = {} takes the node to {}", behaviour,
                 state_name(*next));
    enter(*next, now_us);
  }
}

bool CanopenNode::serves(const od::CanFrame& frame) {
  const std::vector<ReceiveFilter>& list = receive_filters();
  if (list.empty()) return true;  // more CAN-IDs than the kernel filters: every frame is routed
  // The list is sorted and holds each CAN-ID once.
  auto it = std::lower_bound(list.begin(), list.end(), frame.id,
                             [](const ReceiveFilter& f, uint32_t id) { return f.id < id; });
  if (it == list.end() || it->id != frame.id) return false;
  if (frame.rtr && it->frames == ReceiveFilter::Frames::Data) return false;
  // Every node hears NMT; a command for another node is not this one's.
  if (frame.id == od::cob::kNmt) return decode_nmt(frame, configured() ? node_id() : 0).has_value();
  return true;
}

void CanopenNode::on_frame(const od::CanFrame& frame, uint64_t now_us, uint64_t arrival_us) {
  // Route first: a frame this node does not serve (another node's, which the kernel
  // filters let through or a socket without them delivers) costs a lookup, not an advance
  // of the axes and a tick. A frame it serves advances the application before it acts.
  if (!serves(frame)) return;
  // A SYNC samples the application at its arrival, not when the process came to it: the
  // synchronous TPDOs built in its handler then report the instant every node on the bus
  // saw (the device never advances backwards: after a later tick, that tick's values).
  const bool sync = !frame.rtr && frame.id == sync_.cob_id() && arrival_us && arrival_us <= now_us;
  if (app_ && booted_) app_->advance(sync ? arrival_us : now_us);
  if (frame.id == lss::kMasterToSlave) {
    on_lss_frame(frame, now_us);  // in every NMT state, with a node-ID or without
    return;
  }
  if (conflict_.listening()) {
    // Still in initialisation, before the boot-up: only another device's frames matter
    // (an NMT command finds the node not booted yet; the boot-up follows the listening).
    if (auto c = conflict_.on_frame(frame, od::decode<uint32_t>(emcy_cob_id_->value), now_us))
      node_id_conflict(*c, now_us);
    return;
  }
  // Without a node-ID only a broadcast reaches the node, and only a reset means anything
  // in NMT initialisation: it applies a node-ID configured over LSS.
  if (auto command = decode_nmt(frame, configured() ? node_id() : 0)) {
    if (configured() || *command == NmtCommand::ResetNode ||
        *command == NmtCommand::ResetCommunication)
      handle_nmt(*command, now_us);
    return;
  }
  if (!configured()) return;
  if (auto conflict =
          conflict_.on_frame(frame, od::decode<uint32_t>(emcy_cob_id_->value), now_us)) {
    node_id_conflict(*conflict, now_us);
    return;
  }
  // Error control runs in every state.
  if (auto answer = guarding_.on_frame(frame, state_, now_us)) {
    send(*answer);
    return;
  }
  consumer_.on_frame(frame, now_us);
  if (state_ == NmtState::Stopped || state_ == NmtState::Initialising) return;

  // SYNC, TIME, then the SDO server channel the frame was addressed to; the rest may be a PDO.
  const bool handled = sync_.on_frame(frame, now_us, arrival_us) ||
                       time_.on_frame(frame, now_us, arrival_us) || sdo_.on_frame(frame, now_us);
  if (!handled && state_ == NmtState::Operational) pdo_.on_frame(frame, now_us, arrival_us);
  // A received frame may change mapped values: event-driven TPDOs go out now, not on the
  // next tick.
  on_tick(now_us);
}

void CanopenNode::on_tick(uint64_t now_us) {
  if (conflict_.listening()) {
    if (now_us >= conflict_.listen_end_us()) initialise(true, now_us);  // nobody heard
    return;
  }
  if (app_ && booted_) app_->advance(now_us);
  if (filters_dirty_) update_receive_filters();  // a COB-ID the node wrote itself
  consumer_.on_tick(now_us);
  if (state_ == NmtState::Initialising) return;
  guarding_.on_tick(now_us);
  heartbeat_.on_tick(state_, now_us);
  if (state_ == NmtState::Stopped) return;
  sdo_.on_tick(now_us);
  sync_.on_tick(now_us);
  time_.on_tick(now_us);
  pdo_.on_tick(now_us);
  emcy_.on_tick(now_us);
}

uint64_t CanopenNode::next_deadline_us(uint64_t now_us) {
  // The services on_tick runs in this state, and no others: one it skips would otherwise
  // report a deadline that never moves and wake the loop for nothing.
  if (filters_dirty_) return now_us;
  if (conflict_.listening()) return conflict_.listen_end_us();
  uint64_t next = app_ && booted_ ? app_->next_advance_us(now_us) : kNoDeadline;
  next = earliest(next, consumer_.next_deadline_us());
  if (state_ == NmtState::Initialising) return next;
  next = earliest(next, guarding_.next_deadline_us());
  next = earliest(next, heartbeat_.next_deadline_us());
  if (state_ == NmtState::Stopped) return next;
  next = earliest(next, sdo_.next_deadline_us(now_us));
  next = earliest(next, sync_.next_deadline_us(now_us));
  next = earliest(next, time_.next_deadline_us(now_us));
  next = earliest(next, pdo_.next_deadline_us(now_us));
  return earliest(next, emcy_.next_deadline_us(now_us));
}

const std::vector<ReceiveFilter>& CanopenNode::receive_filters() {
  if (filters_dirty_) update_receive_filters();
  return filters_;
}

void CanopenNode::update_receive_filters() {
  filters_dirty_ = false;
  std::vector<ReceiveFilter> next =
      node::receive_filters(dictionary_, node_id(), options_.layout.pdos());
  if (next == filters_) return;
  filters_ = std::move(next);
  spdlog::debug("receive filters: {} CAN-IDs", filters_.size());
  if (app_) app_->receive_filters_changed(filters_);
}

void CanopenNode::on_receive_overruns(uint32_t socket_total, uint64_t now_us) {
  const uint32_t lost = socket_total - overruns_seen_;  // unsigned: survives the wrap
  if (lost == 0) return;
  overruns_seen_ = socket_total;
  const uint32_t total = dictionary_.get<uint32_t>(kReceiveOverruns, 0) + lost;
  dictionary_.put<uint32_t>(kReceiveOverruns, 0, total);
  spdlog::warn("CAN receive queue overflow: {} frames dropped ({} since reset)", lost, total);
  // CiA 301: 0x8110 CAN overrun (objects lost); manufacturer bytes: frames lost, LE.
  emcy_.report(emcy_code::kCanOverrun, error_bits::kCommunication,
               {static_cast<uint8_t>(lost), static_cast<uint8_t>(lost >> 8),
                static_cast<uint8_t>(lost >> 16), static_cast<uint8_t>(lost >> 24), 0},
               now_us);
}

void CanopenNode::on_bus_event(BusEvent event, uint64_t now_us) {
  switch (event) {
    case BusEvent::ErrorPassive:
      emcy_.raise(emcy_code::kCanErrorPassive, error_bits::kCommunication, {}, now_us,
                  emcy_source::kBus);
      break;
    case BusEvent::ErrorActive:
      emcy_.clear(emcy_code::kCanErrorPassive, now_us, emcy_source::kBus);
      break;
    case BusEvent::Restarted:
      // "Recovered from bus-off" first, then the error reset that ends the error-passive
      // condition the bus-off came through, with the error register as it is now.
      emcy_.report(emcy_code::kRecoveredFromBusOff, error_bits::kCommunication, {}, now_us);
      emcy_.clear(emcy_code::kCanErrorPassive, now_us, emcy_source::kBus);
      break;
    case BusEvent::RxOverflow:
    case BusEvent::TxOverflow:
      emcy_.report(emcy_code::kCanOverrun, error_bits::kCommunication, {}, now_us);
      break;
    case BusEvent::BusOff:
      // Nothing can be sent while bus-off (the EMCY waits for the restart); the masters
      // cannot reach the node either: a communication error (CiA 301 0x1029).
      communication_error(CommunicationError::BusOff, 0, now_us);
      break;
    case BusEvent::ErrorWarning: break;  // logged by the transport
  }
}

}  // namespace stepnode::node
