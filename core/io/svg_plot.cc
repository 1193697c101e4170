#include "core/io/svg_plot.h"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace idrig {
namespace {

// Colour-blind-safe palette (Okabe–Ito).
const char* const kColours[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                "#E69F00", "#56B4E9", "#000000", "#F0E442"};
const char* Colour(size_t i) { return kColours[i % (sizeof(kColours) / sizeof(kColours[0]))]; }

std::string Escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else if (c == '"') out += "&quot;";
    else out += c;
  }
  return out;
}

std::string Format(double v, int precision = 4) {
  if (std::abs(v) < 1e-300) return "0";
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

// Long category labels are cut (the whole label stays in the bar's tooltip).
std::string Shorten(const std::string& text, size_t max_chars) {
  size_t chars = 0, i = 0;
  for (; i < text.size(); ++i)
    if ((static_cast<unsigned char>(text[i]) & 0xC0) != 0x80 && ++chars > max_chars) break;
  return i < text.size() ? text.substr(0, i) + "…" : text;
}

std::string AxisTitle(const PlotAxis& a) {
  return a.unit.empty() ? a.label : a.label + " [" + a.unit + "]";
}

// Maps data values to pixels on one axis (linear or log10).
struct Scale {
  double lo = 0, hi = 1, p0 = 0, p1 = 1;
  bool log = false;
  double operator()(double v) const {
    const double a = log ? std::log10(v) : v, l = log ? std::log10(lo) : lo,
                 h = log ? std::log10(hi) : hi;
    return p0 + (p1 - p0) * (a - l) / (h - l);
  }
};

std::vector<std::pair<double, std::string>> AxisTicks(const PlotAxis& axis, double lo, double hi) {
  if (!axis.ticks.empty()) return axis.ticks;
  if (axis.time) return TimeTicks(lo, hi);
  std::vector<std::pair<double, std::string>> out;
  if (axis.log) {
    for (int e = static_cast<int>(std::floor(std::log10(lo))); e <= std::ceil(std::log10(hi)); ++e) {
      const double v = std::pow(10.0, e);
      if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) out.push_back({v, Format(v)});
    }
    if (out.size() < 2) {
      out.clear();
      for (double v : NiceTicks(lo, hi)) if (v > 0) out.push_back({v, Format(v)});
    }
    return out;
  }
  for (double v : NiceTicks(lo, hi)) out.push_back({v, Format(v)});
  return out;
}

void Frame(std::ostringstream& s, int width, int height, const std::string& title) {
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
    << "\" viewBox=\"0 0 " << width << " " << height
    << "\" font-family=\"sans-serif\" font-size=\"11\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << "<text x=\"" << width / 2 << "\" y=\"20\" text-anchor=\"middle\" font-size=\"14\">"
    << Escape(title) << "</text>\n";
}

void Legend(std::ostringstream& s, const std::vector<std::string>& names,
            const std::vector<std::string>& dashes, double x, double y) {
  for (size_t i = 0; i < names.size(); ++i) {
    const double yy = y + 16.0 * i;
    s << "<g class=\"legend\"><line x1=\"" << x << "\" y1=\"" << yy << "\" x2=\"" << x + 22
      << "\" y2=\"" << yy << "\" stroke=\"" << Colour(i) << "\" stroke-width=\"2\""
      << (i < dashes.size() && !dashes[i].empty() ? " stroke-dasharray=\"" + dashes[i] + "\"" : "")
      << "/><circle cx=\"" << x + 11 << "\" cy=\"" << yy << "\" r=\"3\" fill=\"" << Colour(i)
      << "\"/><text x=\"" << x + 28 << "\" y=\"" << yy + 4 << "\">" << Escape(names[i])
      << "</text></g>\n";
  }
}

}  // namespace

std::vector<double> NiceTicks(double lo, double hi, int target) {
  if (!(hi > lo)) return {lo};
  const double raw = (hi - lo) / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * mag >= raw * (1 - 1e-9)) {
      step = m * mag;
      break;
    }
  std::vector<double> out;
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + step * 1e-9; v += step)
    out.push_back(std::abs(v) < step * 1e-9 ? 0.0 : v);
  return out;
}

std::string UtcText(double unix_s) {
  const std::time_t t = static_cast<std::time_t>(std::floor(unix_s));
  char buffer[32];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%d %H:%M:%S", std::gmtime(&t));
  return buffer;
}

std::vector<std::pair<double, std::string>> TimeTicks(double lo, double hi, int target) {
  static const double kSteps[] = {0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1, 2,
                                  5,     10,    15,    30,   60,   120,  300, 600, 900, 1800,
                                  3600,  7200,  10800, 21600, 43200, 86400, 172800, 604800,
                                  2592000, 31536000};
  const double span = std::max(hi - lo, 1e-3);
  double step = kSteps[sizeof(kSteps) / sizeof(kSteps[0]) - 1];
  for (double s : kSteps)
    if (span / s <= target) {
      step = s;
      break;
    }
  std::vector<std::pair<double, std::string>> out;
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + 1e-9 * step; v += step) {
    std::string text = UtcText(v);  // "YYYY-MM-DD HH:MM:SS"
    if (step < 1) {
      std::ostringstream frac;
      frac.precision(3);
      frac << std::fixed << (v - std::floor(v));
      text = text.substr(11) + frac.str().substr(1);  // HH:MM:SS.mmm
    } else if (step < 60) {
      text = text.substr(11);  // HH:MM:SS
    } else if (step < 86400) {
      text = text.substr(5, 11);  // MM-DD HH:MM
    } else {
      text = text.substr(0, 10);  // YYYY-MM-DD
    }
    out.push_back({v, text});
  }
  return out;
}

std::string LinePlotSvg(const LinePlot& plot) {
  double xlo = std::numeric_limits<double>::infinity(), xhi = -xlo, ylo = xlo, yhi = -xlo;
  for (const auto& series : plot.series) {
    if (series.x.size() != series.y.size())
      throw std::invalid_argument("plot series '" + series.name + "': " +
                                  std::to_string(series.x.size()) + " x values but " +
                                  std::to_string(series.y.size()) + " y values");
    for (size_t i = 0; i < series.x.size(); ++i) {
      const double x = series.x[i], y = series.y[i];
      if (!std::isfinite(x) || !std::isfinite(y)) continue;
      if ((plot.x.log && x <= 0) || (plot.y.log && y <= 0))
        throw std::invalid_argument("plot '" + plot.title + "': a value <= 0 on a log axis");
      xlo = std::min(xlo, x), xhi = std::max(xhi, x), ylo = std::min(ylo, y), yhi = std::max(yhi, y);
    }
  }
  if (!std::isfinite(xlo)) throw std::invalid_argument("plot '" + plot.title + "': no finite point");
  for (const auto& [v, label] : plot.x.ticks) xlo = std::min(xlo, v), xhi = std::max(xhi, v);
  // Pad so that single points and flat lines have a visible range.
  auto pad = [](double& lo, double& hi, bool log, double minimum) {
    if (log) {
      if (hi / lo < 1.5) lo /= 1.25, hi *= 1.25;
      return;
    }
    const double span = hi - lo;
    if (span < minimum) {
      const double c = 0.5 * (lo + hi), half = std::max(minimum, std::abs(c) * 0.05) / 2;
      lo = c - half, hi = c + half;
    } else {
      lo -= 0.05 * span, hi += 0.05 * span;
    }
  };
  pad(xlo, xhi, plot.x.log, plot.x.time ? 2.0 : 1e-12);
  pad(ylo, yhi, plot.y.log, 1e-12);

  const int left = 78, right = 20 + 0, top = 36, bottom = 70;
  const int legend_h = 16 * static_cast<int>(plot.series.size());
  const int plot_w = plot.width - left - right, plot_h = plot.height - top - bottom - legend_h;
  const Scale sx{xlo, xhi, static_cast<double>(left), static_cast<double>(left + plot_w), plot.x.log};
  const Scale sy{ylo, yhi, static_cast<double>(top + plot_h), static_cast<double>(top), plot.y.log};
  std::ostringstream s;
  Frame(s, plot.width, plot.height, plot.title);
  s << "<rect class=\"plot-area\" x=\"" << left << "\" y=\"" << top << "\" width=\"" << plot_w
    << "\" height=\"" << plot_h << "\" fill=\"none\" stroke=\"black\"/>\n";
  for (const auto& [v, label] : AxisTicks(plot.y, ylo, yhi)) {
    const double y = sy(v);
    s << "<line x1=\"" << left << "\" y1=\"" << y << "\" x2=\"" << left + plot_w << "\" y2=\"" << y
      << "\" stroke=\"#e0e0e0\"/><text class=\"tick\" x=\"" << left - 5 << "\" y=\"" << y + 4
      << "\" text-anchor=\"end\">" << Escape(label) << "</text>\n";
  }
  const auto x_ticks = AxisTicks(plot.x, xlo, xhi);
  const bool rotate = x_ticks.size() > 5 && (plot.x.time || !plot.x.ticks.empty());
  for (const auto& [v, label] : x_ticks) {
    if (v < xlo || v > xhi) continue;
    const double x = sx(v);
    s << "<line x1=\"" << x << "\" y1=\"" << top << "\" x2=\"" << x << "\" y2=\"" << top + plot_h
      << "\" stroke=\"#e0e0e0\"/><text class=\"tick\" text-anchor=\"" << (rotate ? "end" : "middle")
      << "\" transform=\"translate(" << x << "," << top + plot_h + 14 << ")"
      << (rotate ? " rotate(-25)" : "") << "\">" << Escape(label) << "</text>\n";
  }
  std::string x_title = AxisTitle(plot.x);
  if (plot.x.time && plot.x.unit.empty())
    x_title += " (UTC, " + UtcText(xlo).substr(0, 10) + " .. " + UtcText(xhi).substr(0, 10) + ")";
  s << "<text class=\"axis-label\" x=\"" << left + plot_w / 2 << "\" y=\"" << top + plot_h + 50
    << "\" text-anchor=\"middle\">" << Escape(x_title) << "</text>\n"
    << "<text class=\"axis-label\" transform=\"translate(16," << top + plot_h / 2
    << ") rotate(-90)\" text-anchor=\"middle\">" << Escape(AxisTitle(plot.y)) << "</text>\n";
  std::vector<std::string> names, dashes;
  for (size_t k = 0; k < plot.series.size(); ++k) {
    const auto& series = plot.series[k];
    names.push_back(series.name);
    dashes.push_back(series.dash);
    std::ostringstream points;
    int n = 0;
    for (size_t i = 0; i < series.x.size(); ++i)
      if (std::isfinite(series.x[i]) && std::isfinite(series.y[i])) {
        points << sx(series.x[i]) << "," << sy(series.y[i]) << " ";
        ++n;
      }
    s << "<g class=\"series\" data-name=\"" << Escape(series.name) << "\">";
    if (series.line && n > 1)
      s << "<polyline fill=\"none\" stroke=\"" << Colour(k) << "\" stroke-width=\"1.6\""
        << (series.dash.empty() ? "" : " stroke-dasharray=\"" + series.dash + "\"") << " points=\""
        << points.str() << "\"/>";
    if (series.markers)
      for (size_t i = 0; i < series.x.size(); ++i) {
        if (!std::isfinite(series.x[i]) || !std::isfinite(series.y[i])) continue;
        s << "\n<circle cx=\"" << sx(series.x[i]) << "\" cy=\"" << sy(series.y[i])
          << "\" r=\"3.5\" fill=\"" << Colour(k) << "\"><title>"
          << Escape(i < series.tips.size() ? series.tips[i]
                                           : series.name + ": " + Format(series.y[i], 6))
          << "</title></circle>";
      }
    s << "</g>\n";
  }
  Legend(s, names, dashes, left + 8, top + plot_h + 64);
  s << "</svg>\n";
  return s.str();
}

std::string BarChartSvg(const BarChart& chart) {
  const int left = 78, right = 20, top = 36, bottom = 130;
  const int legend_h = 16 * static_cast<int>(chart.groups.size() + (chart.has_reference ? 1 : 0));
  const int plot_w = chart.width - left - right, plot_h = chart.height - top - bottom - legend_h;
  double hi = chart.has_reference ? chart.reference : 0.0;
  for (const auto& b : chart.bars) hi = std::max(hi, b.value);
  if (!(hi > 0)) hi = 1;
  hi *= 1.1;
  const Scale sy{0.0, hi, static_cast<double>(top + plot_h), static_cast<double>(top), false};
  std::ostringstream s;
  Frame(s, chart.width, chart.height, chart.title);
  s << "<rect class=\"plot-area\" x=\"" << left << "\" y=\"" << top << "\" width=\"" << plot_w
    << "\" height=\"" << plot_h << "\" fill=\"none\" stroke=\"black\"/>\n";
  for (double v : NiceTicks(0.0, hi)) {
    const double y = sy(v);
    s << "<line x1=\"" << left << "\" y1=\"" << y << "\" x2=\"" << left + plot_w << "\" y2=\"" << y
      << "\" stroke=\"#e0e0e0\"/><text class=\"tick\" x=\"" << left - 5 << "\" y=\"" << y + 4
      << "\" text-anchor=\"end\">" << Format(v, 3) << "</text>\n";
  }
  const double slot = chart.bars.empty() ? plot_w : static_cast<double>(plot_w) / chart.bars.size();
  for (size_t i = 0; i < chart.bars.size(); ++i) {
    const auto& b = chart.bars[i];
    const double h = sy(0.0) - sy(std::max(0.0, b.value));
    const double x = left + slot * i + slot * 0.15;
    s << "<rect class=\"bar\" x=\"" << x << "\" y=\"" << sy(0.0) - h << "\" width=\"" << slot * 0.7
      << "\" height=\"" << h << "\" fill=\"" << Colour(b.group) << "\"><title>" << Escape(b.label)
      << ": " << Format(b.value, 4) << "</title></rect>\n"
      << "<text class=\"tick\" transform=\"translate(" << x + slot * 0.35 << "," << top + plot_h + 10
      << ") rotate(40)\">" << Escape(Shorten(b.label, 26)) << "</text>\n";
  }
  if (chart.has_reference) {
    const double y = sy(chart.reference);
    s << "<line x1=\"" << left << "\" y1=\"" << y << "\" x2=\"" << left + plot_w << "\" y2=\"" << y
      << "\" stroke=\"#555\" stroke-dasharray=\"6,4\"/>\n";
  }
  s << "<text class=\"axis-label\" x=\"" << left + plot_w / 2 << "\" y=\"" << top + plot_h + 110
    << "\" text-anchor=\"middle\">" << Escape(chart.x_label) << "</text>\n"
    << "<text class=\"axis-label\" transform=\"translate(16," << top + plot_h / 2
    << ") rotate(-90)\" text-anchor=\"middle\">" << Escape(AxisTitle(chart.y)) << "</text>\n";
  const double ly = top + plot_h + 124;
  for (size_t g = 0; g < chart.groups.size(); ++g)
    s << "<g class=\"legend\"><rect x=\"" << left + 8 << "\" y=\"" << ly + 16 * g - 5
      << "\" width=\"14\" height=\"10\" fill=\"" << Colour(g) << "\"/><text x=\"" << left + 28
      << "\" y=\"" << ly + 16 * g + 4 << "\">" << Escape(chart.groups[g]) << "</text></g>\n";
  if (chart.has_reference)
    s << "<g class=\"legend\"><line x1=\"" << left + 8 << "\" y1=\"" << ly + 16 * chart.groups.size()
      << "\" x2=\"" << left + 22 << "\" y2=\"" << ly + 16 * chart.groups.size()
      << "\" stroke=\"#555\" stroke-dasharray=\"6,4\"/><text x=\"" << left + 28 << "\" y=\""
      << ly + 16 * chart.groups.size() + 4 << "\">" << Escape(chart.reference_label)
      << " (" << Format(chart.reference, 3) << ")</text></g>\n";
  s << "</svg>\n";
  return s.str();
}

}  // namespace idrig
