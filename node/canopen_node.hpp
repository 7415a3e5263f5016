// One CANopen slave (CiA 301): the dictionary and every communication service, driven by
// frames and time passed in. No sockets and no clocks here, so tests run in virtual time;
// node/device.* puts the profiles behind it and node/main.cpp connects it to SocketCAN and
// CLOCK_MONOTONIC.
#pragma once
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>

#include "node/application.hpp"
#include "node/device_objects.hpp"
#include "node/emcy.hpp"
#include "node/heartbeat.hpp"
#include "node/lss_slave.hpp"
#include "node/lss_store.hpp"
#include "node/nmt.hpp"
#include "node/node_guarding.hpp"
#include "node/node_id_conflict.hpp"
#include "node/parameter_store.hpp"
#include "node/pdo_engine.hpp"
#include "node/receive_filters.hpp"
#include "node/sdo_server_channels.hpp"
#include "node/sync.hpp"
#include "node/time_service.hpp"
#include "od/can_frame.hpp"
#include "od/communication_objects.hpp"
#include "od/dictionary.hpp"

namespace stepnode::node {

// Where NodeOptions::device.node_id came from. A node-ID an LSS master configured and had
// stored wins over the configuration file's, never over the command line's (README, LSS).
enum class NodeIdOrigin { CommandLine, ConfigFile, None };

struct NodeOptions {
  od::DeviceInfo device;  // node_id lss::kUnconfigured: none, the node waits for LSS
  NodeIdOrigin node_id_origin = NodeIdOrigin::CommandLine;
  DeviceLayout layout;  // the profiles and axes (the PDO count follows)
  std::filesystem::path state_dir = ".";
  uint64_t sdo_timeout_us = 1'000'000;
  // How long the node listens for another device with its node-ID before its first boot-up
  // (README, "Duplicate node-ID"); 0: it boots at once and checks in the claim period only.
  uint64_t boot_listen_us = 0;
  // The wall clock for a TIME producer (us since 1970, CLOCK_REALTIME in node/main.cpp);
  // empty: a producer sends the network time it received (tests give virtual time).
  TimeService::WallClock wall_clock;
  // CiA 305 activate bit timing: the process carries it out on the interface (node/
  // bit_timing_switch.hpp). Empty: the node only logs it (the bit rate is set outside).
  std::function<void(unsigned kbit, uint16_t delay_ms, uint64_t now_us)> activate_bit_timing;
};

// What the CAN controller reports (SocketCAN error frames), as the node sees it.
enum class BusEvent {
  ErrorWarning,
  ErrorPassive,
  ErrorActive,
  BusOff,
  Restarted,
  RxOverflow,
  TxOverflow
};

class CanopenNode {
 public:
  using Send = std::function<void(const od::CanFrame&)>;
  CanopenNode(NodeOptions options, Send send);
  ~CanopenNode();

  // Power-on: load stored parameters, send boot-up, enter pre-operational. Without a
  // node-ID: nothing but the LSS slave, until a master gives it one (CiA 305). With
  // boot_listen_us, the boot-up waits that long, and never comes if another device with
  // the node-ID was heard (the node then waits for LSS, as without a node-ID).
  void start(uint64_t now_us);
  // `arrival_us`: when the frame reached the interface (kernel timestamp; 0 unknown): the
  // synchronous window 0x1007 is measured from a SYNC's arrival.
  void on_frame(const od::CanFrame& frame, uint64_t now_us, uint64_t arrival_us = 0);
  void on_tick(uint64_t now_us);
  // When on_tick next has work (absolute us, node/deadline.hpp): the earliest deadline of
  // every service that runs in the present NMT state, and of the application. Valid until
  // the next frame or tick, after which the loop asks again.
  uint64_t next_deadline_us(uint64_t now_us);
  void on_bus_event(BusEvent event, uint64_t now_us);
  // The socket's count of received frames it dropped (its queue was full), as reported
  // with the latest frame: an increase is EMCY 0x8110 and adds to object 0x2F10.
  void on_receive_overruns(uint32_t socket_total, uint64_t now_us);

  // An error the device found before it could talk (a configured value it refused): sent
  // as EMCY after every power-up and reset node, since the configuration stays the same.
  void report_at_power_up(uint16_t code, std::array<uint8_t, 5> manufacturer);

  NmtState state() const { return state_; }
  uint8_t node_id() const { return options_.device.node_id; }  // lss::kUnconfigured: none
  bool configured() const { return node_id() != lss::kUnconfigured; }
  const LssSlave& lss() const { return lss_; }
  const std::filesystem::path& lss_file() const { return lss_store_.file(); }
  const od::DeviceInfo& device_info() const { return options_.device; }
  od::Dictionary& dictionary() { return dictionary_; }
  EmcyProducer& emcy() { return emcy_; }
  const std::filesystem::path& parameter_file() const { return store_.file(); }
  // The CAN-IDs this node serves now (node/receive_filters.hpp); the application is told
  // of every change (Application::receive_filters_changed).
  const std::vector<ReceiveFilter>& receive_filters();

  // The profiles behind the dictionary (node/device.* sets it); nullptr: none, a bare
  // CiA 301 slave. Not owned; it outlives the node or is reset first.
  void set_application(Application* application) { app_ = application; }

 private:
  void install_service_hooks();
  void initialise(bool reset_application, uint64_t now_us);
  void adopt_node_id(uint8_t node_id);
  void on_lss_frame(const od::CanFrame& frame, uint64_t now_us);
  void load_parameters(uint16_t first, uint16_t last, uint64_t now_us);
  void enter(NmtState next, uint64_t now_us);
  void handle_nmt(NmtCommand command, uint64_t now_us);
  // The application is told first, then 0x1029 says what happens to the NMT state.
  void communication_error(CommunicationError error, uint8_t node, uint64_t now_us);
  // A frame of another device with this node-ID (EMCY 0x8100; yield or keep the node-ID).
  void node_id_conflict(const NodeIdConflict::Finding& finding, uint64_t now_us);
  // Every frame leaves through here: the receive filters are brought up to date first.
  void send(const od::CanFrame& frame) {
    if (filters_dirty_) update_receive_filters();
    send_(frame);
  }
  void update_receive_filters();
  // Whether a frame is one this node handles: its receive filters, and for NMT the target.
  bool serves(const od::CanFrame& frame);

  // Before options_: the node-ID it holds may be the one the node starts with.
  LssStore lss_store_;
  std::optional<LssStore::Contents> lss_stored_;
  NodeOptions options_;
  Send send_;
  Application* app_ = nullptr;
  od::Dictionary dictionary_;
  ParameterStore store_;
  EmcyProducer emcy_;
  HeartbeatProducer heartbeat_;
  HeartbeatConsumer consumer_;
  NodeGuarding guarding_;  // 0x100C, 0x100D; only while 0x1017 is 0
  SyncService sync_;
  TimeService time_;  // 0x1012, 0x2F12
  PdoEngine pdo_;
  SdoServerChannels sdo_;  // 0x1200..0x1203
  LssSlave lss_;
  NodeIdConflict conflict_;
  // 0x1014, looked at for every frame (the conflict check): the entry, not a lookup.
  const od::Entry* emcy_cob_id_ = nullptr;
  NmtState state_ = NmtState::Initialising;
  bool booted_ = false;  // the application was powered up (the first boot with a node-ID)
  struct PowerUpError {
    uint16_t code;
    std::array<uint8_t, 5> manufacturer;
  };
  std::vector<PowerUpError> power_up_errors_;
  uint32_t overruns_seen_ = 0;  // the socket's count when last looked at
  std::vector<ReceiveFilter> filters_;
  bool filters_dirty_ = true;  // a COB-ID object was written, or the node-ID changed
};

}  // namespace stepnode::node
