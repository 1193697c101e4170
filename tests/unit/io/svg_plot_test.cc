// The shared SVG plotting helper: ticks, time labels, axes with units, a legend entry and a
// line per series, and the errors it names.
#include "core/io/svg_plot.h"

#include <gtest/gtest.h>

#include <regex>

namespace idrig {
namespace {

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

TEST(SvgPlot, NiceTicksAreRoundAndCoverTheRange) {
  const auto t = NiceTicks(0.0, 1.0, 5);
  ASSERT_EQ(t.size(), 6u);  // 0, 0.2, ..., 1
  EXPECT_DOUBLE_EQ(t.front(), 0.0);
  EXPECT_NEAR(t.back(), 1.0, 1e-12);
  EXPECT_NEAR(t[1], 0.2, 1e-12);
  const auto u = NiceTicks(0.47, 0.53, 6);  // step 0.01
  EXPECT_NEAR(u[1] - u[0], 0.01, 1e-12);
  EXPECT_GE(u.front(), 0.47 - 1e-12);
  EXPECT_LE(u.back(), 0.53 + 1e-12);
}

TEST(SvgPlot, TimeTicksHaveReadableUtcLabels) {
  // 2026-12-01 17:00:00 UTC = 1796144400 s (date -u -d '2026-12-01 17:00:00' +%s).
  const double t0 = 1796144400.0;
  EXPECT_EQ(UtcText(t0), "2026-12-01 17:00:00");
  const auto hour = TimeTicks(t0, t0 + 3600, 6);  // every 10 min, labelled MM-DD HH:MM
  ASSERT_GE(hour.size(), 4u);
  EXPECT_EQ(hour.front().second, "12-01 17:00");
  EXPECT_DOUBLE_EQ(hour[1].first - hour[0].first, 600.0);
  const auto seconds = TimeTicks(t0 + 0.2, t0 + 0.9, 6);  // sub-second: HH:MM:SS.mmm
  ASSERT_FALSE(seconds.empty());
  EXPECT_TRUE(std::regex_match(seconds.front().second, std::regex("17:00:00\\.[0-9]{3}")))
      << seconds.front().second;
}

TEST(SvgPlot, LinePlotHasAxesUnitsLegendAndOneLinePerSeries) {
  LinePlot p;
  p.title = "wn_1 of rig sim1";
  p.x = {"time stored", "", true};
  p.y = {"natural frequency", "rad/s"};
  p.series = {{"arx", {1796144400, 1796145000, 1796145600}, {0.5, 0.51, 0.49}},
              {"arx-oe", {1796144400.1, 1796145000.1}, {0.5, 0.5}}};
  const std::string svg = LinePlotSvg(p);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_EQ(Count(svg, "<polyline"), 2);
  EXPECT_EQ(Count(svg, "<circle"), 5 + 2);  // points + legend markers
  EXPECT_EQ(Count(svg, "class=\"legend\""), 2);
  EXPECT_NE(svg.find(">arx-oe</text>"), std::string::npos);
  EXPECT_NE(svg.find("natural frequency [rad/s]"), std::string::npos);
  EXPECT_NE(svg.find("12-01 17:"), std::string::npos);  // time tick labels
  EXPECT_NE(svg.find("UTC, 2026-12-01"), std::string::npos);
  EXPECT_GE(Count(svg, "class=\"tick\""), 6);
}

TEST(SvgPlot, BadInputIsNamed) {
  LinePlot p;
  p.title = "empty";
  p.series = {{"a", {}, {}}};
  EXPECT_THROW(LinePlotSvg(p), std::invalid_argument);
  p.series = {{"a", {1, 2}, {1}}};
  try {
    LinePlotSvg(p);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("2 x values but 1 y values"), std::string::npos);
  }
  p.series = {{"a", {1, 2}, {0, 1}}};
  p.y.log = true;
  EXPECT_THROW(LinePlotSvg(p), std::invalid_argument);
}

TEST(SvgPlot, BarChartHasLegendAndReference) {
  BarChart c;
  c.title = "gap";
  c.y = {"relative RMS", "1"};
  c.x_label = "band";
  c.groups = {"within noise", "significant"};
  c.bars = {{"0-1 Hz", 0.1, 0}, {"1-2 Hz", 0.4, 1}};
  c.has_reference = true;
  c.reference = 0.05;
  c.reference_label = "noise floor";
  const std::string svg = BarChartSvg(c);
  EXPECT_EQ(Count(svg, "class=\"bar\""), 2);
  EXPECT_EQ(Count(svg, "class=\"legend\""), 3);
  EXPECT_NE(svg.find("relative RMS [1]"), std::string::npos);
  EXPECT_NE(svg.find("noise floor (0.05)"), std::string::npos);
}

}  // namespace
}  // namespace idrig
