// The node run as node/main.cpp runs it since issue 13: woken only at its own earliest
// deadline, so a test sees at which virtual instant each frame goes out when nothing polls.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>

#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {

class EventDrivenHarness : public NodeHarness {
 protected:
  // Wakes the node at its deadlines (bounded by `bound_us` after each wake-up, as
  // --tick-us bounds the process's sleep) up to `until`; time ends at `until`. Returns
  // the number of wake-ups.
  unsigned run_event_driven(uint64_t until, uint64_t bound_us = 10'000'000) {
    unsigned wakeups = 0;
    for (;;) {
      const uint64_t next = std::min(device->next_deadline_us(t), t + bound_us);
      EXPECT_GT(next, t) << "a deadline at or before now after a tick would spin the loop";
      if (next > until || next <= t) break;
      t = next;
      device->on_tick(t);
      ++wakeups;
    }
    t = until;
    return wakeups;
  }
  uint64_t deadline() { return device->next_deadline_us(t); }
};

}  // namespace stepnode::node::test
