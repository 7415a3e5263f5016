#include "tools/stepcalc/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace stepnode::tools {
namespace {

constexpr double kWidth = 960, kHeight = 540;
constexpr double kLeft = 95, kRight = 30, kTop = 72, kBottom = 58;  // plot area margins

// A 1-2-5 step giving about `ticks` intervals over [0, range].
double nice_step(double range, int ticks) {
  double raw = range / ticks;
  double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (raw <= m * p) return m * p;
  return 10 * p;
}

std::string number(double v) {
  char buf[32];
  if (std::fabs(v) >= 1 || v == 0) std::snprintf(buf, sizeof buf, "%.0f", v);
  else std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

struct Frame {
  double tmax, vmax;
  double x(double t) const { return kLeft + t / tmax * (kWidth - kLeft - kRight); }
  double y(double v) const { return kHeight - kBottom - v / vmax * (kHeight - kTop - kBottom); }
};

// Screen points of a curve, dropping corners within half a pixel of the last kept one, then
// thinning evenly if still more than kMaxPlotPoints; the first and last points always stay.
std::vector<std::pair<double, double>> screen_points(const Curve& c, const Frame& f) {
  std::vector<std::pair<double, double>> pts;
  for (size_t i = 0; i < c.size(); ++i) {
    double px = f.x(c[i].first), py = f.y(c[i].second);
    bool last = i + 1 == c.size();
    bool near = !pts.empty() && std::fabs(px - pts.back().first) < 0.5 &&
                std::fabs(py - pts.back().second) < 0.5;
    if (near && !last) continue;
    pts.emplace_back(px, py);
  }
  if (pts.size() > kMaxPlotPoints) {
    std::vector<std::pair<double, double>> thin;
    double stride = static_cast<double>(pts.size() - 1) / static_cast<double>(kMaxPlotPoints - 1);
    for (size_t k = 0; k < kMaxPlotPoints; ++k)
      thin.push_back(pts[std::min(
          pts.size() - 1, static_cast<size_t>(std::llround(static_cast<double>(k) * stride)))]);
    pts.swap(thin);
  }
  return pts;
}

// The plot area's corners: x from kX0 to kX1, y from kY0 (bottom) up to kY1.
constexpr double kX0 = kLeft, kX1 = kWidth - kRight, kY0 = kHeight - kBottom, kY1 = kTop;

// The document as it is written.
struct Svg {
  std::string s;

  template <class... Args>
  void put(const char* fmt, Args... args) {
    char buf[1024];
    std::snprintf(buf, sizeof buf, fmt, args...);
    s += buf;
  }
  void line(double xa, double ya, double xb, double yb) {
    put("<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", xa, ya, xb, yb);
  }
  void text(double x, double y, const char* anchor, const std::string& what) {
    put("<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"%s\">%s</text>\n", x, y, anchor, what.c_str());
  }
};

// Both curves fit, with a little room above and to the right.
Frame frame_of(const PlotSpec& p) {
  Frame f{0, 0};
  for (const Curve* c : {&p.reference, &p.engine})
    for (auto [t, v] : *c) f.tmax = std::max(f.tmax, t), f.vmax = std::max(f.vmax, v);
  f.tmax = f.tmax > 0 ? f.tmax * 1.02 : 1.0;
  f.vmax = f.vmax > 0 ? f.vmax * 1.08 : 1.0;
  return f;
}

// The XML header, the title (the inputs), the background and the heading.
void put_heading(Svg& svg, const PlotSpec& p) {
  svg.put(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" viewBox=\"0 0 %.0f "
      "%.0f\" "
      "font-family=\"DejaVu Sans, Arial, sans-serif\" font-size=\"12\">\n",
      kWidth, kHeight, kWidth, kHeight);
  svg.put("<title>%s</title>\n", p.title.c_str());
  svg.put("<rect x=\"0\" y=\"0\" width=\"%.0f\" height=\"%.0f\" fill=\"white\"/>\n", kWidth,
          kHeight);
  svg.put("<text x=\"%.0f\" y=\"24\" font-size=\"15\">%s</text>\n", kLeft, p.heading.c_str());
}

// The Horner move's plot: STPCALC's outline against the engine's staircase.
PlotSpec horner_plot(const ProfileReport& r) {
  PlotSpec p;
  const std::string total =
      r.input.total ? std::to_string(*r.input.total) : std::string("- (no destination)");
  const std::string aq = std::to_string(r.input.aq3) + " " + std::to_string(r.input.aq4) + " " +
                         std::to_string(r.input.aq5) + " " + std::to_string(r.input.aq6) + " " +
                         std::to_string(r.input.aq7);
  p.title = "stepcalc " + total + " " + aq;
  p.heading = "Velocity profile: total " + total + ", AQ3..AQ7 = " + aq +
              (r.triangular ? " (triangular)" : "");
  p.reference_id = "stpcalc";
  p.reference_label = "STPCALC (Appendix B): straight ramps at Rate_A / Rate_D";
  p.engine_label = "engine: quantised ramp, one level per Z_A / Z_D ticks";
  p.reference = r.ideal_curve;
  p.engine = r.engine_curve;
  return p;
}

// Grid, axes, tick marks, tick labels and the axis titles.
void put_axes(Svg& svg, const Frame& f, const std::string& unit) {
  const double tstep = nice_step(f.tmax, 8), vstep = nice_step(f.vmax, 6);
  auto each_tick = [](double step, double max, auto fn) {
    for (int i = 0; i * step <= max * (1 + 1e-9); ++i) fn(i * step);
  };
  svg.s += "<g id=\"grid\" stroke=\"#dddddd\" stroke-width=\"1\">\n";
  each_tick(tstep, f.tmax, [&](double t) { svg.line(f.x(t), kY0, f.x(t), kY1); });
  each_tick(vstep, f.vmax, [&](double v) { svg.line(kX0, f.y(v), kX1, f.y(v)); });
  svg.s += "</g>\n<g id=\"axes\" stroke=\"black\" stroke-width=\"1\">\n";
  svg.line(kX0, kY0, kX1, kY0);
  svg.line(kX0, kY0, kX0, kY1);
  each_tick(tstep, f.tmax, [&](double t) { svg.line(f.x(t), kY0, f.x(t), kY0 + 5); });
  each_tick(vstep, f.vmax, [&](double v) { svg.line(kX0 - 5, f.y(v), kX0, f.y(v)); });
  svg.s += "</g>\n<g id=\"tick-labels\" fill=\"black\">\n";
  each_tick(tstep, f.tmax, [&](double t) { svg.text(f.x(t), kY0 + 19, "middle", number(t)); });
  each_tick(vstep, f.vmax, [&](double v) { svg.text(kX0 - 8, f.y(v) + 4, "end", number(v)); });
  svg.s += "</g>\n";
  svg.text((kX0 + kX1) / 2, kHeight - 14, "middle", "time (ms)");
  svg.put(
      "<text transform=\"translate(22 %.1f) rotate(-90)\" text-anchor=\"middle\">velocity "
      "(%s)</text>\n",
      (kY0 + kY1) / 2, unit.c_str());
}

// The two series, clipped to the plot area.
void put_curves(Svg& svg, const PlotSpec& p, const Frame& f) {
  svg.put(
      "<defs><clipPath id=\"plot-area\">"
      "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\"/></clipPath></defs>\n",
      kX0, kY1 - 2, kX1 - kX0, kY0 - kY1 + 4);
  auto polyline = [&](const Curve& c, const char* id, const char* colour, const char* extra) {
    svg.s += std::string("<polyline id=\"") + id +
             "\" clip-path=\"url(#plot-area)\" fill=\"none\" stroke=\"" + colour +
             "\" stroke-width=\"1.8\" stroke-linejoin=\"round\"" + extra + " points=\"";
    bool first = true;
    for (auto [px, py] : screen_points(c, f)) {
      svg.put(first ? "%.2f,%.2f" : " %.2f,%.2f", px, py);
      first = false;
    }
    svg.s += "\"/>\n";
  };
  polyline(p.engine, "engine", "#1f77b4", "");
  polyline(p.reference, p.reference_id.c_str(), "#d62728", " stroke-dasharray=\"7 4\"");
}

// Legend, above the plot area so it never covers a curve.
void put_legend(Svg& svg, const PlotSpec& p) {
  double lx = kLeft, ly = 50;
  svg.put(
      "<g id=\"legend\">"
      "<line x1=\"%.0f\" y1=\"%.0f\" x2=\"%.0f\" y2=\"%.0f\" stroke=\"#d62728\" stroke-width=\"2\" "
      "stroke-dasharray=\"7 4\"/>"
      "<text x=\"%.0f\" y=\"%.0f\">%s</text>",
      lx, ly, lx + 30, ly, lx + 36, ly + 4, p.reference_label.c_str());
  lx += 400;
  svg.put(
      "<line x1=\"%.0f\" y1=\"%.0f\" x2=\"%.0f\" y2=\"%.0f\" stroke=\"#1f77b4\" "
      "stroke-width=\"2\"/>"
      "<text x=\"%.0f\" y=\"%.0f\">%s</text></g>\n",
      lx, ly, lx + 30, ly, lx + 36, ly + 4, p.engine_label.c_str());
}

}  // namespace

std::string render_svg(const PlotSpec& p) {
  const Frame f = frame_of(p);
  Svg svg;
  put_heading(svg, p);
  put_axes(svg, f, p.velocity_unit);
  put_curves(svg, p, f);
  put_legend(svg, p);
  svg.s += "</svg>\n";
  return svg.s;
}

std::string render_svg(const ProfileReport& r) { return render_svg(horner_plot(r)); }

}  // namespace stepnode::tools
