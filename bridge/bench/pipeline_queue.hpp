// pipeline_bench's generator thread -> bridge thread: the frames, and the run the main
// thread asks the generator for.
#pragma once
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <utility>
#include <vector>

#include "od/can_frame.hpp"

namespace stepnode::bench {

using Clock = std::chrono::steady_clock;

struct Item {
  od::CanFrame frame;
  uint64_t can_time_ns = 0;
};

// Generator -> bridge thread, like a socket: the bridge thread sleeps until something is
// queued (or its tick is due) and then takes everything waiting at once.
class FrameQueue {
 public:
  void push(std::vector<Item>& batch) {
    if (batch.empty()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      items_.insert(items_.end(), batch.begin(), batch.end());
      pushed_ += batch.size();
    }
    batch.clear();
    cv_.notify_one();
  }
  // False when stopped. `out` gets every queued item (may be none at the deadline).
  bool take(std::vector<Item>& out, Clock::time_point deadline) {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait_until(lock, deadline, [&] { return stop_ || !items_.empty(); });
    if (stop_) return false;
    max_backlog_ = std::max(max_backlog_, items_.size());
    out.swap(items_);
    return true;
  }
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    cv_.notify_one();
  }
  uint64_t pushed() {
    std::lock_guard<std::mutex> lock(mutex_);
    return pushed_;
  }
  size_t take_max_backlog() {
    std::lock_guard<std::mutex> lock(mutex_);
    return std::exchange(max_backlog_, 0);
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<Item> items_;
  uint64_t pushed_ = 0;
  size_t max_backlog_ = 0;
  bool stop_ = false;
};

// A run the main thread asks the generator for.
struct RunRequest {
  std::atomic<int> phase{0};  // 0 idle, 1 requested, 2 running, 3 done
  int rate = 0;
  int64_t total = 0;
  int32_t first_seq = 0;
};

}  // namespace stepnode::bench
