// The Horner module's register model for one axis (SPM30 chapter 3, STP100 chapter 4):
// 16 command bits (%Q), 16 status bits (%I), and the command words (%AQ).
#pragma once
#include <cstdint>

#include "node/profiles/horner/bits.hpp"

namespace stepnode::motion {

// %I1..%I16 and %Q1..%Q16 as bits 0..15 of the status and command words (od/axis_bits.hpp).
namespace status = horner::status;
namespace command = horner::command;

// %AQ1..%AQ14. Power-on values are a usable slow profile.
struct CommandWords {
  int32_t destination = 0;             // %AQ1/2, -8,388,608..+8,388,607
  uint16_t velocity_divisor = 600;     // %AQ3, 20..65535
  uint16_t base_velocity = 100;        // %AQ4, 1..8190
  uint16_t running_velocity = 1000;    // %AQ5, 2..8191, > base
  uint16_t acceleration_ms = 500;      // %AQ6, 1..27300
  uint16_t deceleration_ms = 0;        // %AQ7, 0..27300 (0 = acceleration)
  uint32_t index_destination = 0;      // %AQ8/9, steps after the index input
  uint16_t index_deceleration_ms = 0;  // %AQ10 (0 = %AQ7)
  uint32_t index_window_open = 0;      // %AQ11/12, steps after the move's start
  uint32_t index_window_close = 0;     // %AQ13/14
};

// Whether `bit` is on in a command or status word.
constexpr bool is_set(uint16_t bits, uint16_t bit) { return (bits & bit) != 0; }

constexpr int32_t kPositionMin = -8'388'608;
constexpr int32_t kPositionMax = 8'388'607;

}  // namespace stepnode::motion
