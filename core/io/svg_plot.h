#pragma once
// The one SVG plotting helper of the command line: line/marker plots and bar charts with a
// title, axes, ticks, axis labels with units, a legend, and readable time labels (UTC dates)
// on a time axis. Every SVG idrig writes (models history, gap report plots) goes through it.
// Plain SVG 1.1 text, viewable in any browser; text is XML-escaped.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace idrig {

struct PlotAxis {
  PlotAxis(std::string label_ = "", std::string unit_ = "", bool time_ = false, bool log_ = false)
      : label(std::move(label_)), unit(std::move(unit_)), time(time_), log(log_) {}
  std::string label;  // e.g. "natural frequency ω_n,1"
  std::string unit;   // e.g. "rad/s"; shown as "label [unit]"
  bool time = false;  // values are Unix seconds: ticks are UTC dates and times
  bool log = false;   // logarithmic (values must be > 0)
  // Explicit ticks (value, label) instead of computed ones (e.g. a storage-order axis).
  std::vector<std::pair<double, std::string>> ticks;
};

struct PlotSeries {
  PlotSeries(std::string name_ = "", std::vector<double> x_ = {}, std::vector<double> y_ = {})
      : name(std::move(name_)), x(std::move(x_)), y(std::move(y_)) {}
  std::string name;          // legend entry
  std::vector<double> x, y;  // same length; non-finite points are skipped
  bool line = true, markers = true;
  std::string dash;               // SVG stroke-dasharray, e.g. "6,3"; empty: solid
  std::vector<std::string> tips;  // optional tooltip per point (SVG <title>)
};

struct LinePlot {
  std::string title;
  PlotAxis x, y;
  std::vector<PlotSeries> series;
  int width = 760, height = 420;
};

// Throws std::invalid_argument when there is no finite point to draw, x and y lengths differ,
// or a log axis gets a value <= 0.
std::string LinePlotSvg(const LinePlot& plot);

struct BarItem {
  std::string label;
  double value = 0.0;
  int group = 0;  // index into BarChart::groups (colour and legend entry)
};

struct BarChart {
  std::string title;
  PlotAxis y;                       // value axis (label and unit)
  std::string x_label;              // category axis label
  std::vector<BarItem> bars;
  std::vector<std::string> groups;  // legend entries, one colour each
  double reference = 0.0;           // optional dashed reference line (e.g. a noise floor)
  bool has_reference = false;
  std::string reference_label;
  int width = 760, height = 440;
};

std::string BarChartSvg(const BarChart& chart);

// "Nice" tick positions (1, 2, 5 × 10^k) covering [lo, hi], about `target` of them.
std::vector<double> NiceTicks(double lo, double hi, int target = 6);
// Time ticks [Unix s] on round seconds/minutes/hours/days covering [lo, hi], with labels
// whose precision fits the span (e.g. "12-01 17:40" or "17:40:05").
std::vector<std::pair<double, std::string>> TimeTicks(double lo, double hi, int target = 6);
// "2026-12-01 17:40:05" (UTC) for Unix seconds.
std::string UtcText(double unix_s);

}  // namespace idrig
