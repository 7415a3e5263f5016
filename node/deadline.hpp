// When a part of the node next needs to run (issue 13, event-driven timing): an absolute
// microsecond on the node's clock, the same clock as every on_tick/on_frame `now_us`.
// node/main.cpp arms one timer for the earliest deadline of the whole node, bounded by
// --tick-us, instead of ticking every millisecond.
#pragma once
#include <algorithm>
#include <cstdint>
#include <limits>

namespace stepnode::node {

// Nothing timed: only a frame (or the loop's upper bound) wakes the node for this part.
constexpr uint64_t kNoDeadline = std::numeric_limits<uint64_t>::max();

// The conservative answer of a part that cannot say exactly when it next needs to run: in
// one poll period, the node's fixed 1 ms tick before issue 13. So a part that is not (yet)
// precise behaves as it always did, and correctness never depends on a deadline forgotten.
// Still used by: the defaults of Application and Profile (a part that does not say), an
// axis whose job ended without its owner told yet (AxisBank, one wake-up at most), a
// send queue the kernel refuses though the socket says writable (node_process), and, as
// the wake period of a moving axis at horizon 0, the batch of steps denser than it
// (AxisBank; README "Running a node" says why).
constexpr uint64_t kPollUs = 1000;
constexpr uint64_t poll_deadline(uint64_t now_us) { return now_us + kPollUs; }

constexpr uint64_t earliest(uint64_t a, uint64_t b) { return std::min(a, b); }

}  // namespace stepnode::node
