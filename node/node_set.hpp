// Many CANopen nodes in one process (issue 13): N independent Devices, each with its own
// dictionary, NMT state and state files, behind one bus connection and one clock. Pure like
// Device (no sockets, no clocks): node/node_process.* connects it to SocketCAN and
// CLOCK_MONOTONIC, tests and node/bench/multi_node_bench.cpp drive it in virtual time.
//
// On a bus each node would have its own controller and hear every other node's frames.
// Here they share one socket, which never receives its own frames, so a frame one node
// sends goes to the bus and is also delivered to the other nodes of the set, in send order,
// after the call that sent it returns (as a bus would deliver it later, never inside the
// sender's handler). A frame is handed only to the nodes whose receive filters name its
// CAN-ID (a table CAN-ID -> nodes built from the filters); a node still checks every frame
// itself, so the table only spares the others the call.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "node/deadline.hpp"
#include "node/device.hpp"

namespace stepnode::node {

// The receive queue to ask for `nodes` nodes behind one socket, given `one_socket`, the size a
// socket has by default as the kernel counts it (twice what is asked): the queues of that
// many separate processes together, so a burst one process alone would hold is held here.
inline size_t receive_buffer_request(size_t nodes, size_t one_socket) {
  return nodes * (one_socket / 2);
}

class NodeSet {
 public:
  // Hands a frame to the bus; false where the process dropped it instead (a bit timing
  // switch's quiet time): the other nodes of the set hear only what goes to the bus.
  using Send = std::function<bool(const od::CanFrame&)>;
  // One Device per options entry (node/node_id_list.hpp makes them). Every node is ticked
  // at least every `max_sleep_us` (--tick-us), as one node alone was.
  NodeSet(const std::vector<NodeOptions>& options, const Device::ObjectDefaults& defaults,
          Send to_bus, uint64_t max_sleep_us = kNoDeadline);
  ~NodeSet();
  NodeSet(const NodeSet&) = delete;
  NodeSet& operator=(const NodeSet&) = delete;

  size_t size() const { return devices_.size(); }
  Device& device(size_t index) { return *devices_[index]; }

  // Power-on of every node, in order; then each hears the others' boot-ups.
  void start(uint64_t now_us);
  // A frame from the bus, to the nodes that want it.
  void on_frame(const od::CanFrame& frame, uint64_t now_us, uint64_t arrival_us = 0);
  // Ticks the nodes whose deadline has come (or which have not run for max_sleep_us).
  void on_tick(uint64_t now_us);
  // The earliest deadline of all nodes (absolute us; node/deadline.hpp).
  uint64_t next_deadline_us() const;
  void on_bus_event(BusEvent event, uint64_t now_us);
  void on_receive_overruns(uint32_t socket_total, uint64_t now_us);

  // Where the kernel receive filters of the whole set go: the union of every node's list,
  // sorted; empty means every frame (a node without filters, or a union longer than the
  // kernel's kMaxReceiveFilters: the table then routes in software alone). Given the
  // current union at once, then every change.
  using FilterSink = std::function<void(const std::vector<ReceiveFilter>&)>;
  void set_receive_filter_sink(FilterSink sink);

  // Frames one node sent that were handed to another node of the set (figures, tests).
  uint64_t local_deliveries() const { return local_deliveries_; }

 private:
  struct SentFrame {
    od::CanFrame frame;
    size_t sender;
  };
  void sent(size_t sender, const od::CanFrame& frame);
  // Hands the frames the nodes sent to the other nodes, until no more are sent.
  void deliver_sent(uint64_t now_us);
  // To every node whose filters name frame.id, except `except` (the sender).
  void route(const od::CanFrame& frame, uint64_t now_us, uint64_t arrival_us, size_t except);
  void refresh_deadline(size_t index, uint64_t now_us);
  void filters_changed(size_t index, const std::vector<ReceiveFilter>& filters);
  void rebuild_routes();
  void publish_union();

  static constexpr size_t kNone = static_cast<size_t>(-1);
  static constexpr size_t kCanIds = 0x800;
  Send to_bus_;
  uint64_t max_sleep_us_;
  std::vector<std::unique_ptr<Device>> devices_;
  std::vector<uint64_t> deadlines_;  // each node's, as it said after its last call
  std::vector<SentFrame> sent_;      // to deliver locally, in send order
  bool delivering_ = false;
  uint64_t local_deliveries_ = 0;
  // Each node's receive filters (empty: every frame) and the table built from them: the
  // nodes for CAN-ID c are route_nodes_[route_begin_[c] .. route_begin_[c + 1]).
  std::vector<std::vector<ReceiveFilter>> filters_;
  std::array<uint32_t, kCanIds + 1> route_begin_{};
  std::vector<uint16_t> route_nodes_;
  bool routes_dirty_ = true;
  FilterSink sink_;
  std::vector<ReceiveFilter> union_;
  bool union_sent_ = false;
};

}  // namespace stepnode::node
