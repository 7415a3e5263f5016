#include "tools/stepcalc/profile_report.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>

#include "node/motion/step_generator.hpp"

namespace stepnode::tools {
namespace {

using motion::kClockHz;
using motion::ticks_to_ms;

ProfileValues from_stpcalc(const motion::StpcalcResult& s) {
  return {s.acceleration_rate, s.deceleration_rate, s.velocity_resolution, s.base_velocity,
          s.running_velocity, s.peak_velocity, s.acceleration_pulses, s.running_pulses,
          s.deceleration_pulses, s.acceleration_time_ms, s.running_time_ms, s.deceleration_time_ms,
          s.total_time_ms};
}

// Runs the move in the engine; collects its exact phase figures and a velocity staircase.
ProfileValues run_engine(const motion::StpcalcInput& in, const motion::StpcalcResult& s,
                         std::vector<std::pair<double, double>>& curve) {
  motion::RampSpec ramp = motion::horner_ramp(in.aq3, in.aq4, in.aq5, in.aq6, in.aq7);
  motion::StepGenerator g;
  g.start(ramp, 0, +1, in.total ? std::optional<int64_t>(*in.total) : std::nullopt);
  motion::Step step;
  double last_v = -1;
  auto sample = [&](motion::Tick t) {
    double v = g.moving() ? g.velocity() : 0.0;
    if (v != last_v) {
      if (last_v >= 0) curve.emplace_back(ticks_to_ms(t), last_v);
      curve.emplace_back(ticks_to_ms(t), v);
      last_v = v;
    }
  };
  sample(0);
  while (g.next(step)) {
    sample(step.time);
    // A move without destination (jog): ramp up, then stop at once to see the ramp down.
    if (!in.total && g.phase() == motion::MotionPhase::Running) g.stop(step.time);
  }
  const auto& m = g.marks();
  sample(m.end);
  ProfileValues e;
  e.acceleration_rate = s.acceleration_rate;  // the quantised ramp has exactly these rates
  e.deceleration_rate = s.deceleration_rate;
  e.velocity_resolution = ramp.velocity_of(1);
  e.base_velocity = ramp.velocity_of(ramp.base_level);
  e.running_velocity = ramp.velocity_of(ramp.run_level);
  e.peak_velocity = ramp.velocity_of(m.peak_level);
  e.acceleration_pulses = static_cast<double>(m.accel_steps);
  e.running_pulses = static_cast<double>(m.run_steps);
  e.deceleration_pulses = static_cast<double>(m.decel_steps + m.creep_steps);
  motion::Tick accel_end = m.run_start >= 0 ? m.run_start : m.decel_start;
  motion::Tick decel_start = m.decel_start >= 0 ? m.decel_start : m.end;
  e.acceleration_time_ms = ticks_to_ms(accel_end - m.start);
  e.running_time_ms = m.run_start >= 0 ? ticks_to_ms(decel_start - m.run_start) : 0.0;
  e.deceleration_time_ms = ticks_to_ms(m.end - decel_start);
  e.total_time_ms = in.total ? ticks_to_ms(m.end - m.start) : e.acceleration_time_ms + e.deceleration_time_ms;
  return e;
}

}  // namespace

ProfileReport make_report(const motion::StpcalcInput& input) {
  motion::StpcalcResult s = motion::stpcalc(input);  // validates
  ProfileReport r;
  r.input = input;
  r.triangular = s.triangular;
  r.stpcalc = from_stpcalc(s);
  r.engine = run_engine(input, s, r.engine_curve);
  const ProfileValues& v = r.stpcalc;
  double t1 = v.acceleration_time_ms, t2 = t1 + v.running_time_ms, t3 = t2 + v.deceleration_time_ms;
  r.ideal_curve = {{0, v.base_velocity}, {t1, v.peak_velocity}, {t2, v.peak_velocity}, {t3, v.base_velocity}};
  return r;
}

std::string report_text(const ProfileReport& r) {
  const ProfileValues& s = r.stpcalc;
  const ProfileValues& e = r.engine;
  std::string out;
  char line[200];
  auto row = [&](const char* name, double a, double b, const char* unit) {
    std::snprintf(line, sizeof line, "%-36s %14.3f %14.3f  %s\n", name, a, b, unit);
    out += line;
  };
  std::snprintf(line, sizeof line, "%-36s %14s %14s\n", "", "STPCALC", "engine");
  out += line;
  row("Actual acceleration rate =", s.acceleration_rate, e.acceleration_rate, "pulses/sec^2");
  row("Actual deceleration rate =", s.deceleration_rate, e.deceleration_rate, "pulses/sec^2");
  row("Actual velocity resolution =", s.velocity_resolution, e.velocity_resolution, "pulses/sec");
  row("Actual base velocity =", s.base_velocity, e.base_velocity, "pulses/sec");
  if (r.triangular) row("Actual peak velocity =", s.peak_velocity, e.peak_velocity, "pulses/sec");
  else row("Actual running velocity =", s.running_velocity, e.running_velocity, "pulses/sec");
  row("Actual acceleration pulses =", s.acceleration_pulses, e.acceleration_pulses, "pulses");
  if (r.input.total) row("Actual running pulses =", s.running_pulses, e.running_pulses, "pulses");
  row("Actual deceleration pulses =", s.deceleration_pulses, e.deceleration_pulses, "pulses");
  if (!r.input.total)
    row("Actual total acc/dec pulses =", s.acceleration_pulses + s.deceleration_pulses,
        e.acceleration_pulses + e.deceleration_pulses, "pulses");
  row("Actual acceleration time =", s.acceleration_time_ms, e.acceleration_time_ms, "mS");
  if (r.input.total) row("Actual running time =", s.running_time_ms, e.running_time_ms, "mS");
  row("Actual deceleration time =", s.deceleration_time_ms, e.deceleration_time_ms, "mS");
  row(r.input.total ? "Actual total move time =" : "Actual total acc/dec time =", s.total_time_ms,
      e.total_time_ms, "mS");
  if (r.triangular)
    out += "Triangular move: STPCALC scales pulses and times by R_T (B1.3.8); the engine splits the\n"
           "pulses the same way, stays at or below STPCALC's peak velocity and hits the total exactly.\n";
  return out;
}

std::string report_json(const ProfileReport& r) {
  auto values = [](const ProfileValues& v) {
    return nlohmann::json{{"acceleration_rate", v.acceleration_rate},
                          {"deceleration_rate", v.deceleration_rate},
                          {"velocity_resolution", v.velocity_resolution},
                          {"base_velocity", v.base_velocity},
                          {"running_velocity", v.running_velocity},
                          {"peak_velocity", v.peak_velocity},
                          {"acceleration_pulses", v.acceleration_pulses},
                          {"running_pulses", v.running_pulses},
                          {"deceleration_pulses", v.deceleration_pulses},
                          {"acceleration_time_ms", v.acceleration_time_ms},
                          {"running_time_ms", v.running_time_ms},
                          {"deceleration_time_ms", v.deceleration_time_ms},
                          {"total_time_ms", v.total_time_ms}};
  };
  nlohmann::json j = values(r.stpcalc);
  j["engine"] = values(r.engine);
  j["triangular"] = r.triangular;
  return j.dump(2) + "\n";
}

}  // namespace stepnode::tools
