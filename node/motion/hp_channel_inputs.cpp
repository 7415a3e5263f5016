// hp::Channel: its inputs: the HALT switch, the HARDLIM limit switches and the quadrature
// counter with QINDEX (3-17, 3-20..3-22).
#include "node/motion/hp_channel.hpp"

namespace stepnode::motion::hp {

void Channel::input_changed(unsigned motor, const InputEdge& edge) {
  if (motor != core_.selected()) return;
  if (edge.input == Input::Halt) return halt_input_changed(edge.time);
  // QINDEX ONCE: counting begins on the leading edge of the first index pulse (3-21).
  if (edge.input == Input::Marker && edge.active && q_waiting_for_index_) {
    q_offset_ = core_.motor().encoder_count();
    q_waiting_for_index_ = q_frozen_ = false;
  }
}

// ---------------------------------------------------------------- inputs

bool Channel::halt_active() const {
  switch (halt_mode_) {
    // The level as the core applied the HALT input's edges (HIGH: open, pulled up).
    case HaltMode::Lo: return !core_.inputs().halt_high();
    case HaltMode::Hi: return core_.inputs().halt_high();
    case HaltMode::Off: return false;
  }
  return false;
}

bool Channel::limit_active(int direction) const {
  // The simulated limit switches close to PCOM when reached (Figure 3-4): the input is LO
  // there, HI (pulled up) elsewhere. HARDLIM sets which level means "limit reached"; only
  // motion toward a reached limit is prohibited (Command Summary: HARDLIM).
  if (direction > 0) return (!core_.inputs().upper_limit()) == plim_high_;
  return (!core_.inputs().lower_limit()) == nlim_high_;
}

void Channel::halt_input_changed(Tick now) {
  if (halt_active() && (run_ != Run::Idle || start_at_)) {
    core_.halt(*this, now);
    end(Done::Halted, intr::kHaltSwitch, now);
  }
}

// ---------------------------------------------------------------- quadrature counter

void Channel::qindex(QIndexMode mode) {
  switch (mode) {
    case QIndexMode::Off:
      // "Indexing can be turned off with the OFF option" (3-21): the counter counts, as at
      // power-on. Turned off before ONCE's index pulse, it holds what it counted since
      // ONCE's reset, nothing, and counts from now: the encoder's counts while it waited
      // were never counted.
      if (q_frozen_) q_offset_ = core_.motor().encoder_count();
      q_waiting_for_index_ = false;
      q_frozen_ = false;
      break;
    case QIndexMode::Once:
      // Reset now; counting begins on the first index pulse, later ones are ignored.
      q_offset_ = core_.motor().encoder_count();
      q_frozen_ = q_waiting_for_index_ = true;
      break;
    case QIndexMode::Sgl:
      // Reset now and count at once; QINDEX then returns to OFF.
      q_offset_ = core_.motor().encoder_count();
      q_frozen_ = q_waiting_for_index_ = false;
      mode = QIndexMode::Off;
      break;
  }
  // QINDEX ONCE waits for the index's leading edge (input_changed), whoever moves the axis.
  qindex_ = mode;
}

int32_t Channel::quadrature_count() const {
  if (q_frozen_) return 0;
  // "will rollover from the maximum positive number to the maximum negative number"
  return static_cast<int32_t>(static_cast<uint32_t>(core_.motor().encoder_count() - q_offset_));
}

}  // namespace stepnode::motion::hp
