#include "node/profiles/sim/service.hpp"

#include "node/profiles/sim/objects.hpp"

namespace stepnode::node {

namespace sim_obj = sim::obj;

SimService::SimService(od::Dictionary& dictionary, AxisBank& axes)
    : dictionary_(dictionary), axes_(axes) {
  install_hooks();
}

void SimService::configure(uint64_t) {
  for (unsigned m = 0; m < machine().axes.size(); ++m) load_machine(m);
}

void SimService::publish() {
  for (unsigned m = 0; m < machine().axes.size(); ++m) publish_motor(m);
}

void SimService::load_machine(unsigned motor) {
  uint16_t sw = sim_obj::index(motor, sim_obj::kSwitches),
           enc = sim_obj::index(motor, sim_obj::kEncoder),
           f = sim_obj::index(motor, sim_obj::kFaults);
  auto i32 = [&](uint16_t i, uint8_t s) { return int64_t{dictionary_.get<int32_t>(i, s)}; };
  auto on = [&](uint16_t i, uint8_t s) { return dictionary_.get<uint8_t>(i, s) != 0; };
  sim::AxisMachineConfig& m = machine().axes[motor].config();
  using namespace sim;
  int64_t home_width = i32(sw, switches_sub::kHomeWidth);
  m.home = home_width > 0
               ? std::optional<sim::Cam>(sim::Cam{i32(sw, switches_sub::kHomePosition), home_width})
               : std::nullopt;
  int64_t index_width = i32(sw, switches_sub::kIndexWidth);
  m.index =
      index_width > 0
          ? std::optional<sim::Cam>(sim::Cam{i32(sw, switches_sub::kIndexPosition), index_width})
          : std::nullopt;
  m.lower_limit = on(sw, switches_sub::kLowerLimitEnabled)
                      ? std::optional<int64_t>(i32(sw, switches_sub::kLowerLimit))
                      : std::nullopt;
  m.upper_limit = on(sw, switches_sub::kUpperLimitEnabled)
                      ? std::optional<int64_t>(i32(sw, switches_sub::kUpperLimit))
                      : std::nullopt;
  m.steps_per_rev = i32(enc, encoder_sub::kStepsPerRev);
  m.encoder_lines = i32(enc, encoder_sub::kLines);
  m.marker_offset = i32(enc, encoder_sub::kMarkerOffset);
  m.marker_width = i32(enc, encoder_sub::kMarkerWidth);
  m.stall_below = on(f, faults_sub::kStallBelowEnabled)
                      ? std::optional<int64_t>(i32(f, faults_sub::kStallBelow))
                      : std::nullopt;
  m.stall_above = on(f, faults_sub::kStallAboveEnabled)
                      ? std::optional<int64_t>(i32(f, faults_sub::kStallAbove))
                      : std::nullopt;
  m.miss_every = dictionary_.get<uint32_t>(f, faults_sub::kMissEvery);
  m.move_every = dictionary_.get<uint32_t>(f, faults_sub::kMoveEvery);
}

void SimService::install_hooks() {
  for (unsigned m = 0; m < machine().axes.size(); ++m) {
    for (uint16_t obj : {sim_obj::kSwitches, sim_obj::kEncoder, sim_obj::kFaults})
      for (auto& [sub, e] : dictionary_.object(sim_obj::index(m, obj))->entries)
        if (sub)
          od::listen(e, [this, m] {
            load_machine(m);
            axes_.advance(axes_.now_us());  // an input may have changed under a moving axis
          });
    od::listen(dictionary_.at(sim_obj::index(m, sim_obj::kFaults), sim::faults_sub::kDisplace),
               [this, m] {
                 machine().axes[m].displace(dictionary_.get<int32_t>(
                     sim_obj::index(m, sim_obj::kFaults), sim::faults_sub::kDisplace));
                 axes_.advance(axes_.now_us());
               });
  }
  od::listen(dictionary_.at(sim_obj::kEmergencyStop, 0), [this] {
    machine().set_emergency_stop(dictionary_.get<uint8_t>(sim_obj::kEmergencyStop, 0) != 0);
    axes_.advance(axes_.now_us());
  });
}

void SimService::publish_motor(unsigned motor) {
  const sim::AxisMachine& m = machine().axes[motor];
  dictionary_.put<int32_t>(sim_obj::index(motor, sim_obj::kMechanicalPosition), 0,
                           static_cast<int32_t>(m.position()));
  uint8_t inputs = (m.home() ? 1 : 0) | (m.lower_limit() ? 2 : 0) | (m.upper_limit() ? 4 : 0) |
                   (m.index() ? 8 : 0) | (m.marker() ? 16 : 0);
  dictionary_.put<uint8_t>(sim_obj::index(motor, sim_obj::kInputs), 0, inputs);
}

}  // namespace stepnode::node
