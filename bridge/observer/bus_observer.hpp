// The bridge's view of a CAN bus: finds nodes from boot-up and heartbeat, reads what it
// needs over SDO (identity, name, axes, every TPDO's COB-ID and mapping), decodes TPDOs,
// heartbeats, EMCY and SYNC, and hands the results to a SampleSink. Pure: frames in,
// frames out, time passed in, so it runs in virtual time in tests.
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "bridge/samples.hpp"
#include "od/can_frame.hpp"

namespace stepnode::bridge {

// A node's SDO server channel given to this bridge (one of its 0x1201..0x1203, CiA 301
// 7.5.2.33): the bridge reads there instead of waiting for quiet on the default channel.
struct NodeSdoChannel {
  uint8_t node = 0;
  uint32_t client_to_server = 0;  // sub 1
  uint32_t server_to_client = 0;  // sub 2
};

struct ObserverConfig {
  uint32_t heartbeat_timeout_ms = 0;  // 0: 3 x the node's heartbeat interval (seen), min 1000
  uint32_t sdo_timeout_ms = 500;
  uint32_t sdo_quiet_ms = 300;       // wait for another master's SDO traffic to end
  uint32_t retry_initial_ms = 200;   // backoff after a failed discovery, doubling ...
  uint32_t retry_max_ms = 10'000;    // ... up to this
  uint32_t health_period_ms = 1000;  // NodeHealth republished at least this often
  // After a failed SDO read (a collision with another master, or the confusion it leaves)
  // the wait for quiet gets a random extra of up to this much, so two bridges on one bus
  // that saw the same boot-up do not collide again and again in lockstep.
  uint32_t collision_jitter_ms = 200;
  uint32_t random_seed = 0;  // 0: taken from the observer's address (differs per process)
  // The socket delivers the bridge's own frames back to it (CAN_RAW_RECV_OWN_MSGS, or a
  // second socket for sending). Then a request equal to one just sent is taken for the
  // echo. Off by default: with SocketCAN's defaults an identical request is another
  // master's (a second bridge reading the same object), and must count as traffic.
  bool own_frames_echoed = false;
  std::vector<NodeSdoChannel> sdo_channels;  // nodes not named here: the default channel
  // The bridge's SDO reads on the whole bus (issue 13, bridge/observer/transfer_pacer.hpp):
  // at most this many transfers in flight at once, over all nodes ...
  uint32_t sdo_max_outstanding = 8;
  // ... and at most this many transfer starts per second on average; 0: no rate bound,
  // as fast as the answers come (stepbridge's default is 1000, bridge/config.hpp).
  uint32_t sdo_rate_per_s = 0;
  // Timestamps on the network's clock (bridge/observer/network_time.hpp): once a TIME
  // frame (COB-ID 0x100) was seen, every frame's kernel timestamp is mapped by the offset
  // between the last TIME stamp and that frame's own kernel arrival, so the samples'
  // can_time_ns are network time. Before a TIME frame, and when off: the host clock.
  bool network_time = false;
};

// A frame as the socket delivered it.
struct ObservedFrame {
  od::CanFrame frame;
  uint64_t can_time_ns = 0;  // kernel receive timestamp, CLOCK_REALTIME
  bool error_frame = false;
  uint32_t error_class = 0;  // CAN_ERR_* bits of an error frame
  uint8_t controller_status = 0;
};

// Samples go out from inside on_frame/on_tick. AxisPositionSample::publish_time_ns is
// left 0: the publisher stamps it when it writes (the observer has no clock).
class BusObserver {
 public:
  BusObserver(SampleSink& sink, const ObserverConfig& config = {});
  ~BusObserver();
  BusObserver(const BusObserver&) = delete;
  BusObserver& operator=(const BusObserver&) = delete;

  // A frame from the bus; SDO requests the observer sends go to `out`.
  void on_frame(const ObservedFrame& received, uint64_t now_us, std::vector<od::CanFrame>& out);
  // The socket's count of frames the kernel dropped from its full receive queue
  // (SO_RXQ_OVFL, a running total): what it grew by counts as overruns. Returns that.
  uint32_t on_socket_overruns(uint32_t socket_total);
  // Timers: SDO timeouts, retries, heartbeat loss, periodic NodeHealth.
  void on_tick(uint64_t now_us, uint64_t realtime_ns, std::vector<od::CanFrame>& out);
  // Shutdown: dispose every known node's axes.
  void dispose_all();

  // Read-only views (tests, logs, the DDS side's statistics).
  const BusCounters& counters() const;
  // Network time minus host time (ns), once a TIME frame was seen with network_time on.
  std::optional<int64_t> network_time_offset_ns() const;
  // The node's health as it would be published now; state Unknown for a node never seen.
  NodeHealthSample node_health(uint8_t node, uint64_t now_us) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace stepnode::bridge
