#include "tools/stepcalc/profile_report.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <utility>

#include "node/motion/ramp.hpp"
#include "tools/stepcalc/engine_profile.hpp"

namespace stepnode::tools {
namespace {

ProfileValues from_stpcalc(const motion::StpcalcResult& s) {
  return {s.acceleration_rate,    s.deceleration_rate, s.velocity_resolution,
          s.base_velocity,        s.running_velocity,  s.peak_velocity,
          s.acceleration_pulses,  s.running_pulses,    s.deceleration_pulses,
          s.acceleration_time_ms, s.running_time_ms,   s.deceleration_time_ms,
          s.total_time_ms};
}

// STPCALC's outline: base velocity at once, a straight ramp to the peak over Time_A, the
// running time, a straight ramp down over Time_D, then standstill.
Curve ideal_curve(const ProfileValues& v) {
  double t1 = v.acceleration_time_ms, t2 = t1 + v.running_time_ms, t3 = t2 + v.deceleration_time_ms;
  if (t3 <= 0) return {};
  return {{0, 0},
          {0, v.base_velocity},
          {t1, v.peak_velocity},
          {t2, v.peak_velocity},
          {t3, v.base_velocity},
          {t3, 0}};
}

nlohmann::json to_json(const ProfileValues& v) {
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
}

}  // namespace

ProfileReport make_report(const motion::StpcalcInput& input, bool stpcalc_peak) {
  motion::StpcalcResult s = motion::stpcalc(input);  // validates every input
  ProfileReport r;
  r.input = input;
  r.triangular = s.triangular;
  r.stpcalc_peak = stpcalc_peak;
  r.stpcalc = from_stpcalc(s);
  EngineProfile e = run_engine(input, stpcalc_peak);
  r.engine = e.values;
  r.engine_curve = std::move(e.staircase);
  r.ideal_curve = ideal_curve(r.stpcalc);
  return r;
}

std::string report_text(const ProfileReport& r) {
  const ProfileValues& s = r.stpcalc;
  const ProfileValues& e = r.engine;
  const bool total = r.input.total.has_value();
  std::string out;
  char line[256];
  auto row = [&](const char* words, double a, double b, const char* unit) {
    std::snprintf(line, sizeof line, "%-32s %14.3f %14.3f  %s\n", words, a, b, unit);
    out += line;
  };
  std::snprintf(line, sizeof line,
                "total pulses %s, velocity resolution %lld, base %lld, running %lld, accel %lld "
                "mS, decel %lld mS%s\n",
                total ? std::to_string(*r.input.total).c_str() : "(none)",
                static_cast<long long>(r.input.aq3), static_cast<long long>(r.input.aq4),
                static_cast<long long>(r.input.aq5), static_cast<long long>(r.input.aq6),
                static_cast<long long>(r.input.aq7), r.input.aq7 == 0 ? " (= accel)" : "");
  out += line;
  std::snprintf(line, sizeof line, "%-32s %14s %14s\n", "", "STPCALC", "engine");
  out += line;
  row("Actual acceleration rate =", s.acceleration_rate, e.acceleration_rate, "pulses/sec^2");
  row("Actual deceleration rate =", s.deceleration_rate, e.deceleration_rate, "pulses/sec^2");
  row("Actual velocity resolution =", s.velocity_resolution, e.velocity_resolution, "pulses/sec");
  row("Actual base velocity =", s.base_velocity, e.base_velocity, "pulses/sec");
  if (r.triangular) row("Actual peak velocity =", s.peak_velocity, e.peak_velocity, "pulses/sec");
  else row("Actual running velocity =", s.running_velocity, e.running_velocity, "pulses/sec");
  row("Actual acceleration pulses =", s.acceleration_pulses, e.acceleration_pulses, "pulses");
  if (total) row("Actual running pulses =", s.running_pulses, e.running_pulses, "pulses");
  row("Actual deceleration pulses =", s.deceleration_pulses, e.deceleration_pulses, "pulses");
  if (!total)
    row("Actual total acc/dec pulses =", s.acceleration_pulses + s.deceleration_pulses,
        e.acceleration_pulses + e.deceleration_pulses, "pulses");
  row("Actual acceleration time =", s.acceleration_time_ms, e.acceleration_time_ms, "mS");
  if (total) row("Actual running time =", s.running_time_ms, e.running_time_ms, "mS");
  row("Actual deceleration time =", s.deceleration_time_ms, e.deceleration_time_ms, "mS");
  if (total) row("Actual total move time =", s.total_time_ms, e.total_time_ms, "mS");
  else row("Actual total acc/dec time =", s.total_time_ms, e.total_time_ms, "mS");
  if (r.triangular && r.stpcalc_peak)
    out +=
        "Triangular move: STPCALC scales the ramps' pulses and times by R_T = "
        "total/(Pulse_A+Pulse_D)\n"
        "(B1.3.8); the engine (--stpcalc-peak) ramps to STPCALC's peak velocity (B1.3.6), never "
        "above\n"
        "it, and runs at that peak for the pulses its ramps leave.\n";
  else if (r.triangular)
    out +=
        "Triangular move: STPCALC scales the ramps' pulses and times by R_T = "
        "total/(Pulse_A+Pulse_D)\n"
        "(B1.3.8), which no ramp does; the engine, as the module (SPM30 3.4.5), turns on the "
        "highest\n"
        "velocity whose ramps fit the move (halfway with equal ramps) and does not cruise.\n";
  const int64_t useful = motion::horner_max_ramp_ms(r.input.aq4, r.input.aq5);
  for (auto [name, ms] : {std::pair{"AQ6", r.input.aq6}, std::pair{"AQ7", r.input.aq7}})
    if (ms > useful) {
      std::snprintf(line, sizeof line,
                    "%s %lld mS is above its maximum useful value (AQ5-AQ4)/0.3 = %lld mS (SPM30 "
                    "3.4.5): the\n"
                    "module ramps in %lld mS; STPCALC's figures use the time as given.\n",
                    name, static_cast<long long>(ms), static_cast<long long>(useful),
                    static_cast<long long>(useful));
      out += line;
    }
  if (!total)
    out += "No total: the engine's figures are an unbounded move stopped as soon as it runs.\n";
  return out;
}

std::string report_json(const ProfileReport& r) {
  nlohmann::json j = to_json(r.stpcalc);
  j["engine"] = to_json(r.engine);
  j["triangular"] = r.triangular;
  j["input"] = {{"total", r.input.total ? nlohmann::json(*r.input.total) : nlohmann::json(nullptr)},
                {"aq3", r.input.aq3},
                {"aq4", r.input.aq4},
                {"aq5", r.input.aq5},
                {"aq6", r.input.aq6},
                {"aq7", r.input.aq7}};
  return j.dump(2) + "\n";
}

}  // namespace stepnode::tools
