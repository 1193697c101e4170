#include "core/io/frf_csv.h"

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

std::vector<std::string> SplitComma(const std::string& line) {
  std::vector<std::string> out;
  std::string field;
  std::stringstream ss(line);
  while (std::getline(ss, field, ',')) {
    while (!field.empty() && (field.back() == '\r' || field.back() == ' ')) field.pop_back();
    while (!field.empty() && field.front() == ' ') field.erase(field.begin());
    out.push_back(field);
  }
  if (!line.empty() && line.back() == ',') out.push_back("");
  return out;
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("cannot read '" + path + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
}  // namespace

Frf ParseFrfCsv(const std::string& text, const std::string& source) {
  std::stringstream in(text);
  std::string line;
  int line_no = 0;
  std::vector<std::string> header;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
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
  // column -> (output, input, is_imag)
  struct Col { int out, in; bool imag; };
  std::vector<Col> cols;
  std::map<std::pair<int, int>, int> seen;  // (out,in) -> bit mask re=1, im=2
  int ny = 0, nu = 0;
  for (size_t c = 1; c < header.size(); ++c) {
    const std::string& h = header[c];
    Col col{1, 1, false};
    std::string kind = h.substr(0, 2);
    if (kind != "re" && kind != "im")
      throw std::invalid_argument(source + ": column " + std::to_string(c + 1) + " '" + h +
                                  "' is neither re… nor im…");
    col.imag = kind == "im";
    if (h.size() > 2) {
      int o = 0, i = 0;
      char extra;
      if (std::sscanf(h.c_str() + 2, "_%d_%d%c", &o, &i, &extra) != 2 || o < 1 || i < 1)
        throw std::invalid_argument(source + ": column '" + h + "' must be named " + kind +
                                    "_<output>_<input> (1-based)");
      col.out = o;
      col.in = i;
    }
    int& mask = seen[{col.out, col.in}];
    const int bit = col.imag ? 2 : 1;
    if (mask & bit) throw std::invalid_argument(source + ": duplicate column '" + h + "'");
    mask |= bit;
    ny = std::max(ny, col.out);
    nu = std::max(nu, col.in);
    cols.push_back(col);
  }
  if (cols.empty()) throw std::invalid_argument(source + ": no re/im columns after " + header[0]);
  for (int o = 1; o <= ny; ++o)
    for (int i = 1; i <= nu; ++i) {
      auto it = seen.find({o, i});
      if (it == seen.end() || it->second != 3)
        throw std::invalid_argument(source + ": missing re/im column pair for output " + std::to_string(o) +
                                    ", input " + std::to_string(i));
    }
  std::vector<double> freq;
  Frf frf;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const auto fields = SplitComma(line);
    if (fields.size() != header.size())
      throw std::invalid_argument(source + ":" + std::to_string(line_no) + ": " + std::to_string(fields.size()) +
                                  " fields, the header has " + std::to_string(header.size()));
    std::vector<double> v(fields.size());
    for (size_t c = 0; c < fields.size(); ++c) {
      char* end = nullptr;
      v[c] = std::strtod(fields[c].c_str(), &end);
      if (fields[c].empty() || *end != '\0')
        throw std::invalid_argument(source + ":" + std::to_string(line_no) + ": field " + std::to_string(c + 1) +
                                    " '" + fields[c] + "' is not a number");
      if (!std::isfinite(v[c]))
        throw std::invalid_argument(source + ":" + std::to_string(line_no) + ": field " + std::to_string(c + 1) +
                                    " is NaN or Inf");
    }
    freq.push_back(v[0] * to_rad);
    Eigen::MatrixXcd h = Eigen::MatrixXcd::Zero(ny, nu);
    for (size_t c = 1; c < v.size(); ++c) {
      const Col& col = cols[c - 1];
      auto& z = h(col.out - 1, col.in - 1);
      z = col.imag ? std::complex<double>(z.real(), v[c]) : std::complex<double>(v[c], z.imag());
    }
    frf.h.push_back(h);
  }
  if (freq.empty()) throw std::invalid_argument(source + ": no data rows");
  frf.omega = Eigen::Map<Eigen::VectorXd>(freq.data(), freq.size());
  return frf;
}

Frf ReadFrfCsv(const std::string& path) { return ParseFrfCsv(ReadAll(path), path); }

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
    }
  out << "\n" << std::setprecision(17);
  for (int k = 0; k < frf.NumLines(); ++k) {
    out << frf.omega(k) / (2.0 * kPi);
    for (int i = 0; i < nu; ++i)
      for (int o = 0; o < ny; ++o) out << "," << frf.h[k](o, i).real() << "," << frf.h[k](o, i).imag();
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
