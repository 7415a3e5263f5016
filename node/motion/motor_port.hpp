// What an axis drives and senses: the step sink (every step with its exact time and
// direction) and the inputs it reads. The simulated machine implements it (node/sim); a
// hardware backend (GPIO, a pulse generator) will implement the same interface.
#pragma once
#include <cstdint>

#include "node/motion/timebase.hpp"

namespace stepnode::motion {

class MotorPort {
 public:
  virtual ~MotorPort() = default;
  // One step pulse at `time` (+1 up, -1 down).
  virtual void step(Tick time, int direction) = 0;
  virtual bool home() const = 0;
  virtual bool lower_limit() const = 0;
  virtual bool upper_limit() const = 0;
  virtual bool index() const = 0;
  virtual bool marker() const = 0;
  // Encoder counts (0 without an encoder).
  virtual int64_t encoder_count() const = 0;
};

}  // namespace stepnode::motion
