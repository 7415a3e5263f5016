// Velocity against time as a small hand-written SVG: axes, ticks, labels, both curves.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "tools/stepcalc/profile_report.hpp"

namespace stepnode::tools {
namespace {

double nice_step(double range) {
  double raw = range / 6;
  double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (raw <= m * p) return m * p;
  return 10 * p;
}

}  // namespace

std::string report_svg(const ProfileReport& r) {
  const double W = 900, H = 500, L = 90, R = 30, T = 50, B = 60;
  double tmax = 0, vmax = 0;
  for (const auto* c : {&r.ideal_curve, &r.engine_curve})
    for (auto [t, v] : *c) tmax = std::max(tmax, t), vmax = std::max(vmax, v);
  tmax = std::max(tmax, 1e-3);
  vmax = std::max(vmax * 1.1, 1e-3);
  auto x = [&](double t) { return L + t / tmax * (W - L - R); };
  auto y = [&](double v) { return H - B - v / vmax * (H - T - B); };
  std::string s;
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" font-family=\"sans-serif\" "
                "font-size=\"12\">\n<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n", W, H);
  s += buf;
  std::snprintf(buf, sizeof buf, "<text x=\"%.0f\" y=\"25\" font-size=\"15\">Velocity profile: total %s, AQ3..AQ7 = %lld %lld %lld %lld %lld</text>\n",
                L, r.input.total ? std::to_string(*r.input.total).c_str() : "-", static_cast<long long>(r.input.aq3),
                static_cast<long long>(r.input.aq4), static_cast<long long>(r.input.aq5),
                static_cast<long long>(r.input.aq6), static_cast<long long>(r.input.aq7));
  s += buf;
  std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"black\"/>\n", L, H - B, W - R, H - B);
  s += buf;
  std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"black\"/>\n", L, T, L, H - B);
  s += buf;
  for (double t = 0, st = nice_step(tmax); t <= tmax + 1e-9; t += st) {
    std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ccc\"/><text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%g</text>\n",
                  x(t), T, x(t), H - B, x(t), H - B + 18, t);
    s += buf;
  }
  for (double v = 0, sv = nice_step(vmax); v <= vmax + 1e-9; v += sv) {
    std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ccc\"/><text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%g</text>\n",
                  L, y(v), W - R, y(v), L - 6, y(v) + 4, v);
    s += buf;
  }
  std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">time (ms)</text>\n", (L + W - R) / 2, H - 15);
  s += buf;
  std::snprintf(buf, sizeof buf, "<text transform=\"translate(20 %.1f) rotate(-90)\" text-anchor=\"middle\">velocity (pulses/s)</text>\n", (T + H - B) / 2);
  s += buf;
  auto polyline = [&](const std::vector<std::pair<double, double>>& c, const char* id, const char* colour,
                      const char* extra) {
    s += std::string("<polyline id=\"") + id + "\" fill=\"none\" stroke=\"" + colour + "\" stroke-width=\"2\" " + extra + " points=\"";
    size_t stride = std::max<size_t>(1, c.size() / 4000);  // a few thousand points at most
    for (size_t i = 0; i < c.size(); i += stride) {
      std::snprintf(buf, sizeof buf, "%.2f,%.2f ", x(c[i].first), y(c[i].second));
      s += buf;
    }
    if (!c.empty()) {
      std::snprintf(buf, sizeof buf, "%.2f,%.2f", x(c.back().first), y(c.back().second));
      s += buf;
    }
    s += "\"/>\n";
  };
  polyline(r.engine_curve, "engine", "#1f77b4", "");
  polyline(r.ideal_curve, "stpcalc", "#d62728", "stroke-dasharray=\"6 4\"");
  std::snprintf(buf, sizeof buf,
                "<g><line x1=\"%.0f\" y1=\"%.0f\" x2=\"%.0f\" y2=\"%.0f\" stroke=\"#d62728\" stroke-width=\"2\" stroke-dasharray=\"6 4\"/>"
                "<text x=\"%.0f\" y=\"%.0f\">STPCALC (Appendix B)</text>"
                "<line x1=\"%.0f\" y1=\"%.0f\" x2=\"%.0f\" y2=\"%.0f\" stroke=\"#1f77b4\" stroke-width=\"2\"/>"
                "<text x=\"%.0f\" y=\"%.0f\">engine (quantised ramp)</text></g>\n",
                W - 260, T + 10, W - 230, T + 10, W - 222, T + 14, W - 260, T + 30, W - 230, T + 30, W - 222, T + 34);
  s += buf;
  s += "</svg>\n";
  return s;
}

}  // namespace stepnode::tools
