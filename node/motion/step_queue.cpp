#include "node/motion/step_queue.hpp"

namespace stepnode::motion {

std::size_t StepQueue::cancel_after(Tick after) {
  std::size_t dropped = 0;
  while (!queued_.empty() && queued_.back().time > after) {
    queued_.pop_back();
    ++dropped;
  }
  return dropped;
}

std::optional<int64_t> StepQueue::position_at(Tick time) const {
  int64_t at = count_;
  // Ahead: the queued steps that will have gone out by then.
  for (const Entry& e : queued_) {
    if (e.time > time) break;
    at += e.direction;
  }
  // Back: undo the steps that went out after `time`, newest first.
  const uint64_t kept = sent_ < history_.size() ? sent_ : history_.size();
  for (uint64_t i = 1; i <= kept; ++i) {
    const Entry& e = history_[(sent_ - i) & mask_];
    if (e.time <= time) return at;
    at -= e.direction;
  }
  // Every step kept went out after `time`: the answer is known only if none was forgotten.
  if (sent_ <= history_.size()) return at;
  return std::nullopt;
}

}  // namespace stepnode::motion
