// The meaning of the Horner register words on the bus (objects 0x2n00 command bits and
// 0x2n01 status bits, SPM30 chapter 3, STP100 chapter 4): the node's axes, stepctl and the
// bridge all read and write these bits, so they are defined once, here.
#pragma once
#include <cstdint>

namespace stepnode::horner {

// %I1..%I16 as bits 0..15 of the status word.
namespace status {
constexpr uint16_t kEmergencyStop = 1u << 0;   // %I1
constexpr uint16_t kLowerLimit = 1u << 1;      // %I2
constexpr uint16_t kUpperLimit = 1u << 2;      // %I3
constexpr uint16_t kIllegalMove = 1u << 3;     // %I4
constexpr uint16_t kMotorStalled = 1u << 4;    // %I5
constexpr uint16_t kPowerUp = 1u << 7;         // %I8 power-up / watchdog
constexpr uint16_t kErrors = 0x00FF;           // %I1..%I8 latch until Clear Errors
constexpr uint16_t kPositionValid = 1u << 8;   // %I9
constexpr uint16_t kResumable = 1u << 9;       // %I10
constexpr uint16_t kAxis2Selected = 1u << 10;  // %I11
constexpr uint16_t kAxis3Selected = 1u << 11;  // %I12
constexpr uint16_t kAtHome = 1u << 12;         // %I13 (at origin)
constexpr uint16_t kAccelerating = 1u << 13;   // %I14
constexpr uint16_t kDecelerating = 1u << 14;   // %I15
constexpr uint16_t kMoving = 1u << 15;         // %I16
}  // namespace status

// %Q1..%Q16 as bits 0..15 of the command word.
namespace command {
constexpr uint16_t kSelectAxis1 = 1u << 0;     // %Q1
constexpr uint16_t kSelectAxis2 = 1u << 1;     // %Q2
constexpr uint16_t kSelectAxis3 = 1u << 2;     // %Q3
constexpr uint16_t kFindHomeUp = 1u << 3;      // %Q4
constexpr uint16_t kFindHomeDown = 1u << 4;    // %Q5
constexpr uint16_t kJogUp = 1u << 5;           // %Q6 (level)
constexpr uint16_t kJogDown = 1u << 6;         // %Q7 (level)
constexpr uint16_t kMoveRelative = 1u << 7;    // %Q8
constexpr uint16_t kMoveAbsolute = 1u << 8;    // %Q9
constexpr uint16_t kResumeMove = 1u << 9;      // %Q10
constexpr uint16_t kMoveIndexed = 1u << 10;    // %Q11 (STP113 / STP100)
constexpr uint16_t kRepeatMove = 1u << 11;     // %Q12 (STP100, level)
constexpr uint16_t kSetPosition = 1u << 12;    // %Q13
constexpr uint16_t kClearErrors = 1u << 13;    // %Q14
constexpr uint16_t kDecelStop = 1u << 14;      // %Q15
constexpr uint16_t kImmediateStop = 1u << 15;  // %Q16
}  // namespace command

}  // namespace stepnode::horner
