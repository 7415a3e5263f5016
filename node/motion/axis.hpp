// One axis of the Horner module: every command bit and status bit with its rules
// (SPM30 chapters 3-5, STP100 chapters 4-6, STP113 appendix C), driving the pulse engine
// and a simulated (or real) machine. Pure and deterministic: time comes in as ticks.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "node/motion/axis_registers.hpp"
#include "node/motion/encoder_kind.hpp"
#include "node/motion/motor_port.hpp"
#include "node/motion/step_generator.hpp"

namespace stepnode::motion {

// Where the two manuals differ, both behaviours are settings (the default is the SPM30).
struct AxisConfig {
  enum class HomeMethod { Normal, Simple };          // STP113 C1.2.1 / STP100 3.2.3
  enum class OriginSource { HomeSwitch, Marker };    // STP100 3.2.3 (SPM30: marker = QUAD)
  HomeMethod home_method = HomeMethod::Normal;
  OriginSource origin_source = OriginSource::HomeSwitch;
  bool limit_qualified_home = false;  // STP100 3.2.3; SPM30 does this with encoder QUAD
  EncoderKind encoder = EncoderKind::None;
  int64_t encoder_multiplier = 1;  // 1..255
  int64_t encoder_divisor = 1;     // 1..16
  int64_t encoder_tolerance = 0;   // 0..255, 0 = no position validation
  bool stall_detection = false;    // STP100 6.3.3 (SPM30: on when the tolerance is set)
  bool indexed_moves = true;       // %Q11 is Move Indexed (STP113, STP100)
  bool limit_started_moves = false;  // STP100 5.3.4: a move toward an active limit waits
};

// What the axis reports as it happens (status changes go out on the bus at once).
struct AxisEvent {
  enum Kind { StatusChanged, Error, MoveDone } kind;
  uint16_t status;
  uint16_t error_bits;  // for Error: the bits that just latched
};

class Axis {
 public:
  // `motors`: where steps go and inputs come from (the simulated machine or hardware): one,
  // or three for an SPM30 multiplexed axis. `estop` is the e-stop input.
  Axis(AxisConfig config, std::vector<MotorPort*> motors, const bool* estop);

  // Power-up or watchdog reset (also NMT reset node): everything off, %I8 on.
  void power_up(Tick now);
  // The command bits as the master last wrote them; edges act at once (after advancing
  // the axis to `now`).
  void write_commands(uint16_t bits, Tick now);
  CommandWords& words() { return words_; }
  const CommandWords& words() const { return words_; }

  // Takes every step due up to `now` and reacts to the inputs they change.
  void advance_to(Tick now);
  // The master was lost (heartbeat consumer timeout): decelerate and latch %I8.
  void master_lost(Tick now);

  uint16_t status() const;
  int32_t motor_position() const { return motor_position_; }
  int32_t encoder_position() const;
  double velocity() const { return generator_.velocity(); }
  MotionPhase phase() const { return generator_.phase(); }
  bool dir_output_high() const { return dir_high_; }  // DIR+ level (STP100 5.3.5)
  unsigned selected_motor() const { return selected_; }
  std::optional<Tick> next_step_time();

  const AxisConfig& config() const { return config_; }
  void set_config(const AxisConfig& config) { config_ = config; }
  std::function<void(const AxisEvent&)> on_event;

  // Another front end's job (the HP 44714A channel, node/motion/hp_channel.*): the axis
  // runs the same generator on the same position and motor, and leaves the rules to the
  // front end. Limits are the front end's (HP HARDLIM has its own senses and outcome); the
  // e-stop, and the Horner stops (%Q15/%Q16), still end it.
  enum class ExternalEnd { Completed, Aborted };
  bool busy() const { return job_ != Job::None || generator_.moving() || waiting_for_limit_release_; }
  bool external_job() const { return job_ == Job::External; }
  void start_external(const RampSpec& ramp, int direction, std::optional<int64_t> steps, Tick now);
  void external_velocity(Tick now, int64_t level, std::optional<RampSpec> then = std::nullopt) {
    generator_.change_velocity(now, level, std::move(then));
  }
  void external_regrid(Tick now, const RampSpec& ramp) { generator_.regrid(now, ramp); }
  void external_stop(Tick now) { generator_.stop(now); }
  void external_halt(Tick now);  // no ramp, no end report: the front end knows why
  const StepGenerator& generator() const { return generator_; }
  // Every step of an external job, after the motor took it (the front end may halt here).
  std::function<void(const Step&)> on_external_step;
  // The external job ended by itself (Completed) or by the e-stop or a Horner stop.
  std::function<void(ExternalEnd, Tick)> on_external_end;
  // Set by the front end: how an external job's step leaves the outputs (PULSE SD|SS).
  std::function<OutputPulse(const Step&)> external_pulse;
  // Every step of any job (the HP quadrature index and first-step time watch them).
  std::function<void(const Step&)> on_any_step;

 private:
  enum class Job { None, Jog, Move, Home, External };
  enum class HomeStage { Seek, BackToOrigin, Clear, Approach };

  MotorPort& motor() { return *motors_[selected_]; }
  const MotorPort& motor() const { return *motors_[selected_]; }
  bool origin_active() const;
  void execute(uint16_t command_bit, Tick now);
  void latch(uint16_t error_bits, Tick now);
  void notify(AxisEvent::Kind kind, uint16_t error_bits = 0);
  std::optional<RampSpec> ramp_from_words(Tick now, bool index_decel = false);
  void start_move(int64_t distance, const RampSpec& ramp, Tick now, bool indexed, bool resume = false);
  void start_motion(const RampSpec& ramp, int direction, std::optional<int64_t> distance, Tick now);
  void start_base_run(int direction, Tick now);
  void on_step(const Step& step);
  void after_step(const Step& step);
  void finish(Tick now);
  void end_external(ExternalEnd how, Tick now);
  void home_event(Tick now, bool at_limit = false);
  void check_position_valid();
  void check_stall(const Step& step);
  void select(unsigned motor, Tick now);

  AxisConfig config_;
  std::vector<MotorPort*> motors_;
  const bool* estop_;
  CommandWords words_;
  StepGenerator generator_;
  uint16_t previous_commands_ = 0;
  uint16_t commands_ = 0;
  uint16_t errors_ = 0;
  bool position_valid_ = false;
  bool resumable_ = false;
  bool dir_high_ = false;
  unsigned selected_ = 0;
  int32_t motor_position_ = 0;
  int64_t encoder_offset_ = 0;  // encoder position = offset + counts * mlt / div
  uint16_t last_status_ = 0;

  // The job in progress.
  Job job_ = Job::None;
  int job_direction_ = +1;
  int64_t move_target_steps_ = 0;  // rel/abs/indexed: steps of the whole move
  int64_t move_done_steps_ = 0;
  RampSpec move_ramp_;
  bool move_indexed_ = false, move_repeatable_ = false, index_taken_ = false;
  // The indexed move's own words, taken with the command (SPM30 3.4: the words may change for
  // the next move once a command started), and the index input's level after the last step
  // (an index counts when it becomes active inside the window, C1.3.4 / STP100 5.3.5).
  uint32_t index_destination_ = 0, index_window_open_ = 0, index_window_close_ = 0;
  RampSpec index_ramp_;
  bool index_was_active_ = false;
  bool waiting_for_limit_release_ = false;
  int64_t repeat_distance_ = 0;
  HomeStage home_stage_ = HomeStage::Seek;
  std::optional<Tick> origin_inactive_since_;
  bool origin_seen_inactive_ = false;
  // Stall detection window.
  int64_t stall_window_steps_ = 0;
  int64_t stall_window_encoder_start_ = 0;

  // Per-motor memory for SPM30 axis selection (3.2 SELECT AXIS).
  struct Saved {
    int32_t position = 0;
    bool valid = false;
    bool at_home = false;
  };
  std::vector<Saved> saved_;
};

}  // namespace stepnode::motion
