#include "core/io/gap_svg.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "core/io/svg_plot.h"

namespace idrig {
namespace {

std::string Format(double v) {
  std::ostringstream s;
  s.precision(3);
  s << v;
  return s.str();
}

std::vector<BarItem> FactorBars(const nlohmann::json& factor) {
  std::vector<BarItem> bars;
  for (const auto& b : factor.at("bins"))
    bars.push_back({b.at("label").get<std::string>(), b.at("relative_rms").get<double>(), 0});
  return bars;
}

// A bar chart of the gap (relative RMS of the residual y − ŷ0 per bin) against the noise floor.
std::string FactorChart(const std::string& title, const std::string& x_label,
                        std::vector<BarItem> bars, double floor) {
  BarChart c;
  c.title = title;
  c.x_label = x_label;
  c.y = {"relative RMS of y − ŷ0 (residual / simulated output)", "1"};
  c.bars = std::move(bars);
  c.groups = {"gap in this bin"};
  c.has_reference = true;
  c.reference = floor;
  c.reference_label = "noise floor (NRMSE)";
  return BarChartSvg(c);
}

// The output spectrum of a periodic odd multisine by line: excited lines (black), odd (red) and
// even (blue) detection lines, and the noise of the period mean (grey), in dB.
std::string LinesChart(const nlohmann::json& lines) {
  const int width = 760, height = 420, left = 70, right = 20, top = 40, bottom = 60;
  const int plot_w = width - left - right, plot_h = height - top - bottom;
  double f_max = 0, hi = -300, lo = 300;
  for (const auto& l : lines) {
    f_max = std::max(f_max, l.at("f_hz").get<double>());
    for (const char* key : {"y_db", "noise_db"}) {
      const double v = l.at(key).get<double>();
      if (v > -290) hi = std::max(hi, v), lo = std::min(lo, v);
    }
  }
  if (!(f_max > 0) || !(hi > lo)) return "";
  lo = std::max(lo, hi - 120);
  auto px = [&](double f) { return left + plot_w * f / f_max; };
  auto py = [&](double v) { return top + plot_h * (hi - std::max(v, lo)) / (hi - lo); };
  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
    << "\" font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << "<text x=\"" << width / 2 << "\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">"
    << "Output by line: excited (black), odd (red) and even (blue) detection lines, noise (grey)</text>\n"
    << "<line x1=\"" << left << "\" y1=\"" << top + plot_h << "\" x2=\"" << left + plot_w << "\" y2=\""
    << top + plot_h << "\" stroke=\"black\"/>\n<line x1=\"" << left << "\" y1=\"" << top << "\" x2=\"" << left
    << "\" y2=\"" << top + plot_h << "\" stroke=\"black\"/>\n"
    << "<text x=\"" << left + plot_w / 2 << "\" y=\"" << height - 20 << "\" text-anchor=\"middle\">frequency [Hz] (0 – "
    << Format(f_max) << ")</text>\n<text transform=\"translate(16," << top + plot_h / 2
    << ") rotate(-90)\" text-anchor=\"middle\">|Y|² [dB]</text>\n";
  for (int i = 0; i <= 4; ++i) {
    const double v = lo + (hi - lo) * i / 4;
    s << "<text x=\"" << left - 6 << "\" y=\"" << py(v) + 4 << "\" text-anchor=\"end\">" << Format(v) << "</text>\n";
  }
  for (const auto& l : lines) {
    const std::string kind = l.at("kind").get<std::string>();
    const char* colour = kind == "excited" ? "black" : (kind == "odd" ? "#c0392b" : "#2e86c1");
    const double x = px(l.at("f_hz").get<double>());
    s << "<circle cx=\"" << x << "\" cy=\"" << py(l.at("noise_db").get<double>()) << "\" r=\"1.5\" fill=\"#aaa\"/>"
      << "<circle cx=\"" << x << "\" cy=\"" << py(l.at("y_db").get<double>()) << "\" r=\"2.5\" fill=\"" << colour
      << "\"/>\n";
  }
  s << "</svg>\n";
  return s.str();
}

}  // namespace

std::map<std::string, std::string> GapReportSvgs(const nlohmann::json& report) {
  std::map<std::string, std::string> out;
  const auto& where = report.at("where");
  BarChart bands;
  bands.title = "Where: gap by frequency band, |model error / G0| on excited lines";
  bands.x_label = "frequency band [Hz]";
  bands.y = {"median |Ê/G0|", "1"};
  bands.groups = {"within the noise", "significant against the noise"};
  for (const auto& b : where.at("bands"))
    bands.bars.push_back({Format(b.at("f_lo_hz").get<double>()) + "–" +
                              Format(b.at("f_hi_hz").get<double>()) + " Hz",
                          b.at("relative_error").get<double>(), b.at("significant").get<bool>() ? 1 : 0});
  out["gap_frequency.svg"] = BarChartSvg(bands);
  const auto& factors = where.at("factors");
  const double floor = where.at("noise_nrmse").get<double>();
  if (factors.contains("amplitude"))
    out["gap_amplitude.svg"] = FactorChart("Where: gap by input amplitude", "input amplitude bin",
                                           FactorBars(factors["amplitude"]), floor);
  std::vector<BarItem> state;
  for (const char* name : {"velocity_sign", "reversal", "output_level"})
    if (factors.contains(name)) {
      auto bars = FactorBars(factors[name]);
      state.insert(state.end(), bars.begin(), bars.end());
    }
  out["gap_state.svg"] = FactorChart("Where: gap by state (velocity sign, reversals, output level)",
                                     "state bin", state, floor);
  if (factors.contains("time"))
    out["gap_time.svg"] = FactorChart("Where: gap over time", "record quarter",
                                      FactorBars(factors["time"]), floor);
  if (where.contains("detection_lines") && where["detection_lines"].value("available", false)) {
    const std::string svg = LinesChart(where["detection_lines"].at("lines"));
    if (!svg.empty()) out["gap_lines.svg"] = svg;
  }
  BarChart ranking;
  ranking.title = "Which, and how far: validation NRMSE with each candidate effect added";
  ranking.x_label = "candidate effect";
  ranking.y = {"simulation NRMSE on validation data", "1"};
  ranking.groups = {"candidate", "the verdict"};
  const std::string verdict = report.at("verdict").at("effect_fitted").get<std::string>();
  for (const auto& c : report.at("ranking"))
    ranking.bars.push_back({c.at("effect").get<std::string>(), c.at("nrmse_after").get<double>(),
                            c.at("effect").get<std::string>() == verdict ? 1 : 0});
  ranking.has_reference = true;
  ranking.reference = report.at("verdict").at("nrmse_before").get<double>();
  ranking.reference_label = "G0 as given";
  out["gap_ranking.svg"] = BarChartSvg(ranking);
  return out;
}

std::vector<std::string> WriteGapReportSvgs(const nlohmann::json& report, const std::string& directory) {
  std::filesystem::create_directories(directory);
  std::vector<std::string> written;
  for (const auto& [name, svg] : GapReportSvgs(report)) {
    const std::string path = (std::filesystem::path(directory) / name).string();
    std::ofstream file(path);
    if (!file) throw std::invalid_argument("cannot write " + path);
    file << svg;
    written.push_back(path);
  }
  return written;
}

}  // namespace idrig
