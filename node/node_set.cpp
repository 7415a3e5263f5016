#include "node/node_set.hpp"

#include <algorithm>

namespace stepnode::node {

NodeSet::NodeSet(const std::vector<NodeOptions>& options, const Device::ObjectDefaults& defaults,
                 Send to_bus, uint64_t max_sleep_us)
    : to_bus_(std::move(to_bus)), max_sleep_us_(max_sleep_us) {
  devices_.reserve(options.size());
  filters_.resize(options.size());
  deadlines_.assign(options.size(), 0);  // due at once: start() sets them
  for (size_t i = 0; i < options.size(); ++i) {
    devices_.push_back(std::make_unique<Device>(options[i], defaults,
                                                [this, i](const od::CanFrame& f) { sent(i, f); }));
    devices_[i]->set_receive_filter_sink(
        [this, i](const std::vector<ReceiveFilter>& f) { filters_changed(i, f); });
  }
}

NodeSet::~NodeSet() = default;

void NodeSet::sent(size_t sender, const od::CanFrame& frame) {
  // Dropped before the bus (found in review: a node watching another's heartbeat kept
  // hearing it through a bit timing switch's quiet time, when separate processes hear none).
  if (to_bus_(frame) && devices_.size() > 1) sent_.push_back({frame, sender});
}

void NodeSet::start(uint64_t now_us) {
  // All power up first: a node that has not started yet must not be handed a frame.
  for (auto& d : devices_) d->start(now_us);
  deliver_sent(now_us);
  for (size_t i = 0; i < devices_.size(); ++i) refresh_deadline(i, now_us);
}

void NodeSet::on_frame(const od::CanFrame& frame, uint64_t now_us, uint64_t arrival_us) {
  route(frame, now_us, arrival_us, kNone);
  deliver_sent(now_us);
}

void NodeSet::on_tick(uint64_t now_us) {
  for (size_t i = 0; i < devices_.size(); ++i) {
    if (deadlines_[i] > now_us) continue;
    devices_[i]->on_tick(now_us);
    refresh_deadline(i, now_us);
    deliver_sent(now_us);  // before the next node runs: the bus order is the send order
  }
}

uint64_t NodeSet::next_deadline_us() const {
  // A scan: 127 comparisons per wake-up cost less than keeping a heap up to date after
  // every frame each node handles (node/bench/multi_node_bench.cpp has the figures).
  uint64_t next = kNoDeadline;
  for (uint64_t d : deadlines_) next = std::min(next, d);
  return next;
}

void NodeSet::on_bus_event(BusEvent event, uint64_t now_us) {
  for (size_t i = 0; i < devices_.size(); ++i) {
    devices_[i]->on_bus_event(event, now_us);
    refresh_deadline(i, now_us);
  }
  deliver_sent(now_us);
}

void NodeSet::on_receive_overruns(uint32_t socket_total, uint64_t now_us) {
  // The socket is every node's: each lost what it would have received (EMCY 0x8110 each,
  // as N processes behind one overrun queue would report).
  for (size_t i = 0; i < devices_.size(); ++i) {
    devices_[i]->on_receive_overruns(socket_total, now_us);
    refresh_deadline(i, now_us);
  }
  deliver_sent(now_us);
}

void NodeSet::deliver_sent(uint64_t now_us) {
  if (delivering_) return;  // the outer call goes on with what was added
  delivering_ = true;
  // Indexes, not iterators: a node handed a frame may send more, appended here.
  for (size_t k = 0; k < sent_.size(); ++k) {
    const SentFrame s = sent_[k];
    route(s.frame, now_us, now_us, s.sender);
  }
  sent_.clear();
  delivering_ = false;
}

void NodeSet::route(const od::CanFrame& frame, uint64_t now_us, uint64_t arrival_us,
                    size_t except) {
  if (routes_dirty_) rebuild_routes();
  // A node changing its filters while it handles the frame only marks the table dirty:
  // the range below stays valid until the next route().
  const size_t id = frame.id & (kCanIds - 1);
  for (uint32_t k = route_begin_[id]; k < route_begin_[id + 1]; ++k) {
    const size_t i = route_nodes_[k];
    if (i == except) continue;
    if (except != kNone) ++local_deliveries_;
    devices_[i]->on_frame(frame, now_us, arrival_us);
    refresh_deadline(i, now_us);
  }
}

void NodeSet::refresh_deadline(size_t index, uint64_t now_us) {
  const uint64_t bound = max_sleep_us_ == kNoDeadline ? kNoDeadline : now_us + max_sleep_us_;
  deadlines_[index] = std::min(devices_[index]->next_deadline_us(now_us), bound);
}

void NodeSet::filters_changed(size_t index, const std::vector<ReceiveFilter>& filters) {
  filters_[index] = filters;
  routes_dirty_ = true;
  if (sink_) publish_union();
}

void NodeSet::rebuild_routes() {
  routes_dirty_ = false;
  // Counting sort by CAN-ID: node indexes ascending within an id (the order they are
  // handed a frame). A node without filters is in every id's list.
  std::array<uint32_t, kCanIds + 1> count{};
  auto each = [this](auto&& f) {
    for (size_t i = 0; i < filters_.size(); ++i) {
      if (filters_[i].empty())
        for (uint32_t id = 0; id < kCanIds; ++id) f(id, i);
      else
        for (const ReceiveFilter& r : filters_[i]) f(r.id & (kCanIds - 1), i);
    }
  };
  each([&count](uint32_t id, size_t) { ++count[id + 1]; });
  for (size_t c = 0; c < kCanIds; ++c) count[c + 1] += count[c];
  route_begin_ = count;
  route_nodes_.assign(count[kCanIds], 0);
  each([&count, this](uint32_t id, size_t i) {
    route_nodes_[count[id]++] = static_cast<uint16_t>(i);
  });
}

void NodeSet::set_receive_filter_sink(FilterSink sink) {
  sink_ = std::move(sink);
  union_sent_ = false;
  publish_union();
}

void NodeSet::publish_union() {
  std::vector<ReceiveFilter> all;
  bool everything = false;
  for (const auto& f : filters_) {
    everything |= f.empty();
    all.insert(all.end(), f.begin(), f.end());
  }
  // Sorted by id then kind: of one id's entries the last is DataAndRemote if any is.
  std::sort(all.begin(), all.end());
  std::vector<ReceiveFilter> out;
  for (const ReceiveFilter& r : all) {
    if (!out.empty() && out.back().id == r.id) out.back() = r;
    else out.push_back(r);
  }
  if (everything || out.size() > kMaxReceiveFilters) out.clear();
  if (union_sent_ && out == union_) return;
  union_ = std::move(out);
  union_sent_ = true;
  sink_(union_);
}

}  // namespace stepnode::node
