// The CiA 402 profile's objects (CiA 402-2 / IEC 61800-7-201): device control, the option
// codes, modes of operation, the position, velocity, homing and interpolation objects, the
// factor group, digital inputs and the supported modes, for each axis, and their default
// PDOs. Axis a (0-based) has its objects at index + 0x800 * a: axis 1 at 0x6000..0x67FF,
// axis 2 at 0x6800..0x6FFF, up to 8 axes (CiA 402-2, multiple axes). Pure table, shared by
// the node, stepctl and the bridge; the drive's state machine is node/profiles/cia402/
// drive_state.*.
#pragma once
#include <cstdint>

#include "od/dictionary.hpp"

namespace stepnode::cia402 {

constexpr unsigned kMaxAxes = 8;
constexpr uint16_t kAxisOffset = 0x800;

// Indices of axis 1; index(axis, base) gives the others.
namespace obj {
constexpr uint16_t kAbortConnectionOption = 0x6007;      // I16 rw
constexpr uint16_t kErrorCode = 0x603F;                  // U16 ro
constexpr uint16_t kControlword = 0x6040;                // U16 rw
constexpr uint16_t kStatusword = 0x6041;                 // U16 ro
constexpr uint16_t kQuickStopOption = 0x605A;            // I16 rw
constexpr uint16_t kShutdownOption = 0x605B;             // I16 rw
constexpr uint16_t kDisableOperationOption = 0x605C;     // I16 rw
constexpr uint16_t kHaltOption = 0x605D;                 // I16 rw
constexpr uint16_t kFaultReactionOption = 0x605E;        // I16 rw
constexpr uint16_t kModesOfOperation = 0x6060;           // I8 rw
constexpr uint16_t kModesOfOperationDisplay = 0x6061;    // I8 ro
constexpr uint16_t kPositionDemand = 0x6062;             // I32 ro, position units
constexpr uint16_t kPositionActualInternal = 0x6063;     // I32 ro, increments
constexpr uint16_t kPositionActual = 0x6064;             // I32 ro, position units
constexpr uint16_t kFollowingErrorWindow = 0x6065;       // U32 rw
constexpr uint16_t kFollowingErrorTimeout = 0x6066;      // U16 rw, ms
constexpr uint16_t kPositionWindow = 0x6067;             // U32 rw
constexpr uint16_t kPositionWindowTime = 0x6068;         // U16 rw, ms
constexpr uint16_t kVelocityActual = 0x606C;             // I32 ro, velocity units
constexpr uint16_t kTargetPosition = 0x607A;             // I32 rw
constexpr uint16_t kHomeOffset = 0x607C;                 // I32 rw
constexpr uint16_t kSoftwarePositionLimit = 0x607D;      // ARRAY I32
constexpr uint16_t kMaxProfileVelocity = 0x607F;         // U32 rw
constexpr uint16_t kProfileVelocity = 0x6081;            // U32 rw
constexpr uint16_t kProfileAcceleration = 0x6083;        // U32 rw
constexpr uint16_t kProfileDeceleration = 0x6084;        // U32 rw
constexpr uint16_t kQuickStopDeceleration = 0x6085;      // U32 rw
constexpr uint16_t kMotionProfileType = 0x6086;          // I16 rw
constexpr uint16_t kProfileJerk = 0x60A4;                // ARRAY U32
constexpr uint16_t kPositionEncoderResolution = 0x608F;  // ARRAY U32
constexpr uint16_t kGearRatio = 0x6091;                  // ARRAY U32
constexpr uint16_t kFeedConstant = 0x6092;               // ARRAY U32
constexpr uint16_t kHomingMethod = 0x6098;               // I8 rw
constexpr uint16_t kHomingSpeeds = 0x6099;               // ARRAY U32
constexpr uint16_t kHomingAcceleration = 0x609A;         // U32 rw
constexpr uint16_t kPositionOffset = 0x60B0;             // I32 rw
constexpr uint16_t kVelocityOffset = 0x60B1;             // I32 rw
constexpr uint16_t kInterpolationSubMode = 0x60C0;       // I16 rw
constexpr uint16_t kInterpolationData = 0x60C1;          // ARRAY I32
constexpr uint16_t kInterpolationPeriod = 0x60C2;        // RECORD U8, I8
constexpr uint16_t kFollowingErrorActual = 0x60F4;       // I32 ro
constexpr uint16_t kDigitalInputs = 0x60FD;              // U32 ro
constexpr uint16_t kTargetVelocity = 0x60FF;             // I32 rw
constexpr uint16_t kSupportedDriveModes = 0x6502;        // U32 ro
constexpr uint16_t kSingleDeviceType = 0x67FF;           // U32 ro
// The index of object `base` (an axis-1 index above) for axis `axis` (0-based).
inline uint16_t index(unsigned axis, uint16_t base) {
  return static_cast<uint16_t>(base + kAxisOffset * axis);
}
}  // namespace obj

// Sub-indices of the arrays and the record.
namespace limit_sub {
constexpr uint8_t kMin = 1, kMax = 2;  // 607Dh min / max position limit
}
namespace encoder_sub {
constexpr uint8_t kIncrements = 1, kMotorRevolutions = 2;  // 608Fh
}
namespace gear_sub {
constexpr uint8_t kMotorRevolutions = 1, kShaftRevolutions = 2;  // 6091h
}
namespace feed_sub {
constexpr uint8_t kFeed = 1, kShaftRevolutions = 2;  // 6092h
}
namespace homing_speed_sub {
constexpr uint8_t kSwitchSearch = 1, kZeroSearch = 2;  // 6099h
}
namespace jerk_sub {
// 60A4h as drives number it (Nanotec PD4 manual): the jerk at each end of the ramps.
constexpr uint8_t kBeginAcceleration = 1, kBeginDeceleration = 2, kEndAcceleration = 3,
                  kEndDeceleration = 4;
}  // namespace jerk_sub
namespace ip_data_sub {
constexpr uint8_t kSetPoint = 1;  // 60C1h: the position set-point of linear interpolation
}
namespace ip_period_sub {
constexpr uint8_t kUnits = 1, kIndex = 2;  // 60C2h: the period is units * 10^index s
}

// 6060h modes of operation this drive accepts (0: no mode assigned). 2 velocity mode, 4
// profile torque and 10 cyclic synchronous torque are not stepper modes here.
namespace mode {
constexpr int8_t kNone = 0, kProfilePosition = 1, kProfileVelocity = 3, kHoming = 6,
                 kInterpolatedPosition = 7, kCyclicSyncPosition = 8, kCyclicSyncVelocity = 9;
}
bool mode_supported(int8_t mode);

// 6502h: bit 0 pp, 2 pv, 5 hm, 6 ip, 7 csp, 8 csv (1 vl, 3 tq, 9 cst, 10 cstca not
// supported): the modes the drive runs.
constexpr uint32_t kSupportedDriveModesValue =
    (1u << 0) | (1u << 2) | (1u << 5) | (1u << 6) | (1u << 7) | (1u << 8);
static_assert(kSupportedDriveModesValue == 0x1E5);

// 67FFh + 0x800 * axis, the device type of each axis: bits 0-15 the profile number 402
// (0x192), bits 16-23 the type, bits 24-31 the mode bits (none). Type 04h is a stepper drive
// (02h a servo drive), as CiA 402 device stacks code it (TI's EtherCAT SubDevice API:
// 0x00020192 servo, 0x00040192 stepper). A device with several axes says FFFFh in 1000h's
// bits 16-31 and the profile of its first axis in bits 0-15 (CiA 301, 1000h).
constexpr uint32_t kDeviceTypeStepper = 0x0004'0192;

// 60FDh digital inputs.
namespace input {
constexpr uint32_t kNegativeLimit = 1u << 0, kPositiveLimit = 1u << 1, kHomeSwitch = 1u << 2,
                   kInterlock = 1u << 3;
}

// The objects of `axes` axes (1..kMaxAxes).
void add_objects(od::Dictionary& od, unsigned axes);

// The default PDOs of axis `a`: PDO numbers n (0-based: communication 0x1400 + n / 0x1800 + n,
// mapping 0x1600 + n / 0x1A00 + n) first_rpdo {6040h, 6060h}, first_rpdo + 1 {607Ah, 60FFh},
// first_tpdo {6041h, 6061h}, first_tpdo + 1 {6064h, 606Ch}. The PDO objects must exist.
void set_default_pdos(od::Dictionary& od, unsigned a, unsigned first_rpdo, unsigned first_tpdo);

}  // namespace stepnode::cia402
