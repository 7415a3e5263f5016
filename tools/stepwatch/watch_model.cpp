#include "tools/stepwatch/watch_model.hpp"

#include <fmt/format.h>

#include "bridge/dds/convert.hpp"

namespace stepnode::stepwatch {
namespace {

uint16_t key(uint8_t node, uint8_t axis) { return static_cast<uint16_t>(node << 8 | axis); }

std::string csv_quote(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + '"';
}

// Columns: recv_time_ns,topic,node,axis,status_bits,motor_position,encoder_position,
//          velocity,motion_phase,sync_counter,state,code,text,can_time_ns,publish_time_ns
struct Row {
  Row(uint64_t recv_time, std::string topic_name) : recv(recv_time), topic(std::move(topic_name)) {}
  uint64_t recv = 0;
  std::string topic;
  std::string node, axis, status_bits, motor, encoder, velocity, phase, sync, state, code, text,
      can_time, publish_time;
  std::string str() const {
    return fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", recv, topic, node, axis,
                       status_bits, motor, encoder, velocity, phase, sync, state, code, text,
                       can_time, publish_time);
  }
};

}  // namespace

std::string status_words(const ::stepnode::AxisStatus& s) {
  std::string out;
  auto add = [&](bool on, const char* word) {
    if (!on) return;
    if (!out.empty()) out += ' ';
    out += word;
  };
  add(s.emergency_stop(), "estop");
  add(s.lower_limit(), "lower_limit");
  add(s.upper_limit(), "upper_limit");
  add(s.illegal_move(), "illegal_move");
  add(s.motor_stalled(), "stalled");
  add(s.power_up_error(), "power_up");
  add(s.position_valid(), "position_valid");
  add(s.resumable(), "resumable");
  add(s.axis2_selected(), "axis2");
  add(s.axis3_selected(), "axis3");
  add(s.at_home(), "at_home");
  add(s.accelerating(), "accelerating");
  add(s.decelerating(), "decelerating");
  add(s.moving(), "moving");
  return out.empty() ? "-" : out;
}

nlohmann::json to_json(const ::stepnode::AxisStatus& s) {
  return {{"node", s.node()},
          {"axis", s.axis()},
          {"status_bits", s.status_bits()},
          {"error_bits", s.error_bits()},
          {"emergency_stop", s.emergency_stop()},
          {"lower_limit", s.lower_limit()},
          {"upper_limit", s.upper_limit()},
          {"illegal_move", s.illegal_move()},
          {"motor_stalled", s.motor_stalled()},
          {"power_up_error", s.power_up_error()},
          {"position_valid", s.position_valid()},
          {"resumable", s.resumable()},
          {"axis2_selected", s.axis2_selected()},
          {"axis3_selected", s.axis3_selected()},
          {"at_home", s.at_home()},
          {"accelerating", s.accelerating()},
          {"decelerating", s.decelerating()},
          {"moving", s.moving()},
          {"done_code", s.done_code()},
          {"hp_error", s.hp_error()},
          {"can_time_ns", s.can_time_ns()}};
}

nlohmann::json to_json(const ::stepnode::AxisPosition& p) {
  return {{"node", p.node()},
          {"axis", p.axis()},
          {"motor_position", p.motor_position()},
          {"encoder_position", p.encoder_position()},
          {"motor_user_units", p.motor_user_units()},
          {"encoder_user_units", p.encoder_user_units()},
          {"velocity", p.velocity()},
          {"motion_phase", p.motion_phase()},
          {"sync_counter", p.sync_counter()},
          {"can_time_ns", p.can_time_ns()},
          {"publish_time_ns", p.publish_time_ns()}};
}

nlohmann::json to_json(const ::stepnode::NodeHealth& h) {
  return {{"node", h.node()},
          {"state", std::string(bridge::dds::state_text(h.state()))},
          {"is_stepnode", h.is_stepnode()},
          {"discovered", h.discovered()},
          {"device_name", h.device_name()},
          {"vendor_id", h.vendor_id()},
          {"product_code", h.product_code()},
          {"revision", h.revision()},
          {"serial", h.serial()},
          {"axes", h.axes()},
          {"heartbeat_age_ms", h.heartbeat_age_ms()},
          {"last_emcy_code", h.last_emcy_code()},
          {"error_register", h.error_register()},
          {"frames", h.frames()},
          {"bad_frames", h.bad_frames()},
          {"sdo_failures", h.sdo_failures()},
          {"bus_frames", h.bus_frames()},
          {"bus_bad_frames", h.bus_bad_frames()},
          {"bus_undecoded", h.bus_undecoded()},
          {"bus_error_frames", h.bus_error_frames()},
          {"bus_error_passive", h.bus_error_passive()},
          {"bus_off", h.bus_off()},
          {"bus_overruns", h.bus_overruns()}};
}

nlohmann::json to_json(const ::stepnode::Emergency& e) {
  std::vector<int> manufacturer(e.manufacturer().begin(), e.manufacturer().end());
  return {{"node", e.node()},
          {"code", e.code()},
          {"error_register", e.error_register()},
          {"manufacturer", manufacturer},
          {"text", e.text()},
          {"can_time_ns", e.can_time_ns()}};
}

namespace {

std::string mode_text(int8_t mode) {
  switch (mode) {  // 6060h/6061h
    case 0: return "no mode";
    case 1: return "pp";
    case 3: return "pv";
    case 6: return "hm";
    case 7: return "ip";
    case 8: return "csp";
    case 9: return "csv";
    default: return "mode " + std::to_string(mode);
  }
}

}  // namespace

std::string drive_words(const ::stepnode::DriveStatus& d) {
  std::string out =
      std::string(bridge::dds::drive_state_text(d.state())) + ", " + mode_text(d.mode_display());
  auto add = [&](bool on, const char* word) {
    if (on) out += std::string(" ") + word;
  };
  add(d.warning(), "warning");
  add(d.target_reached(), "target_reached");
  add(d.internal_limit_active(), "internal_limit");
  add(d.bit12(), "bit12");
  add(d.bit13(), "bit13");
  if (d.error_code()) out += fmt::format(" error 0x{:04X}", d.error_code());
  return out;
}

nlohmann::json to_json(const ::stepnode::DriveStatus& d) {
  return {{"node", d.node()},
          {"axis", d.axis()},
          {"statusword", d.statusword()},
          {"state", std::string(bridge::dds::drive_state_text(d.state()))},
          {"mode_display", d.mode_display()},
          {"position_actual", d.position_actual()},
          {"velocity_actual", d.velocity_actual()},
          {"following_error", d.following_error()},
          {"error_code", d.error_code()},
          {"ready_to_switch_on", d.ready_to_switch_on()},
          {"switched_on", d.switched_on()},
          {"operation_enabled", d.operation_enabled()},
          {"fault", d.fault()},
          {"voltage_enabled", d.voltage_enabled()},
          {"quick_stop", d.quick_stop()},
          {"switch_on_disabled", d.switch_on_disabled()},
          {"warning", d.warning()},
          {"remote", d.remote()},
          {"target_reached", d.target_reached()},
          {"internal_limit_active", d.internal_limit_active()},
          {"bit12", d.bit12()},
          {"bit13", d.bit13()},
          {"can_time_ns", d.can_time_ns()},
          {"publish_time_ns", d.publish_time_ns()}};
}

void WatchModel::on_drive(const ::stepnode::DriveStatus& d) {
  auto& row = axes_[key(d.node(), d.axis())];
  row.node = d.node();
  row.axis = d.axis();
  row.drive = d;
  ++samples_;
}

void WatchModel::on_status(const ::stepnode::AxisStatus& s) {
  auto& row = axes_[key(s.node(), s.axis())];
  row.node = s.node();
  row.axis = s.axis();
  row.status = s;
  ++samples_;
}

void WatchModel::on_position(const ::stepnode::AxisPosition& p) {
  auto& row = axes_[key(p.node(), p.axis())];
  row.node = p.node();
  row.axis = p.axis();
  row.position = p;
  ++samples_;
}

void WatchModel::on_health(const ::stepnode::NodeHealth& h) {
  nodes_[h.node()] = h;
  ++samples_;
}

void WatchModel::on_emergency(const ::stepnode::Emergency& e) {
  last_emcy_[e.node()] = e;
  ++samples_;
}

void WatchModel::on_axis_disposed(uint8_t node, uint8_t axis) { axes_.erase(key(node, axis)); }

std::vector<nlohmann::json> WatchModel::snapshot() const {
  std::vector<nlohmann::json> out;
  for (const auto& [id, health] : nodes_) {
    nlohmann::json j = to_json(health);
    j["type"] = "node";
    auto emcy = last_emcy_.find(id);
    j["last_emcy"] = emcy == last_emcy_.end() ? nlohmann::json(nullptr) : to_json(emcy->second);
    out.push_back(std::move(j));
  }
  for (const auto& [k, row] : axes_) {
    nlohmann::json j = {{"type", "axis"}, {"node", row.node}, {"axis", row.axis}};
    j["status"] = row.status ? to_json(*row.status) : nlohmann::json(nullptr);
    j["position"] = row.position ? to_json(*row.position) : nlohmann::json(nullptr);
    if (row.drive) j["drive"] = to_json(*row.drive);
    out.push_back(std::move(j));
  }
  return out;
}

std::string WatchModel::table() const {
  std::string out = fmt::format("{:>4} {:>4} {:>12} {:>12} {:>9} {:>5} {:>6}  {}\n", "node", "axis",
                                "position", "encoder", "velocity", "phase", "errors", "status");
  std::map<uint8_t, bool> shown;
  auto node_line = [&](uint8_t node) {
    auto it = nodes_.find(node);
    if (it == nodes_.end()) return fmt::format("{:>4} {}\n", node, "(no NodeHealth yet)");
    const auto& h = it->second;
    std::string line = fmt::format(
        "{:>4} {} {} {} axes, heartbeat {} ms ago, frames {} (bad {}), SDO failures {}", node,
        bridge::dds::state_text(h.state()), h.device_name().empty() ? "?" : h.device_name(),
        h.axes(), h.heartbeat_age_ms(), h.frames(), h.bad_frames(), h.sdo_failures());
    auto emcy = last_emcy_.find(node);
    if (emcy != last_emcy_.end())
      line += fmt::format(", last EMCY {:04X} {}", emcy->second.code(), emcy->second.text());
    return line + "\n";
  };
  for (const auto& [k, row] : axes_) {
    if (!shown[row.node]) {
      out += node_line(row.node);
      shown[row.node] = true;
    }
    std::string pos = row.position ? std::to_string(row.position->motor_position()) : "-";
    std::string enc = row.position ? std::to_string(row.position->encoder_position()) : "-";
    std::string vel = row.position ? std::to_string(row.position->velocity()) : "-";
    std::string phase = row.position ? std::to_string(row.position->motion_phase()) : "-";
    std::string errors = row.status ? fmt::format("0x{:02X}", row.status->error_bits()) : "-";
    std::string words = row.status ? status_words(*row.status) : "-";
    if (row.drive) {
      // A CiA 402 axis: its actual values where no Horner position came, and its state.
      if (!row.position) {
        pos = std::to_string(row.drive->position_actual());
        vel = std::to_string(row.drive->velocity_actual());
      }
      if (row.status) words += " | ";
      else words.clear();
      words.append("402: ").append(drive_words(*row.drive));
    }
    out += fmt::format("{:>4} {:>4} {:>12} {:>12} {:>9} {:>5} {:>6}  {}\n", "", row.axis, pos, enc,
                       vel, phase, errors, words);
  }
  for (const auto& [id, h] : nodes_)
    if (!shown[id]) out += node_line(id);
  return out;
}

std::string csv_header() {
  return "recv_time_ns,topic,node,axis,status_bits,motor_position,encoder_position,velocity,motion_"
         "phase,"
         "sync_counter,state,code,text,can_time_ns,publish_time_ns\n";
}

std::string csv_row(uint64_t recv, const ::stepnode::AxisStatus& s) {
  Row r(recv, "AxisStatus");
  r.node = std::to_string(s.node());
  r.axis = std::to_string(s.axis());
  r.status_bits = fmt::format("0x{:04X}", s.status_bits());
  r.text = csv_quote(status_words(s));
  r.can_time = std::to_string(s.can_time_ns());
  return r.str();
}

std::string csv_row(uint64_t recv, const ::stepnode::AxisPosition& p) {
  Row r(recv, "AxisPosition");
  r.node = std::to_string(p.node());
  r.axis = std::to_string(p.axis());
  r.motor = std::to_string(p.motor_position());
  r.encoder = std::to_string(p.encoder_position());
  r.velocity = std::to_string(p.velocity());
  r.phase = std::to_string(p.motion_phase());
  r.sync = std::to_string(p.sync_counter());
  r.can_time = std::to_string(p.can_time_ns());
  r.publish_time = std::to_string(p.publish_time_ns());
  return r.str();
}

std::string csv_row(uint64_t recv, const ::stepnode::NodeHealth& h) {
  Row r(recv, "NodeHealth");
  r.node = std::to_string(h.node());
  r.state = std::string(bridge::dds::state_text(h.state()));
  r.code = fmt::format("0x{:04X}", h.last_emcy_code());
  r.text = csv_quote(h.device_name());
  return r.str();
}

std::string csv_row(uint64_t recv, const ::stepnode::Emergency& e) {
  Row r(recv, "Emergency");
  r.node = std::to_string(e.node());
  r.code = fmt::format("0x{:04X}", e.code());
  r.text = csv_quote(e.text());
  r.can_time = std::to_string(e.can_time_ns());
  return r.str();
}

std::string csv_row(uint64_t recv, const ::stepnode::DriveStatus& d) {
  Row r(recv, "DriveStatus");
  r.node = std::to_string(d.node());
  r.axis = std::to_string(d.axis());
  r.status_bits = fmt::format("0x{:04X}", d.statusword());
  r.motor = std::to_string(d.position_actual());
  r.velocity = std::to_string(d.velocity_actual());
  r.state = std::string(bridge::dds::drive_state_text(d.state()));
  r.code = fmt::format("0x{:04X}", d.error_code());
  r.text = csv_quote(drive_words(d));
  r.can_time = std::to_string(d.can_time_ns());
  r.publish_time = std::to_string(d.publish_time_ns());
  return r.str();
}

std::string csv_disposed_row(uint64_t recv, const char* topic, uint8_t node, uint8_t axis) {
  Row r(recv, topic);
  r.node = std::to_string(node);
  r.axis = std::to_string(axis);
  r.state = "DISPOSED";
  return r.str();
}

}  // namespace stepnode::stepwatch
