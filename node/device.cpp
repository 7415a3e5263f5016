#include "node/device.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>

#include "node/diagnostic_objects.hpp"
#include "node/profiles/cia402/service.hpp"
#include "node/profiles/horner/service.hpp"
#include "node/profiles/hp44714a/service.hpp"
#include "node/profiles/sim/service.hpp"

namespace stepnode::node {

Device::Device(const NodeOptions& options, const ObjectDefaults& object_defaults,
               CanopenNode::Send send)
    : canopen_(options, std::move(send)),
      refused_(complete_dictionary(canopen_, options.layout, object_defaults)),
      axes_(options.layout) {
  od::Dictionary& od = canopen_.dictionary();
  // The order they are called in: the back end's settings first, then the front ends.
  profiles_.push_back(std::make_unique<SimService>(od, axes_));
  if (options.layout.horner)
    profiles_.push_back(std::make_unique<HornerService>(od, axes_, canopen_.emcy()));
  if (options.layout.hp)
    profiles_.push_back(std::make_unique<HpService>(od, axes_, canopen_.emcy()));
  if (options.layout.cia402)
    profiles_.push_back(std::make_unique<Cia402Service>(od, axes_, canopen_.emcy()));
  register_axes_ = options.layout.horner || options.layout.hp;
  for (const RefusedMapping& r : refused_) {
    spdlog::warn(
        "config: PDO mapping {:04X} is not valid on this device ({}); its built-in mapping is kept",
        r.index, od::abort_text(r.reason));
    // EMCY 0x6100 after boot-up, manufacturer bytes: the record's index, little-endian.
    canopen_.report_at_power_up(
        emcy_code::kSoftware,
        {static_cast<uint8_t>(r.index), static_cast<uint8_t>(r.index >> 8), 0, 0, 0});
  }
  canopen_.set_application(this);
}

Device::~Device() { canopen_.set_application(nullptr); }

std::vector<RefusedMapping> Device::complete_dictionary(CanopenNode& canopen,
                                                        const DeviceLayout& layout,
                                                        const ObjectDefaults& object_defaults) {
  add_profile_objects(canopen.dictionary(), layout);
  return apply_object_defaults(canopen.dictionary(), object_defaults);
}

void Device::on_frame(const od::CanFrame& frame, uint64_t now_us, uint64_t arrival_us) {
  frame_arrival_us_ = arrival_us && arrival_us <= now_us ? arrival_us : 0;
  canopen_.on_frame(frame, now_us, frame_arrival_us_);
  frame_arrival_us_ = 0;
}

void Device::advance(uint64_t now_us) {
  // Never backwards: a SYNC is sampled at its arrival, which a tick may already have passed.
  now_us = std::max(now_us, axes_.now_us());
  axes_.advance(now_us);
  for (auto& p : profiles_) p->advance(now_us);
  axes_.advance(now_us);  // the steps of a job a profile started at or before now
  publish();
}

uint64_t Device::next_advance_us(uint64_t now_us) {
  uint64_t next = axes_.next_deadline_us(now_us);
  for (auto& p : profiles_) next = earliest(next, p->next_advance_us(now_us));
  return next;
}

void Device::publish() {
  for (auto& p : profiles_) p->publish();
}

void Device::reset_application(uint64_t now_us) {
  axes_.advance(now_us);
  for (auto& p : profiles_) p->configure(now_us);
  axes_.power_up(now_us);
  for (auto& p : profiles_) p->power_up(now_us);
  publish();
}

void Device::sync(uint64_t now_us) {
  // TRIG SYS starts at the SYNC frame's arrival, not when the process got round to reading
  // it: every node on the bus then starts together. A SYNC produced here: now.
  advance(now_us);
  for (auto& p : profiles_) p->sync(now_us, frame_arrival_us_ ? frame_arrival_us_ : now_us);
  advance(now_us);
}

void Device::master_lost(uint64_t now_us) {
  // The register front ends' rule (README "Communication errors and NMT states"): every
  // moving axis ramps down and %I8 latches. A CiA 402 only device follows 6007h alone.
  if (register_axes_) axes_.master_lost(now_us);
  else axes_.advance(now_us);
  for (auto& p : profiles_) p->master_lost(now_us);
  publish();
}

void Device::state_changed(NmtState state, uint64_t now_us) {
  // NMT Stopped: no SDO and no PDO reach the axes any more, so the master has lost control
  // of them; they ramp down and latch %I8 exactly as for a lost master (README, "NMT
  // states and motion"). Pre-operational keeps SDO, and the axes keep their job.
  // Initialising is only reported for a node that lost its node-ID over LSS: unreachable
  // as well.
  if (state == NmtState::Stopped || state == NmtState::Initialising) {
    spdlog::warn("NMT {}: every moving axis ramps down",
                 state == NmtState::Stopped ? "stopped" : "initialising (no node-ID)");
    master_lost(now_us);
  }
}

void Device::communication_error(CommunicationError error, uint8_t node, uint64_t now_us) {
  if (error == CommunicationError::HeartbeatLost && !is_master(node)) return;  // EMCY 0x8130 only
  // Life guarding is the guarding master's own check: its loss is the master's, like a lost
  // heartbeat of the master (README, "Communication errors and NMT states").
  spdlog::warn("{}: every moving axis ramps down",
               error == CommunicationError::BusOff ? std::string("bus-off")
               : error == CommunicationError::LifeGuardingLost
                   ? std::string("life guarding (the guarding master) lost")
                   : "master (node " + std::to_string(node) + ") lost");
  master_lost(now_us);
}

void Device::heartbeat_recovered(uint8_t node, uint64_t now_us) {
  if (!is_master(node)) return;
  for (auto& p : profiles_) p->master_back(now_us);
}

void Device::life_guarding_recovered(uint64_t now_us) {
  for (auto& p : profiles_) p->master_back(now_us);
}

void Device::set_receive_filter_sink(FilterSink sink) {
  filter_sink_ = std::move(sink);
  if (filter_sink_) filter_sink_(canopen_.receive_filters());
}

void Device::receive_filters_changed(const std::vector<ReceiveFilter>& filters) {
  if (filter_sink_) filter_sink_(filters);
}

bool Device::is_master(uint8_t node) {
  const uint8_t master = canopen_.dictionary().get<uint8_t>(kMasterNodeId, 0);
  return master == 0 || master == node;
}

}  // namespace stepnode::node
