// How many frames the bridge handles per wake-up of its loop (issue 13). Draining the
// socket until it is empty never ends under a flood: the loop then never reaches its
// timers (SDO timeouts, heartbeat loss, the watchdog) nor SIGTERM. So one wake-up handles
// at most a budget of frames and returns; the socket is level-triggered in epoll, so what
// is left makes the next epoll_wait return at once, together with any timer or signal
// that became ready meanwhile, and each gets its turn.
#pragma once
#include <cstddef>

namespace stepnode::bridge {

// 64 frames are a few hundred microseconds of the bridge's work, and at 1 Mbit/s a full
// bus brings about 8 frames per millisecond: a flood is still drained faster than it
// comes, with a turn for the timers every 64 frames.
constexpr size_t kFramesPerTurn = 64;

// Calls `handle(frame)` for each frame `receive()` gives (an optional-like: false when the
// socket is empty), at most `budget` of them. Returns how many were handled.
template <class Receive, class Handle>
size_t handle_frames(Receive&& receive, Handle&& handle, size_t budget = kFramesPerTurn) {
  size_t handled = 0;
  while (handled < budget) {
    auto frame = receive();
    if (!frame) break;
    handle(*frame);
    ++handled;
  }
  return handled;
}

}  // namespace stepnode::bridge
