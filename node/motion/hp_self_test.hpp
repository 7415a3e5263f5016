// TEST, the HP 44714A's self test (Command Summary 4-3: "Initiates a pass/fail self test").
// The simulated module tests what it is made of: the pulse outputs decode back to the
// direction they encode in every PULSE mode and sense, the pulse engine makes a MOVE of the
// power-on profile with the right count and no pulse faster than max, the position counter
// rounds as the PSCALE round-off example says, and PROFILE finds the settings-conflict
// table's rows. Pure: no channel state is touched, so the settings survive the test.
#pragma once
#include <cstdint>

namespace stepnode::motion::hp {

// The checks, as bits of the failed-checks word.
namespace self_test_check {
constexpr uint8_t kPulseOutputs = 1u << 0;
constexpr uint8_t kPulseEngine = 1u << 1;
constexpr uint8_t kPositionCounter = 1u << 2;
constexpr uint8_t kProfileRules = 1u << 3;
}  // namespace self_test_check

// Runs every check; returns the failed ones (0: the module passed).
uint8_t run_self_test();

}  // namespace stepnode::motion::hp
