// The bookkeeping a step back end needs behind motion::StepPort: the steps queued ahead of
// their time, the ones that went out (a bounded history), and where the motor was at a
// time. The simulated machine keeps its steps here; a hardware back end would keep the
// steps it has sent here too, to answer position_at.
#pragma once
#include <bit>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "node/motion/timebase.hpp"

namespace stepnode::motion {

class StepQueue {
 public:
  struct Entry {
    Tick time;
    int direction;  // +1 / -1
  };

  // `history`: how many of the steps that went out are kept for position_at (rounded up
  // to a power of two: a step costs a store and an increment).
  explicit StepQueue(std::size_t history = 4096)
      : history_(std::bit_ceil(history)), mask_(history_.size() - 1) {}

  void push(Tick time, int direction) { queued_.push_back({time, direction >= 0 ? +1 : -1}); }
  bool due(Tick until) const { return !queued_.empty() && queued_.front().time <= until; }
  // The oldest queued step, which goes out now (call only while due()).
  Entry pop() {
    Entry e = queued_.front();
    queued_.pop_front();
    went_out(e.time, e.direction);
    return e;
  }
  // A step that went out without being queued (a step given at its time); direction +1/-1.
  void went_out(Tick time, int direction) {
    count_ += direction;
    history_[sent_ & mask_] = {time, direction};
    ++sent_;
  }
  // Drops the queued steps after `after`; returns how many.
  std::size_t cancel_after(Tick after);
  // The net step count at `time` (see StepPort::position_at).
  std::optional<int64_t> position_at(Tick time) const;

  int64_t count() const { return count_; }  // net steps that went out
  std::size_t queued() const { return queued_.size(); }

 private:
  std::deque<Entry> queued_;
  std::vector<Entry> history_;  // a ring: step n that went out is in slot n & mask_
  uint64_t mask_;
  uint64_t sent_ = 0;  // steps that went out (history_ holds the last of them)
  int64_t count_ = 0;
};

}  // namespace stepnode::motion
