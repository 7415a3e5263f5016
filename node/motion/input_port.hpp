// The inputs of one motor as timestamped edges: home, the two limits, the index input, the
// encoder marker, the e-stop and the HALT switch. A back end reports each change with the
// time it happened (a hardware back end: the capture time of the edge; the simulation: the
// tick of the step that moved the load onto or off the switch), so the motion core applies
// it between exactly the steps it fell between, instead of polling the inputs after every
// step. The encoder is a counter, read when needed.
#pragma once
#include <cstdint>

#include "node/motion/timebase.hpp"

namespace stepnode::motion {

enum class Input : uint8_t {
  Home = 1 << 0,
  LowerLimit = 1 << 1,
  UpperLimit = 1 << 2,
  Index = 1 << 3,
  Marker = 1 << 4,
  EmergencyStop = 1 << 5,
  Halt = 1 << 6,  // the HALT input is at its HIGH level (HP 44714A 3-17: HALT LO|HI says
                  // which level halts; the switch open, pulled up, is HIGH)
};

// The two end limits, as a set of Input bits (the inputs a limit rule looks at).
constexpr uint8_t kLimitInputs =
    static_cast<uint8_t>(Input::LowerLimit) | static_cast<uint8_t>(Input::UpperLimit);

// Which inputs are active (a set of Input bits).
struct InputLevels {
  uint8_t active = 0;

  bool is(Input i) const { return (active & static_cast<uint8_t>(i)) != 0; }
  void set(Input i, bool on) {
    if (on) active |= static_cast<uint8_t>(i);
    else active &= static_cast<uint8_t>(~static_cast<uint8_t>(i));
  }
  bool home() const { return is(Input::Home); }
  bool lower_limit() const { return is(Input::LowerLimit); }
  bool upper_limit() const { return is(Input::UpperLimit); }
  bool index() const { return is(Input::Index); }
  bool marker() const { return is(Input::Marker); }
  bool emergency_stop() const { return is(Input::EmergencyStop); }
  bool halt_high() const { return is(Input::Halt); }
  bool operator==(const InputLevels&) const = default;
};

struct InputEdge {
  Tick time = 0;
  Input input = Input::Home;
  bool active = false;  // the level after the edge
  bool operator==(const InputEdge&) const = default;
};

class InputPort {
 public:
  virtual ~InputPort() = default;
  // The levels now (before any edge is read: at power-up).
  virtual InputLevels levels() = 0;
  // The oldest edge not read yet; false when there is none. Edges come in time order.
  virtual bool next_edge(InputEdge& edge) = 0;
  // Whether next_edge may have one: a flag, not a call, because the core asks after every
  // step and almost always the answer is no.
  bool edges_waiting() const { return edges_waiting_; }
  // Encoder counts (0 without an encoder): for a quadrature encoder every edge of A and B,
  // 4 per line, as a quadrature decoder counts them at its finest.
  virtual int64_t encoder_count() const = 0;
  // Whether there is an encoder to count (a front end that needs one, such as homing on a
  // hard stop, refuses to run without).
  virtual bool has_encoder() const = 0;

 protected:
  bool edges_waiting_ = true;  // the back end sets it when it has an edge or a change to look at
};

}  // namespace stepnode::motion
