// The velocity plot: well-formed SVG with axes, labels, a legend and both series.
#include <gtest/gtest.h>

#include <sstream>

#include "tools/stepcalc/svg_plot.hpp"
#include "tools/stepcalc/tests/xml_check.hpp"

namespace stepnode::tools {
namespace {

using testing::XmlCheck;
using testing::XmlElement;

const XmlElement* find_id(const std::vector<XmlElement>& els, const std::string& id) {
  for (const XmlElement& e : els) {
    auto it = e.attributes.find("id");
    if (it != e.attributes.end() && it->second == id) return &e;
  }
  return nullptr;
}

std::vector<std::pair<double, double>> points(const XmlElement& polyline) {
  std::vector<std::pair<double, double>> pts;
  std::istringstream in(polyline.attributes.at("points"));
  std::string pair;
  while (in >> pair) {
    size_t comma = pair.find(',');
    EXPECT_NE(comma, std::string::npos) << pair;
    pts.emplace_back(std::stod(pair.substr(0, comma)), std::stod(pair.substr(comma + 1)));
  }
  return pts;
}

TEST(StepcalcSvg, CheckerRejectsBrokenXml) {
  EXPECT_NO_THROW(XmlCheck("<a x=\"1\"><b/>t &amp; u</a>"));
  EXPECT_THROW(XmlCheck("<a><b></a>"), std::runtime_error);
  EXPECT_THROW(XmlCheck("<a x=1/>"), std::runtime_error);
  EXPECT_THROW(XmlCheck("<a>&nbsp;</a>"), std::runtime_error);
  EXPECT_THROW(XmlCheck("<a/><b/>"), std::runtime_error);
}

TEST(StepcalcSvg, WellFormedWithBothSeriesAxesAndLegend) {
  for (motion::StpcalcInput in : {motion::StpcalcInput{10000, 600, 100, 1000, 500, 0},
                                  motion::StpcalcInput{300, 600, 100, 1000, 500, 250},
                                  motion::StpcalcInput{std::nullopt, 20, 1, 8191, 100, 0},
                                  motion::StpcalcInput{2'000'000, 20, 1, 8191, 100, 0}}) {
    ProfileReport r = make_report(in);
    std::string svg = render_svg(r);
    SCOPED_TRACE(svg.substr(0, 400));
    XmlCheck xml(svg);  // throws on malformed XML
    const auto& els = xml.elements();
    ASSERT_FALSE(els.empty());
    EXPECT_EQ(els.front().name, "svg");
    EXPECT_EQ(els.front().attributes.at("xmlns"), "http://www.w3.org/2000/svg");
    for (const char* id : {"grid", "axes", "tick-labels", "legend"})
      EXPECT_NE(find_id(els, id), nullptr) << id;
    EXPECT_NE(svg.find(">time (ms)</text>"), std::string::npos);
    EXPECT_NE(svg.find(">velocity (pulses/s)</text>"), std::string::npos);
    EXPECT_NE(svg.find("STPCALC"), std::string::npos);
    for (const char* id : {"stpcalc", "engine"}) {
      const XmlElement* line = find_id(els, id);
      ASSERT_NE(line, nullptr) << id;
      EXPECT_EQ(line->name, "polyline");
      auto pts = points(*line);
      EXPECT_GE(pts.size(), 4u) << id;
      EXPECT_LE(pts.size(), kMaxPlotPoints) << id;
      for (auto [x, y] : pts) {  // inside the drawing
        EXPECT_GE(x, 0);
        EXPECT_LE(x, 960);
        EXPECT_GE(y, 0);
        EXPECT_LE(y, 540);
      }
      for (size_t i = 1; i < pts.size(); ++i)
        EXPECT_GE(pts[i].first, pts[i - 1].first - 1e-9) << id;
    }
  }
}

}  // namespace
}  // namespace stepnode::tools
