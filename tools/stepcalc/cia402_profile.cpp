#include "tools/stepcalc/cia402_profile.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

#include "node/motion/ramp.hpp"
#include "node/motion/step_generator.hpp"

namespace stepnode::tools {
namespace {

using motion::kClockHz;
using motion::Tick;

constexpr int16_t kLinearRamp = 0, kJerkLimitedRamp = 3;

// A stretch of constant jerk: the acceleration is `accel` at its start (a jerk that is not
// limited makes it jump there) and changes by `jerk` per second.
struct Segment {
  double duration, accel, jerk;
};

// The continuous profile: position and velocity against time from rest at 0.
class ClosedForm {
 public:
  explicit ClosedForm(std::vector<Segment> segments) : segments_(std::move(segments)) {
    for (const Segment& s : segments_) duration_ += s.duration;
  }
  double duration() const { return duration_; }
  // Position (steps) and velocity (steps/s) at `t` seconds.
  std::pair<double, double> at(double t) const {
    double p = 0, v = 0;
    for (const Segment& s : segments_) {
      const double dt = std::clamp(t, 0.0, s.duration);
      p += v * dt + s.accel * dt * dt / 2 + s.jerk * dt * dt * dt / 6;
      v += s.accel * dt + s.jerk * dt * dt / 2;
      t -= s.duration;
      if (t <= 0) break;
    }
    return {p, v};
  }
  // The first instant the position reaches `p` (it never moves backwards), from `from` on.
  double time_of(double p, double from) const {
    double lo = from, hi = duration_;
    for (int i = 0; i < 64 && hi - lo > 1e-12; ++i) {
      const double mid = (lo + hi) / 2;
      (at(mid).first < p ? lo : hi) = mid;
    }
    return hi;
  }

 private:
  std::vector<Segment> segments_;
  double duration_ = 0;
};

double inverse(uint32_t jerk) { return jerk ? 1.0 / jerk : 0.0; }

// From rest to `v` at slope `a`, the jerk `begin` then `end` (0: not limited). If the jerk
// phases alone would pass `v`, the acceleration peaks lower, where they meet.
std::vector<Segment> ramp(double v, double a, uint32_t begin, uint32_t end) {
  const double k = (inverse(begin) + inverse(end)) / 2;  // v gained = peak^2 * k in the jerks
  const double peak = v >= a * a * k ? a : std::sqrt(v / k);
  const double constant = std::max(0.0, (v - peak * peak * k) / peak);
  return {{peak * inverse(begin), 0, static_cast<double>(begin)},
          {constant, peak, 0},
          {peak * inverse(end), peak, -static_cast<double>(end)}};
}

double distance_of(const std::vector<Segment>& segments) {
  return ClosedForm(segments).at(1e300).first;
}

// The move as the profile defines it, or nullopt for a jerk-limited move too short to reach
// 6081h (the planner chooses its peak where both ramps fit; that closed form is not made).
std::optional<ClosedForm> closed_form(const Cia402Move& m) {
  const bool jerks = m.profile_type == kJerkLimitedRamp;
  const uint32_t j1 = jerks ? m.jerk[0] : 0, j2 = jerks ? m.jerk[1] : 0;
  const uint32_t j3 = jerks ? m.jerk[2] : 0, j4 = jerks ? m.jerk[3] : 0;
  const double v = m.velocity, a = m.acceleration, d = m.deceleration;
  std::vector<Segment> up = ramp(v, a, j1, j3), down = ramp(v, d, j2, j4);
  const double cruise = (static_cast<double>(m.distance) - distance_of(up) - distance_of(down)) / v;
  if (cruise < 0 && jerks) return std::nullopt;
  if (cruise < 0) {  // a linear ramp's triangle: the peak where the two slopes meet
    const double peak = std::sqrt(2.0 * static_cast<double>(m.distance) * a * d / (a + d));
    return ClosedForm({{peak / a, a, 0}, {peak / d, -d, 0}});
  }
  std::vector<Segment> all = up;
  all.push_back({cruise, 0, 0});
  for (const Segment& s : down) all.push_back({s.duration, -s.accel, -s.jerk});
  return ClosedForm(all);
}

// The engine's ticks of every step, as the CiA 402 drive starts a PP move (drive_pp.cpp).
std::vector<Tick> engine_steps(const Cia402Move& m) {
  const int64_t v = m.velocity, acc = m.acceleration, dec = m.deceleration;
  motion::RampSpec r =
      motion::profile_ramp(v, acc, dec, motion::profile_levels_per_hz(std::max(acc, dec)));
  if (m.profile_type == kJerkLimitedRamp) {
    r.s_curve = true;
    std::copy(std::begin(m.jerk), std::end(m.jerk), std::begin(r.jerk));
  }
  motion::StepGenerator g;
  g.start(r, 0, +1, m.distance);
  std::vector<Tick> ticks;
  ticks.reserve(static_cast<size_t>(m.distance));
  motion::Step step;
  while (g.next(step)) ticks.push_back(step.time);
  return ticks;
}

void check(const Cia402Move& m) {
  auto refuse = [](const std::string& what) { throw std::invalid_argument(what); };
  if (m.distance < 1 || m.distance > INT32_MAX) refuse("DISTANCE must be 1..2147483647 steps");
  if (m.velocity == 0) refuse("--velocity (6081h) must be at least 1 step/s");
  if (m.acceleration == 0 || m.deceleration == 0)
    refuse("--acceleration and --deceleration (6083h, 6084h) must be at least 1 step/s^2");
  if (m.profile_type != kLinearRamp && m.profile_type != kJerkLimitedRamp)
    refuse("--profile-type (6086h) must be 0 (linear ramp) or 3 (jerk-limited ramp)");
}

double ms(double seconds) { return seconds * 1e3; }

}  // namespace

Cia402Report make_cia402_report(const Cia402Move& move) {
  check(move);
  Cia402Report r;
  r.move = move;
  const std::vector<Tick> ticks = engine_steps(move);
  r.steps = static_cast<int64_t>(ticks.size());
  r.engine_time_ms = ticks.empty() ? 0 : ms(static_cast<double>(ticks.back()) / kClockHz);
  Tick last = 0;
  r.engine_curve.emplace_back(0, 0);
  for (Tick t : ticks) {
    const double v = t > last ? static_cast<double>(kClockHz) / static_cast<double>(t - last) : 0;
    r.peak_velocity = std::max(r.peak_velocity, v);
    r.engine_curve.emplace_back(ms(static_cast<double>(t) / kClockHz), v);
    last = t;
  }
  r.engine_curve.emplace_back(r.engine_time_ms, 0);
  const std::optional<ClosedForm> form = closed_form(move);
  if (!form) return r;
  r.closed_form_time_ms = ms(form->duration());
  double worst = 0, from = 0, peak = 0;
  for (size_t n = 0; n < ticks.size(); ++n) {
    from = form->time_of(static_cast<double>(n + 1), from);
    worst = std::max(worst, std::fabs(static_cast<double>(ticks[n]) / kClockHz - from));
  }
  r.max_step_deviation_us = worst * 1e6;
  constexpr int kSamples = 2000;
  for (int i = 0; i <= kSamples; ++i) {
    const double t = form->duration() * i / kSamples;
    const double v = form->at(t).second;
    peak = std::max(peak, v);
    r.closed_form_curve.emplace_back(ms(t), v);
  }
  r.closed_form_peak_velocity = peak;
  return r;
}

std::string cia402_text(const Cia402Report& r) {
  const Cia402Move& m = r.move;
  char buf[512];
  std::string out;
  std::snprintf(buf, sizeof buf,
                "CiA 402 profile position move of %lld steps: 6081h %u steps/s, 6083h %u and 6084h "
                "%u steps/s^2, 6086h %d (%s)",
                static_cast<long long>(m.distance), m.velocity, m.acceleration, m.deceleration,
                m.profile_type,
                m.profile_type == kJerkLimitedRamp ? "jerk-limited" : "linear ramp");
  out += buf;
  if (m.profile_type == kJerkLimitedRamp) {
    std::snprintf(buf, sizeof buf, ", 60A4h %u %u %u %u steps/s^3", m.jerk[0], m.jerk[1], m.jerk[2],
                  m.jerk[3]);
    out += buf;
  }
  out += "\n";
  auto row = [&](const char* what, std::optional<double> form, double engine) {
    if (form) std::snprintf(buf, sizeof buf, "  %-26s %14.3f %14.3f\n", what, *form, engine);
    else std::snprintf(buf, sizeof buf, "  %-26s %14s %14.3f\n", what, "-", engine);
    out += buf;
  };
  std::snprintf(buf, sizeof buf, "  %-26s %14s %14s\n", "", "closed form", "engine");
  out += buf;
  row("move time (ms)", r.closed_form_time_ms, r.engine_time_ms);
  row("peak velocity (steps/s)", r.closed_form_peak_velocity, r.peak_velocity);
  row("steps", static_cast<double>(m.distance), static_cast<double>(r.steps));
  if (r.max_step_deviation_us) {
    std::snprintf(
        buf, sizeof buf,
        "  largest step time from the closed form's: %.3f us (one engine tick: %.3f us)\n",
        *r.max_step_deviation_us, 1e6 / kClockHz);
    out += buf;
  } else {
    out +=
        "  the move does not reach 6081h: no closed form (the planner peaks where both ramps "
        "fit)\n";
  }
  return out;
}

std::string cia402_json(const Cia402Report& r) {
  nlohmann::json j;
  j["distance"] = r.move.distance;
  j["velocity"] = r.move.velocity;
  j["acceleration"] = r.move.acceleration;
  j["deceleration"] = r.move.deceleration;
  j["profile_type"] = r.move.profile_type;
  j["jerk"] = {r.move.jerk[0], r.move.jerk[1], r.move.jerk[2], r.move.jerk[3]};
  auto maybe = [](std::optional<double> v) { return v ? nlohmann::json(*v) : nlohmann::json(); };
  j["closed_form"] = {{"time_ms", maybe(r.closed_form_time_ms)},
                      {"peak_velocity", maybe(r.closed_form_peak_velocity)}};
  j["engine"] = {{"time_ms", r.engine_time_ms},
                 {"peak_velocity", r.peak_velocity},
                 {"steps", r.steps},
                 {"max_step_deviation_us", maybe(r.max_step_deviation_us)}};
  return j.dump() + "\n";
}

PlotSpec cia402_plot(const Cia402Report& r) {
  PlotSpec p;
  const Cia402Move& m = r.move;
  const bool jerks = m.profile_type == kJerkLimitedRamp;
  p.title = "stepcalc cia402 " + std::to_string(m.distance);
  p.heading = "CiA 402 PP move: " + std::to_string(m.distance) + " steps, 6081h " +
              std::to_string(m.velocity) + ", 6083h " + std::to_string(m.acceleration) +
              ", 6084h " + std::to_string(m.deceleration) + ", 6086h " +
              std::to_string(m.profile_type) + (jerks ? " (jerk-limited)" : " (linear ramp)");
  p.reference_id = "closed-form";
  p.reference_label = jerks ? "closed form: constant-jerk segments" : "closed form: trapezoid";
  p.engine_label = "engine: the rate of every step";
  p.velocity_unit = "steps/s";
  p.reference = r.closed_form_curve;
  p.engine = r.engine_curve;
  return p;
}

}  // namespace stepnode::tools
