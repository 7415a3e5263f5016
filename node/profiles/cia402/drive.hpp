// One CiA 402 axis as a front end of the motion core (node/motion/axis_core.hpp): the power
// drive system state machine (drive_state.hpp) gates the motion; the profile position (PP)
// and profile velocity (PV) modes run on the engine's exact step times (CiA 402-2 / IEC
// 61800-7-201 "Profile position mode", "Profile velocity mode"). Everything is in the
// drive's internal units: steps, steps/s, steps/s^2 (the profile's service converts the
// user units of 608Fh/6091h/6092h). Pure and deterministic: time comes in as ticks.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>

#include "node/motion/axis_core.hpp"
#include "node/profiles/cia402/drive_state.hpp"
#include "node/profiles/cia402/homing.hpp"

namespace stepnode::cia402 {

// Modes of operation (6060h / 6061h).
enum class Mode : int8_t {
  None = 0,
  ProfilePosition = 1,
  ProfileVelocity = 3,
  Homing = 6,
  InterpolatedPosition = 7,
  CyclicSyncPosition = 8,
  CyclicSyncVelocity = 9,
};

// The modes this drive runs today; 6060h refuses the others.
constexpr bool runs(Mode m) {
  return m == Mode::ProfilePosition || m == Mode::ProfileVelocity || m == Mode::Homing ||
         m == Mode::InterpolatedPosition || m == Mode::CyclicSyncPosition ||
         m == Mode::CyclicSyncVelocity;
}
constexpr bool cyclic(Mode m) {
  return m == Mode::InterpolatedPosition || m == Mode::CyclicSyncPosition ||
         m == Mode::CyclicSyncVelocity;
}

// Controlword bits 4..9, mode-specific (CiA 402-2 "Profile position mode": 6040h bits).
namespace cw_pp {
constexpr uint16_t kNewSetPoint = 1u << 4;
constexpr uint16_t kChangeSetImmediately = 1u << 5;
constexpr uint16_t kRelative = 1u << 6;
constexpr uint16_t kChangeOnSetPoint = 1u << 9;
}  // namespace cw_pp
// Statusword bits 12, 13 of the modes (6041h).
namespace sw_mode {
constexpr uint16_t kSetPointAcknowledge = 1u << 12;  // PP
constexpr uint16_t kFollowingError = 1u << 13;       // PP
constexpr uint16_t kSpeedZero = 1u << 12;            // PV
constexpr uint16_t kHomingAttained = 1u << 12;       // HM
constexpr uint16_t kHomingError = 1u << 13;          // HM
constexpr uint16_t kDriveFollows = 1u << 12;         // CSP, CSV: the command value is followed
constexpr uint16_t kIpModeActive = 1u << 12;         // IP
}  // namespace sw_mode
// 6086h motion profile types this drive runs: 0 linear ramp (trapezoid), 3 jerk-limited ramp.
constexpr int16_t kLinearRamp = 0, kJerkLimitedRamp = 3;
// Controlword bit 4 in interpolated position mode: enable interpolation (CiA 402-2).
constexpr uint16_t kEnableIp = 1u << 4;
// Controlword bit 4 in homing mode: the rising edge starts the homing (CiA 402-2).
constexpr uint16_t kHomingOperationStart = 1u << 4;

// The profile (6067h..6085h, 607Dh) in steps, steps/s and steps/s^2.
struct Parameters {
  uint32_t max_velocity = 100'000;            // 607Fh
  uint32_t profile_velocity = 1'000;          // 6081h
  uint32_t acceleration = 10'000;             // 6083h
  uint32_t deceleration = 10'000;             // 6084h
  uint32_t quick_stop_deceleration = 50'000;  // 6085h
  int16_t motion_profile_type = 0;            // 6086h: 0 trapezoid, 3 jerk-limited (PP, PV)
  // 60A4h:1..4 in steps/s^3: begin acceleration, begin deceleration, end acceleration, end
  // deceleration jerk (0: not limited).
  uint32_t jerk[4] = {10'000, 10'000, 10'000, 10'000};
  uint32_t position_window = 0;            // 6067h: |target - actual| <= window
  uint16_t position_window_time_ms = 0;    // 6068h
  int32_t min_position_limit = INT32_MIN;  // 607Dh:1
  int32_t max_position_limit = INT32_MAX;  // 607Dh:2
  int8_t homing_method = 0;                // 6098h
  uint32_t homing_switch_speed = 1'000;    // 6099h:1
  uint32_t homing_zero_speed = 100;        // 6099h:2
  uint32_t homing_acceleration = 1'000;    // 609Ah
  int32_t home_offset = 0;                 // 607Ch: the position of the home position
  motion::Tick interpolation_period = motion::kClockHz / 1000;  // 60C2h, until SYNCs are seen
  uint32_t following_error_window = UINT32_MAX;                 // 6065h (UINT32_MAX: off)
  uint16_t following_error_timeout_ms = 0;                      // 6066h
};

class Drive final : public motion::FrontEnd, public motion::AxisListener {
 public:
  explicit Drive(motion::AxisCore& core);
  Drive(const Drive&) = delete;
  Drive& operator=(const Drive&) = delete;

  // Power-up / NMT reset node: transitions 0 and 1, no set-point, mode as configured.
  void power_up(motion::Tick now, Mode mode);

  // ---- what the master writes
  void controlword(uint16_t cw, motion::Tick now);                       // 6040h
  void set_mode(Mode mode, motion::Tick now);                            // 6060h (runs(mode) only)
  void set_target_position(int32_t steps) { target_position_ = steps; }  // 607Ah
  void set_target_velocity(int32_t steps_per_s, motion::Tick now);       // 60FFh
  // 60B0h position offset, added to 607Ah in CSP; 60B1h velocity offset, added to 60FFh in
  // CSV (CiA 402-2). In CSP 60B1h would be a velocity feed-forward: this drive (linear
  // interpolation of the set-points, open loop) has none, so it is not used there.
  void set_position_offset(int32_t steps) { position_offset_ = steps; }
  void set_velocity_offset(int32_t steps_per_s) { velocity_offset_ = steps_per_s; }
  Parameters& parameters() { return parameters_; }
  void set_options(const Options& options) { machine_.set_options(options); }

  // ---- the drive's events
  // A fault (603Fh code): transition 13 and the 605Eh reaction.
  void fault(uint16_t error_code, motion::Tick now);
  // The master was lost: the 6007h reaction. While it is (a fault's cause persists, CiA
  // 402-2 transition 15), a fault reset is refused; connection_restored() ends that.
  void connection_lost(int16_t option_6007, motion::Tick now);
  void connection_restored() { connection_lost_ = false; }
  // Time passes: the position window time (6068h) runs out between steps.
  void advance(motion::Tick now);
  // The earliest tick after `now` (the latest advance) at which advance() changes what the
  // master sees without a step or a frame (issue 13): the position window time (6068h)
  // running out, the following error (CSP, IP) leaving its window 6065h (computed from the
  // segment, drive_following_error.cpp) or its time-out (6066h) running out. The motion's
  // steps and its end are the core's. Nothing: no timed work.
  std::optional<motion::Tick> next_event(motion::Tick now) const;
  // A SYNC that arrived on the bus at `arrival` and is handled at `now` (CSP, CSV, IP: the
  // set-point written for this cycle takes effect; drive_cyclic.cpp).
  void sync(motion::Tick now, motion::Tick arrival);
  void set_ip_set_point(int32_t steps) { ip_set_point_ = steps; }  // 60C1h:1

  // ---- what the master reads
  uint16_t statusword() const;                         // 6041h
  Mode mode_display() const { return mode_display_; }  // 6061h
  Mode mode() const { return mode_; }                  // the mode 6060h asked for
  State state() const { return machine_.state(); }
  uint16_t error_code() const { return machine_.error_code(); }  // 603Fh
  int32_t position_demand() const { return demand_; }            // 6062h: where the trajectory is
  int32_t position_actual() const { return core_.position(); }   // 6063h/6064h (open loop)
  int32_t velocity_actual() const;                               // 606Ch, steps/s signed
  uint32_t digital_inputs() const;                               // 60FDh
  int32_t following_error() const { return following_error_value_; }  // 60F4h
  const DriveStateMachine& machine() const { return machine_; }

  // The statusword changed (an event-driven TPDO goes out).
  std::function<void()> on_status_changed;

  // FrontEnd: this drive's jobs.
  Hooks hooks() const override;
  void after_step(const motion::Step& step) override;
  void motion_ended(motion::Tick when) override;
  void aborted(motion::Tick when) override;
  // AxisListener: the status follows every job on the axis; the e-stop is a fault (9000h).
  void emergency_stop(motion::Tick when, bool was_moving) override;
  void advanced(motion::Tick now) override;
  void job_halted(const motion::FrontEnd& owner, motion::Tick when) override;

 private:
  struct SetPoint {
    int64_t target = 0;     // absolute, steps, inside the software limits
    uint32_t velocity = 0;  // 6081h when it was taken (bit 12)
    // Change on set-point (bit 9 with bit 5 = 0): the motion to the running set-point's
    // target runs on through it to this one.
    bool through = false;
  };
  void carry_out(Stop stop, motion::Tick now);
  void stopped(motion::Tick now);
  void new_set_point(uint16_t cw, motion::Tick now);
  void start_positioning(const SetPoint& sp, motion::Tick now);
  void run_on_to_next(motion::Tick now);
  void pass_first_target(motion::Tick at);
  void stop_at_limit(motion::Tick at);  // a limit in the direction of travel (8612h)
  int64_t level_of(uint32_t velocity) const;
  void velocity_to(int64_t target, motion::Tick now);
  void halt(bool on, motion::Tick now);
  void resume_after_halt(motion::Tick now);
  void start_homing(motion::Tick now);
  void interrupt_homing(motion::Tick now);
  void run_search(motion::Tick now);
  void homing_step(const motion::Step& step);
  void homing_done(bool ok, motion::Tick now);
  bool block_detected(const motion::Step& step);
  HomingInputs homing_inputs() const;
  void cyclic_position(int64_t target, motion::Tick now);
  void cyclic_velocity(int64_t velocity, motion::Tick now);
  // Before a stop ramp (6084h or 6085h) of a cyclic job: the job carried over to a profile
  // ramp it can ramp down on (drive_cyclic.cpp); any other job is left as it is.
  void ramp_from_cyclic(motion::Tick now);
  // A stop ramp of the drive's own: 6085h (quick stop ramp) or 6084h.
  void ramp_down(bool quick, motion::Tick now);
  void measure_cycle(motion::Tick arrival);
  // CSP or IP in operation enabled, on the master's set-points (not on a stop ramp of the
  // drive's own): 60F4h is the demand minus the actual position.
  bool following_position() const;
  // ... and 6065h is set: the error is watched.
  bool following_error_watched() const;
  // The first tick after `after` at which 60F4h leaves 6065h, the segment's steps taken at
  // their ticks; nothing if it does not within the segment (or is not watched).
  std::optional<motion::Tick> following_error_exit(motion::Tick after) const;
  // 60F4h at an advance `at`: since when it is outside the window, or back in.
  void track_following_error(motion::Tick at);
  // ... and at an advance, the fault once it has been outside for 6066h.
  void check_following_error(motion::Tick now);
  int64_t cyclic_demand(motion::Tick now) const;
  // 607Dh in PV and CSV, and on the cyclic modes' stop ramps (drive_limits.cpp): the limit
  // in `direction` while the limits are in effect; whether the quick stop is jerk-limited;
  // the most steps a 6085h stop from `v` steps/s takes (`accelerating`: begun in a ramp up);
  // the highest velocity a ramp from `from` to `to` reaches before it must turn to stop
  // before the limit; the step at which a motion from `from` at up to `v` begins its stop.
  std::optional<int64_t> limit_ahead(int direction) const;
  bool jerk_limited_stop() const;
  double stop_steps(double v, bool accelerating) const;
  double reachable(int direction, double from, double to) const;
  std::optional<int64_t> brake_point(int direction, double from, double v) const;
  bool room_to_stop(int direction, double from, double v) const;
  // The running motion, toward `direction` from `from` at up to `v`: its brake point as the
  // step rule (or the stop now, if it is there already).
  void watch_limit(int direction, double from, double v, motion::Tick now);
  void brake_for_limit(int direction, motion::Tick at);
  void at_limit_rule(motion::Tick at);
  motion::RampSpec ramp(uint32_t velocity) const;
  motion::Rational quick_stop_slope() const;
  int64_t clamp_to_limits(int64_t target);
  void notify();

  motion::AxisCore& core_;
  DriveStateMachine machine_;
  Parameters parameters_;
  Mode mode_ = Mode::ProfilePosition;
  Mode mode_display_ = Mode::ProfilePosition;
  uint16_t controlword_ = 0;
  int32_t target_position_ = 0;
  int32_t target_velocity_ = 0;
  int32_t position_offset_ = 0;  // 60B0h
  int32_t velocity_offset_ = 0;  // 60B1h
  int64_t grid_ = 1;             // levels per step/s of the running motion

  // PP: the set-point being carried out, the buffered next one (bit 5 = 0), and the
  // handshake (bit 4 edge -> bit 12 until bit 4 is taken back).
  std::optional<SetPoint> active_, next_;
  std::optional<int64_t> last_target_;  // the preceding target (relative set-points)
  bool restart_after_stop_ = false;     // change set immediately: stop, then go to active_
  bool acknowledged_ = false;
  bool internal_limit_ = false;
  std::optional<motion::Tick> in_window_since_;
  bool target_reached_ = true;
  // A stop ramp the state machine waits for (quick stop, 605Ch/605Bh, fault reaction).
  bool stopping_for_machine_ = false;
  bool halted_ = false;
  bool connection_lost_ = false;
  // PV: a reversal runs as a stop, then a start the other way.
  std::optional<int64_t> velocity_after_stop_;
  uint16_t last_status_ = 0;
  // 607Dh in the velocity modes: the step rule of the running motion (its brake point, then
  // the limit once it brakes), the direction it watches.
  std::optional<int32_t> limit_rule_;
  int limit_direction_ = 0;
  bool limit_braking_ = false;

  // HM: the searches of the method being performed and where it is.
  enum class Homing : uint8_t { Idle, InProgress, Attained, Error };
  Homing homing_ = Homing::Idle;  // Idle: not started, or interrupted
  std::vector<HomingSearch> searches_;
  size_t search_ = 0;
  bool search_stopping_ = false;  // a Stop search's ramp runs; the next begins at its end
  HomingInputs last_inputs_;
  // A search for a hard stop (HomingEvent::Block): the encoder count when it last moved in
  // the direction of travel, the steps given since, and since when they exceed 6065h.
  int64_t block_count_ = 0;
  uint32_t block_steps_ = 0;
  std::optional<motion::Tick> block_since_;

  // CSP / IP: the running segment, from seg_from_ at seg_start_ to seg_to_ in seg_ticks_
  // (linear interpolation, one cycle behind the master's set-points); CSV: a constant
  // velocity on a grid of its own (csv_running_). The cycle is measured from the SYNCs.
  std::optional<motion::Tick> last_sync_;
  motion::Tick cycle_ = 0;
  motion::Tick odd_interval_ = 0;  // intervals that do not fit the cycle (a new period?)
  int odd_intervals_ = 0;
  int64_t seg_from_ = 0, seg_to_ = 0;
  motion::Tick seg_start_ = 0, seg_ticks_ = 1;
  int64_t seg_steps_ = 0;  // the steps the segment's job gives (fewer than d: it lags)
  bool csv_running_ = false;
  // The drive's own stop ramp replaced the cyclic trajectory: 6062h is the steps given and
  // 60F4h is 0 until a SYNC starts a segment again.
  bool own_ramp_ = false;
  int32_t ip_set_point_ = 0;
  int32_t following_error_value_ = 0;
  int32_t demand_ = 0;
  std::optional<motion::Tick> following_error_since_;
  motion::Tick following_error_checked_ = 0;  // the last tick 60F4h was looked at
  bool following_error_ = false;
};

}  // namespace stepnode::cia402
