// What an axis drives and senses, one motor: the step output (node/motion/step_port.hpp)
// and the inputs (node/motion/input_port.hpp). The simulated machine implements it
// (node/sim); a hardware back end (a pulse generator, GPIO with edge capture) implements the
// same two interfaces.
#pragma once
#include "node/motion/input_port.hpp"
#include "node/motion/step_port.hpp"

namespace stepnode::motion {

class MotorPort : public StepPort, public InputPort {};

}  // namespace stepnode::motion
