#include "core/io/gap_svg.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace idrig {
namespace {

struct Bar {
  std::string label;
  double value = 0;
  bool highlight = false;
};

std::string Escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else out += c;
  }
  return out;
}

std::string Format(double v) {
  std::ostringstream s;
  s.precision(3);
  s << v;
  return s.str();
}

// A vertical bar chart; an optional horizontal reference line (e.g. the noise floor).
std::string BarChart(const std::string& title, const std::string& y_label, const std::vector<Bar>& bars,
                     double reference = NAN, const std::string& reference_label = "") {
  const int width = 760, height = 420, left = 70, right = 20, top = 40, bottom = 120;
  const int plot_w = width - left - right, plot_h = height - top - bottom;
  double top_value = std::isfinite(reference) ? reference : 0.0;
  for (const auto& b : bars) top_value = std::max(top_value, b.value);
  if (!(top_value > 0)) top_value = 1;
  top_value *= 1.1;
  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
    << "\" font-family=\"sans-serif\" font-size=\"11\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << "<text x=\"" << width / 2 << "\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">" << Escape(title)
    << "</text>\n"
    << "<text transform=\"translate(16," << top + plot_h / 2 << ") rotate(-90)\" text-anchor=\"middle\">"
    << Escape(y_label) << "</text>\n"
    << "<line x1=\"" << left << "\" y1=\"" << top + plot_h << "\" x2=\"" << left + plot_w << "\" y2=\""
    << top + plot_h << "\" stroke=\"black\"/>\n"
    << "<line x1=\"" << left << "\" y1=\"" << top << "\" x2=\"" << left << "\" y2=\"" << top + plot_h
    << "\" stroke=\"black\"/>\n";
  for (int i = 0; i <= 4; ++i) {
    const double v = top_value * i / 4;
    const double y = top + plot_h - plot_h * i / 4.0;
    s << "<text x=\"" << left - 6 << "\" y=\"" << y + 4 << "\" text-anchor=\"end\">" << Format(v) << "</text>\n"
      << "<line x1=\"" << left << "\" y1=\"" << y << "\" x2=\"" << left + plot_w << "\" y2=\"" << y
      << "\" stroke=\"#ddd\"/>\n";
  }
  const double slot = bars.empty() ? plot_w : static_cast<double>(plot_w) / bars.size();
  for (size_t i = 0; i < bars.size(); ++i) {
    const double h = plot_h * std::max(0.0, bars[i].value) / top_value;
    const double x = left + slot * i + slot * 0.15;
    s << "<rect x=\"" << x << "\" y=\"" << top + plot_h - h << "\" width=\"" << slot * 0.7 << "\" height=\"" << h
      << "\" fill=\"" << (bars[i].highlight ? "#c0392b" : "#5d8aa8") << "\"><title>" << Escape(bars[i].label)
      << ": " << Format(bars[i].value) << "</title></rect>\n"
      << "<text transform=\"translate(" << x + slot * 0.35 << "," << top + plot_h + 8
      << ") rotate(40)\" text-anchor=\"start\">" << Escape(bars[i].label) << "</text>\n";
  }
  if (std::isfinite(reference)) {
    const double y = top + plot_h - plot_h * reference / top_value;
    s << "<line x1=\"" << left << "\" y1=\"" << y << "\" x2=\"" << left + plot_w << "\" y2=\"" << y
      << "\" stroke=\"#27ae60\" stroke-dasharray=\"6,4\"/>\n"
      << "<text x=\"" << left + plot_w - 4 << "\" y=\"" << y - 4 << "\" text-anchor=\"end\" fill=\"#27ae60\">"
      << Escape(reference_label) << "</text>\n";
  }
  s << "</svg>\n";
  return s.str();
}

std::vector<Bar> FactorBars(const nlohmann::json& factor, const std::string& prefix = "") {
  std::vector<Bar> bars;
  for (const auto& b : factor.at("bins"))
    bars.push_back({prefix + b.at("label").get<std::string>(), b.at("relative_rms").get<double>(), false});
  return bars;
}

// The output spectrum of a periodic odd multisine by line: excited lines (black), odd (red) and
// even (blue) detection lines, and the noise of the period mean (grey), in dB.
std::string LinesChart(const nlohmann::json& lines) {
  const int width = 760, height = 420, left = 70, right = 20, top = 40, bottom = 60;
  const int plot_w = width - left - right, plot_h = height - top - bottom;
  auto db = [](double p) { return p > 0 ? 10 * std::log10(p) : -300.0; };
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
  std::vector<Bar> bands;
  for (const auto& b : where.at("bands"))
    bands.push_back({Format(b.at("f_lo_hz").get<double>()) + "–" + Format(b.at("f_hi_hz").get<double>()) + " Hz",
                     b.at("relative_error").get<double>(), b.at("significant").get<bool>()});
  out["gap_frequency.svg"] = BarChart(
      "Gap by frequency: |model error / G0| (red: significant against the noise)",
      "median |Ê/G0| on excited lines", bands);
  const auto& factors = where.at("factors");
  const double floor = where.at("noise_nrmse").get<double>();
  if (factors.contains("amplitude"))
    out["gap_amplitude.svg"] = BarChart("Gap by input amplitude (residual RMS / simulated output RMS)",
                                        "relative RMS of y − ŷ0", FactorBars(factors["amplitude"]), floor,
                                        "noise floor (NRMSE)");
  std::vector<Bar> state;
  for (const char* name : {"velocity_sign", "reversal", "output_level"})
    if (factors.contains(name)) {
      auto bars = FactorBars(factors[name]);
      state.insert(state.end(), bars.begin(), bars.end());
    }
  out["gap_state.svg"] = BarChart("Gap by state: velocity sign, reversals, output level",
                                  "relative RMS of y − ŷ0", state, floor, "noise floor (NRMSE)");
  if (factors.contains("time"))
    out["gap_time.svg"] = BarChart("Gap over time (record quarters)", "relative RMS of y − ŷ0",
                                   FactorBars(factors["time"]), floor, "noise floor (NRMSE)");
  if (where.contains("detection_lines") && where["detection_lines"].value("available", false)) {
    const std::string svg = LinesChart(where["detection_lines"].at("lines"));
    if (!svg.empty()) out["gap_lines.svg"] = svg;
  }
  std::vector<Bar> ranking;
  const std::string verdict = report.at("verdict").at("effect_fitted").get<std::string>();
  for (const auto& c : report.at("ranking"))
    ranking.push_back({c.at("effect").get<std::string>(), c.at("nrmse_after").get<double>(),
                       c.at("effect").get<std::string>() == verdict});
  out["gap_ranking.svg"] = BarChart("Validation NRMSE with each candidate effect (red: the verdict)",
                                    "simulation NRMSE on validation data", ranking,
                                    report.at("verdict").at("nrmse_before").get<double>(), "G0 as given");
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
