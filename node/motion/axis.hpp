// The Horner front end of one axis: every command bit and status bit of the module with its
// rules (SPM30 chapters 3-5, STP100 chapters 4-6, STP113 appendix C), driving the axis'
// motion core (node/motion/axis_core.hpp) and reporting every job's motion in its status
// bits, whichever front end runs it. Pure and deterministic: time comes in as ticks.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "node/motion/axis_core.hpp"
#include "node/motion/axis_registers.hpp"
#include "node/motion/encoder_kind.hpp"
#include "node/motion/motor_port.hpp"
#include "node/motion/step_generator.hpp"

namespace stepnode::motion {

// Where the two manuals differ, the module model chooses (the default is the SPM30); the
// STP100's own options are settings.
struct AxisConfig {
  // SPM30: stall detection on whenever the tolerance is non-zero (5.4), %I9 off when the
  // difference reaches the tolerance (5.4), QUAD homes on the marker qualified by the end
  // limit (4 FIND HOME). STP100: stall detection is its own checkbox (6.3.3), %I9 off when
  // the difference exceeds the tolerance (6.3.2), origin source and limit qualification
  // are options (3.2.3).
  enum class Module { Spm30, Stp100 };
  enum class HomeMethod { Normal, Simple };        // STP113 C1.2.1 / STP100 3.2.3
  enum class OriginSource { HomeSwitch, Marker };  // STP100 3.2.3 (SPM30: marker = QUAD)
  Module module = Module::Spm30;
  HomeMethod home_method = HomeMethod::Normal;
  OriginSource origin_source = OriginSource::HomeSwitch;
  bool limit_qualified_home = false;  // STP100 3.2.3; SPM30 does this with encoder QUAD
  EncoderKind encoder = EncoderKind::None;
  int64_t encoder_multiplier = 1;  // 1..255
  int64_t encoder_divisor = 1;     // 1..16
  int64_t encoder_tolerance = 0;   // 0..255, 0 = no position validation
  // Quadrature counts per encoder line: 1 as the ratio tables count a 1000-line encoder
  // (SPM30 5.3, STP100 Table 6.1), or 2 / 4 ("doubled or quadrupled", SPM30 5.1, STP100 6.2.1).
  int64_t quadrature_decoding = 1;
  bool stall_detection = false;      // STP100 6.3.3 "Enable Stall Detection" (STP100 model only)
  bool indexed_moves = true;         // %Q11 is Move Indexed (STP113, STP100)
  bool limit_started_moves = false;  // STP100 5.3.4: a move toward an active limit waits
  // A move too short for the running velocity cruises at STPCALC's peak (B1.3.6) instead of
  // turning at halfway (SPM30 3.4.5): STPCALC's figures rather than the module's motion.
  bool stpcalc_peak_short_moves = false;
  // Direction output setup time (SPM30 and STP100 specifications: 2 ms): the first step
  // after DIR changed comes at least this long after it. 0 = none.
  int64_t direction_setup_us = 2000;
};

// What the axis reports as it happens (status changes go out on the bus at once).
struct AxisEvent {
  enum Kind { StatusChanged, Error, MoveDone } kind;
  uint16_t status;
  uint16_t error_bits;  // for Error: the bits that just latched
};

class Axis final : public FrontEnd, public AxisListener {
 public:
  // On a motion core shared with other front ends (the device's axes).
  Axis(AxisConfig config, AxisCore& core);
  // On a core of its own: `motors` (one, or three for an SPM30 multiplexed axis; their
  // inputs include the e-stop).
  Axis(AxisConfig config, const std::vector<MotorPort*>& motors);
  Axis(const Axis&) = delete;
  Axis& operator=(const Axis&) = delete;

  AxisCore& core() { return core_; }
  const AxisCore& core() const { return core_; }

  // Power-up or watchdog reset (also NMT reset node): everything off, %I8 on. The core is
  // powered up by its owner (or here, for an axis with a core of its own).
  void power_up(Tick now);
  // The command bits as the master last wrote them; edges act at once (after advancing
  // the axis to `now`).
  void write_commands(uint16_t bits, Tick now);
  CommandWords& words() { return words_; }
  const CommandWords& words() const { return words_; }

  // Takes every step due up to `now` and reacts to the inputs they change.
  void advance_to(Tick now) { core_.advance_to(now); }
  // The master was lost (heartbeat consumer timeout): decelerate and latch %I8.
  void master_lost(Tick now);

  uint16_t status() const;
  int32_t motor_position() const { return core_.position(); }
  int32_t encoder_position() const;
  double velocity() const { return core_.generator().velocity(); }
  MotionPhase phase() const { return core_.generator().phase(); }
  bool dir_output_high() const { return core_.dir_output_high(); }  // DIR+ level (STP100 5.3.5)
  unsigned selected_motor() const { return core_.selected(); }
  std::optional<Tick> next_step_time() { return core_.next_step_time(); }

  const AxisConfig& config() const { return config_; }
  void set_config(const AxisConfig& config);
  std::function<void(const AxisEvent&)> on_event;

  // FrontEnd: the Horner jobs' rules.
  Hooks hooks() const override;
  void poll(Tick now) override;
  std::optional<Tick> deadline() const override;
  void at_deadline(Tick when) override;
  void before_step() override;
  void after_step(const Step& step) override;
  void motion_ended(Tick when) override { finish(when); }
  void aborted(Tick when) override;
  // AxisListener: every job's motion shows in the status bits (and latches %I1).
  void step_taken(const Step& step) override;
  void job_started(const FrontEnd& owner, Tick when) override;
  void job_halted(const FrontEnd& owner, Tick when) override;
  void emergency_stop(Tick when, bool was_moving) override;
  void advanced(Tick now) override;

 private:
  enum class Job { None, Jog, Move, Home };
  enum class HomeStage { Seek, BackToOrigin, Clear, Approach };

  // The selected motor's inputs, as the core applied its edges.
  const InputLevels& inputs() const { return core_.inputs(); }
  bool origin_active() const;
  // The rules the module model and the settings give (set_config).
  struct Rules {
    bool stall_detection = false;      // SPM30 5.4 / STP100 6.3.3
    bool invalid_at_tolerance = true;  // SPM30 5.4 "reaches"; STP100 6.3.2 "exceeds"
    bool marker_origin = false;        // STP100 3.2.3 option; SPM30 QUAD on axis 1
    bool limit_qualified = false;      // STP100 3.2.3 option; SPM30 QUAD on axis 1
  };
  static Rules rules_of(const AxisConfig& config);
  // Axis 1's encoder counts as the module decodes them (the motor port gives edges).
  int64_t encoder_counts() const;
  bool limit_qualified_home() const { return rules_.limit_qualified && core_.selected() == 0; }
  void execute(uint16_t command_bit, Tick now);
  // The commands (SPM30 section 4), one each; FIND HOME is node/motion/axis_homing.cpp.
  void immediate_stop(Tick now);
  void decelerate_and_stop(Tick now);
  void set_current_position(Tick now);
  void find_home(int direction, Tick now);
  void jog(int direction, Tick now);
  void move(uint16_t command_bit, Tick now);
  void resume_move(Tick now);
  // Whether the move a Decelerate and Stop ends is resumable: a Move Relative or Move Absolute
  // "unless an error occurred" (SPM30 4 DECELERATE AND STOP, STP100 5.3.9); Move Indexed's
  // "Status Bits Affected" have no %I10 (STP100 5.3.5), and Resume Move resumes "a previously
  // pre-empted Relative Move or Absolute Move" (5.3.7).
  bool preempted_move_resumable() const { return !errors_ && !move_indexed_; }
  void latch(uint16_t error_bits, Tick now);
  void latched(uint16_t error_bits, bool was_moving, Tick when);
  void notify(AxisEvent::Kind kind, uint16_t error_bits = 0);
  std::optional<RampSpec> ramp_from_words(Tick now, bool index_decel = false);
  void start_move(int64_t distance, const RampSpec& ramp, Tick now, bool indexed,
                  bool resume = false);
  // Positions are those the status words carry (SPM30 3.3): whether a move of `distance`
  // steps from here, and an indexed one's end after any index its window accepts, ends
  // inside them; whether the index words are inside the module model's ranges.
  bool ends_in_range(int64_t distance, bool indexed) const;
  bool index_words_legal() const;
  bool start_motion(const RampSpec& ramp, int direction, std::optional<int64_t> distance, Tick now);
  void start_base_run(int direction, Tick now);
  void finish(Tick now);
  void end_job(Tick when);
  bool moving() const { return core_.moving() || waiting_for_limit_release_; }
  void home_event(Tick now, bool at_limit = false);
  void check_position_valid();
  void check_stall(const Step& step);
  // Whether the encoder's rules look at every step: position validation (STP100 6.3.2)
  // or stall detection (6.3.3), both of axis 1's encoder.
  bool encoder_rules_every_step() const;
  void select(unsigned index, Tick now);

  AxisConfig config_;
  std::unique_ptr<AxisCore> own_core_;  // only for an axis on a core of its own
  AxisCore& core_;
  CommandWords words_;
  uint16_t previous_commands_ = 0;
  uint16_t commands_ = 0;
  uint16_t errors_ = 0;
  bool position_valid_ = false;
  bool resumable_ = false;
  int64_t encoder_offset_ = 0;  // encoder position = offset + counts * mlt / div
  uint16_t last_status_ = 0;

  // The job in progress.
  Job job_ = Job::None;
  int job_direction_ = +1;
  int64_t move_target_steps_ = 0;  // rel/abs/indexed: steps of the whole move
  // The steps the move took: those of its earlier motions (a resume starts a new one) here,
  // and, while `move_stepping_`, the running motion's as the generator counts them (no
  // count of its own at every step). Settled into move_done_steps_ when the job ends.
  int64_t move_done_steps_ = 0;
  bool move_stepping_ = false;
  int64_t move_done_steps() const {
    return move_done_steps_ + (move_stepping_ ? core_.generator().steps_done() : 0);
  }
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
  // A jog far from the bound of the positions runs without an end (no distance to count
  // per step); at this position, closer to the bound than its ramp down, it is given its
  // end on the bound (after_step).
  std::optional<int32_t> jog_end_from_;
  HomeStage home_stage_ = HomeStage::Seek;
  std::optional<Tick> origin_inactive_since_;
  bool origin_seen_inactive_ = false;
  Rules rules_;
  // Stall detection (STP100 6.3.3): over a short window a jam shows at once, over a long
  // one a slipping motor is measured to within 0.1 % of the 10 % threshold.
  struct StallWindow {
    int64_t steps = 0;         // commanded steps since the window began
    int64_t counts_start = 0;  // encoder counts when it began
  };
  StallWindow stall_short_, stall_long_;
  int stall_direction_ = 0;
  void restart_stall_windows(int direction);
  bool stall_judged(const StallWindow& window, int64_t counts) const;
  bool stalled_over(StallWindow& window, int64_t counts_per_window);
  // Whether the motion that just ended stalled over its partly filled windows (then new ones).
  bool stalled_at_motion_end();

  // Per-motor memory for SPM30 axis selection (3.2 SELECT AXIS).
  struct Saved {
    int32_t position = 0;
    bool valid = false;
    bool at_home = false;
  };
  std::vector<Saved> saved_;
};

}  // namespace stepnode::motion
