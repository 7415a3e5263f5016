// CiA 305 "activate bit timing" carried out on the interface (with --apply-bit-timing): the
// switch delay d of the command is waited twice, once before the controller switches and
// once after, and the node transmits nothing in those 2·d (CiA 305: every device of the
// network switches together; a frame in between would be at a bit rate the others no
// longer or not yet use). Pure, in the node's microseconds: node/node_process.cpp gives it
// a timer and the call that sets the controller (canio/link_config.hpp).
#pragma once
#include <cstdint>
#include <functional>
#include <string>

namespace stepnode::node {

class BitTimingSwitch {
 public:
  // Sets the interface's bit rate (bit/s); returns "" or why it failed, in one line.
  using Apply = std::function<std::string(uint32_t bit_rate)>;
  explicit BitTimingSwitch(Apply apply) : apply_(std::move(apply)) {}

  // The command, heard at `now_us`. Every node of a process hears the same broadcast: a
  // second activation while one is under way changes nothing.
  void activate(unsigned kbit, uint16_t delay_ms, uint64_t now_us);
  bool active() const { return active_; }  // a switch is under way
  // Whether frames are held back now (from the command to the end of the second delay).
  bool silent(uint64_t now_us) const { return active_ && now_us < quiet_until_us_; }
  // When on_tick next has work; kNoDeadline (node/deadline.hpp) when nothing is pending.
  uint64_t next_deadline_us() const;
  void on_tick(uint64_t now_us);
  // Frames the node made in the quiet time and did not send (logged when it ends).
  void dropped_one() { ++dropped_; }

 private:
  Apply apply_;
  bool active_ = false;
  bool switched_ = false;
  unsigned kbit_ = 0;
  uint64_t switch_at_us_ = 0;
  uint64_t quiet_until_us_ = 0;
  uint64_t dropped_ = 0;
};

}  // namespace stepnode::node
