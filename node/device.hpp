// The device assembly: the one place the node is put together. From the configuration it
// builds the CiA 301 slave (CanopenNode), the axes on their back end (AxisBank: the engine
// and the simulated machine) and the profiles the device has (node/profiles/*: the
// simulator's objects, the Horner registers, the HP 44714A channels), and is their
// application: it advances them, powers them up, hands them SYNC, and applies the policy
// for a lost master and for NMT Stopped. node/main.cpp, the benchmarks and the test
// harnesses build the node through it and wire nothing themselves.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "node/application.hpp"
#include "node/axis_bank.hpp"
#include "node/canopen_node.hpp"
#include "node/config.hpp"
#include "node/profile.hpp"

namespace stepnode::node {

class Device final : private Application {
 public:
  using ObjectDefaults = std::vector<std::pair<std::string, std::string>>;

  // `object_defaults`: the configuration's [defaults] (throws UsageError for one that is
  // wrong on its face; a mapping the device cannot use is kept built-in and reported by
  // EMCY 0x6100 after boot-up, see refused_mappings()).
  Device(const NodeOptions& options, const ObjectDefaults& object_defaults, CanopenNode::Send send);
  ~Device() override;
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  // Power-on: stored parameters, boot-up, pre-operational.
  void start(uint64_t now_us) { canopen_.start(now_us); }
  // A received frame. `arrival_us`: when it reached the bus interface (the kernel's
  // timestamp, <= now_us; 0 when unknown), so TRIG SYS starts at the SYNC's arrival.
  void on_frame(const od::CanFrame& frame, uint64_t now_us, uint64_t arrival_us = 0);
  void on_tick(uint64_t now_us) { canopen_.on_tick(now_us); }
  // When on_tick next has work (absolute us; node/deadline.hpp): every service, axis and
  // profile. node/main.cpp sleeps until then (bounded by --tick-us).
  uint64_t next_deadline_us(uint64_t now_us) { return canopen_.next_deadline_us(now_us); }
  void on_bus_event(BusEvent event, uint64_t now_us) { canopen_.on_bus_event(event, now_us); }
  void on_receive_overruns(uint32_t socket_total, uint64_t now_us) {
    canopen_.on_receive_overruns(socket_total, now_us);
  }

  // Where the node's kernel receive filters go (node/main.cpp: the socket). Given the
  // current list at once (before start(): from the defaults), then every change.
  using FilterSink = std::function<void(const std::vector<ReceiveFilter>&)>;
  void set_receive_filter_sink(FilterSink sink);

  CanopenNode& canopen() { return canopen_; }
  od::Dictionary& dictionary() { return canopen_.dictionary(); }
  AxisBank& axes() { return axes_; }
  sim::Machine& machine() { return axes_.machine(); }
  const std::vector<RefusedMapping>& refused_mappings() const { return refused_; }

 private:
  // Application: what the CanopenNode calls.
  void advance(uint64_t now_us) override;
  uint64_t next_advance_us(uint64_t now_us) override;
  void reset_application(uint64_t now_us) override;
  void sync(uint64_t now_us) override;
  void state_changed(NmtState state, uint64_t now_us) override;
  void communication_error(CommunicationError error, uint8_t node, uint64_t now_us) override;
  void heartbeat_recovered(uint8_t node, uint64_t now_us) override;
  void life_guarding_recovered(uint64_t now_us) override;
  void receive_filters_changed(const std::vector<ReceiveFilter>& filters) override;

  // 0x2F11: 0 makes every monitored node a master; otherwise only that node is.
  bool is_master(uint8_t node);
  void master_lost(uint64_t now_us);
  void publish();

  // The profiles' objects, then the configuration's defaults over them.
  static std::vector<RefusedMapping> complete_dictionary(CanopenNode& canopen,
                                                         const DeviceLayout& layout,
                                                         const ObjectDefaults& object_defaults);

  CanopenNode canopen_;
  std::vector<RefusedMapping> refused_;  // before the services: they load what it leaves
  AxisBank axes_;
  std::vector<std::unique_ptr<Profile>> profiles_;  // called in this order
  uint64_t frame_arrival_us_ = 0;                   // the frame being handled (0: none, or unknown)
  bool register_axes_ = true;  // Horner or HP: the register front ends' master-lost rule
  FilterSink filter_sink_;
};

}  // namespace stepnode::node
