#include "core/io/frf_csv.h"

#include <string_view>

#include "core/io/csv_scan.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace idrig {

namespace {
constexpr double kPi = 3.14159265358979323846;

// Fields trimmed of spaces, tabs and '\r' (csv_scan.h).
constexpr std::string_view kStrip = " \t\r";

std::vector<std::string> SplitComma(std::string_view line) {
  std::vector<std::string_view> views;
  csv::SplitFields(line, kStrip, &views);
  return std::vector<std::string>(views.begin(), views.end());
}
}  // namespace

Frf ParseFrfCsv(const std::string& text, const std::string& source) {
  csv::LineReader lines(text);
  std::string_view line;
  std::vector<std::string> header;
  while (lines.Next(&line)) {
    if (line.find_first_not_of(" \t\r") == std::string_view::npos) continue;
    header = SplitComma(line);
    break;
  }
  if (header.empty()) throw std::invalid_argument(source + ": empty file (expected a header f_hz,re,im)");
  double to_rad = 0.0;
  if (header[0] == "f_hz") to_rad = 2.0 * kPi;
  else if (header[0] == "w_rad_s") to_rad = 1.0;
  else
    throw std::invalid_argument(source + ": first column must be f_hz (Hz) or w_rad_s (rad/s), found '" +
                                header[0] + "'");
  // column -> (output, input, kind); a `sigma` column is the noise standard deviation of that
  // element, √E|e_k|² (the FRF's variance is its square).
  enum Kind { kRe = 1, kIm = 2, kSigma = 4 };
  struct Col { int out, in; Kind kind; };
  std::vector<Col> cols;
  std::map<std::pair<int, int>, int> seen;  // (out,in) -> bit mask re=1, im=2, sigma=4
  int ny = 0, nu = 0;
  bool any_sigma = false;
  for (size_t c = 1; c < header.size(); ++c) {
    const std::string& h = header[c];
    Col col{1, 1, kRe};
    const bool sigma = h.rfind("sigma", 0) == 0;
    const std::string kind = sigma ? "sigma" : h.substr(0, 2);
    if (kind != "re" && kind != "im" && !sigma)
      throw std::invalid_argument(source + ": column " + std::to_string(c + 1) + " '" + h +
                                  "' is neither re… nor im…");
    col.kind = sigma ? kSigma : kind == "im" ? kIm : kRe;
    any_sigma |= sigma;
    if (h.size() > kind.size()) {
      int o = 0, i = 0;
      char extra;
      if (std::sscanf(h.c_str() + kind.size(), "_%d_%d%c", &o, &i, &extra) != 2 || o < 1 || i < 1)
        throw std::invalid_argument(source + ": column '" + h + "' must be named " + kind +
                                    "_<output>_<input> (1-based)");
      col.out = o;
      col.in = i;
    }
    int& mask = seen[{col.out, col.in}];
    if (mask & col.kind) throw std::invalid_argument(source + ": duplicate column '" + h + "'");
    mask |= col.kind;
    ny = std::max(ny, col.out);
    nu = std::max(nu, col.in);
    cols.push_back(col);
  }
  if (cols.empty()) throw std::invalid_argument(source + ": no re/im columns after " + header[0]);
  for (int o = 1; o <= ny; ++o)
    for (int i = 1; i <= nu; ++i) {
      auto it = seen.find({o, i});
      if (it == seen.end() || (it->second & 3) != 3)
        throw std::invalid_argument(source + ": missing re/im column pair for output " + std::to_string(o) +
                                    ", input " + std::to_string(i));
      if (any_sigma && !(it->second & kSigma))
        throw std::invalid_argument(source + ": no sigma column for output " + std::to_string(o) + ", input " +
                                    std::to_string(i) + " (give the noise sigma of every element, or of none)");
    }
  std::vector<std::vector<double>> variance;  // per line, ny·nu (out + ny·in)
  std::vector<double> freq;
  Frf frf;
  std::vector<std::string_view> fields;
  std::vector<double> v(header.size());
  while (lines.Next(&line)) {
    const int line_no = lines.line_number();
    if (line.find_first_not_of(" \t\r") == std::string_view::npos) continue;
    csv::SplitFields(line, kStrip, &fields);
    if (fields.size() != header.size())
      throw std::invalid_argument(source + ":" + std::to_string(line_no) + ": " + std::to_string(fields.size()) +
                                  " fields, the header has " + std::to_string(header.size()));
    for (size_t c = 0; c < fields.size(); ++c) {
      if (!csv::ParseDouble(fields[c], &v[c]))
        throw std::invalid_argument(source + ":" + std::to_string(line_no) + ": field " + std::to_string(c + 1) +
                                    " '" + std::string(fields[c]) + "' is not a number");
      if (!std::isfinite(v[c]))
        throw std::invalid_argument(source + ":" + std::to_string(line_no) + ": field " + std::to_string(c + 1) +
                                    " is NaN or Inf");
    }
    freq.push_back(v[0] * to_rad);
    Eigen::MatrixXcd h = Eigen::MatrixXcd::Zero(ny, nu);
    if (any_sigma) variance.emplace_back(ny * nu, 0.0);
    for (size_t c = 1; c < v.size(); ++c) {
      const Col& col = cols[c - 1];
      auto& z = h(col.out - 1, col.in - 1);
      if (col.kind == kSigma) {
        if (!(v[c] > 0.0))
          throw std::invalid_argument(source + ":" + std::to_string(line_no) + ": field " + std::to_string(c + 1) +
                                      " (" + header[c] + ") must be > 0: a noise sigma");
        variance.back()[(col.out - 1) + ny * (col.in - 1)] = v[c] * v[c];
      } else {
        z = col.kind == kIm ? std::complex<double>(z.real(), v[c]) : std::complex<double>(v[c], z.imag());
      }
    }
    frf.h.push_back(h);
  }
  if (freq.empty()) throw std::invalid_argument(source + ": no data rows");
  frf.omega = Eigen::Map<Eigen::VectorXd>(freq.data(), freq.size());
  if (any_sigma) {
    frf.variance.resize(static_cast<long>(variance.size()), ny * nu);
    for (size_t k = 0; k < variance.size(); ++k)
      for (int e = 0; e < ny * nu; ++e) frf.variance(static_cast<long>(k), e) = variance[k][e];
  }
  return frf;
}

Frf ReadFrfCsv(const std::string& path) {
  return ParseFrfCsv(csv::ReadFile(path, "cannot read '" + path + "'"), path);
}

void WriteFrfCsv(const Frf& frf, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write '" + path + "'");
  const int ny = frf.NumOutputs(), nu = frf.NumInputs();
  const bool siso = ny == 1 && nu == 1;
  out << "f_hz";
  for (int i = 0; i < nu; ++i)
    for (int o = 0; o < ny; ++o) {
      const std::string suffix = siso ? "" : "_" + std::to_string(o + 1) + "_" + std::to_string(i + 1);
      out << ",re" << suffix << ",im" << suffix;
      if (frf.variance.size()) out << ",sigma" << suffix;
    }
  out << "\n" << std::setprecision(17);
  for (int k = 0; k < frf.NumLines(); ++k) {
    out << frf.omega(k) / (2.0 * kPi);
    for (int i = 0; i < nu; ++i)
      for (int o = 0; o < ny; ++o) {
        out << "," << frf.h[k](o, i).real() << "," << frf.h[k](o, i).imag();
        if (frf.variance.size()) out << "," << std::sqrt(frf.variance(k, o + ny * i));
      }
    out << "\n";
  }
  if (!out) throw std::runtime_error("write to '" + path + "' failed");
}

bool IsTimeRecordCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("cannot read '" + path + "'");
  std::string line;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) break;
  const auto fields = SplitComma(line);
  return !fields.empty() && fields[0] == "t";
}

}  // namespace idrig
