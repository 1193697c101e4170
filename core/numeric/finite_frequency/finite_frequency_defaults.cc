#include "core/numeric/finite_frequency/finite_frequency_defaults.h"

#include <unsupported/Eigen/FFT>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace idrig {
namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

[[noreturn]] void Fail(const std::string& what) { throw std::invalid_argument("finite-frequency: " + what); }

std::string Num(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

// Least squares of x on [sin, cos](n_k ω_b t_i) and 1; returns ‖residual‖², fills a_k, b_k.
double MultisineResidual(const Eigen::VectorXd& x, double h, double base, const std::vector<int>& multiples,
                         Eigen::VectorXd* coef = nullptr) {
  const int n = static_cast<int>(x.size()), k = static_cast<int>(multiples.size());
  Eigen::MatrixXd a(n, 2 * k + 1);
  for (int i = 0; i < n; ++i) {
    for (int l = 0; l < k; ++l) {
      const double phase = multiples[l] * base * i * h;
      a(i, 2 * l) = std::sin(phase);
      a(i, 2 * l + 1) = std::cos(phase);
    }
    a(i, 2 * k) = 1.0;
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(x);
  if (coef) *coef = c;
  return (x - a * c).squaredNorm();
}

}  // namespace

FoundTestSignal FindTestSignal(const Eigen::VectorXd& u, double h, const TestSignalSearchOptions& options) {
  const int n = static_cast<int>(u.size());
  if (!(h > 0.0)) Fail("sample time must be positive");
  if (n < 16) Fail("the record has " + std::to_string(n) + " samples: too short to find the test frequencies");
  const Eigen::VectorXd x = u.array() - u.mean();
  const double variance = x.squaredNorm();
  if (!(variance > 0.0)) Fail("the input is constant: no test frequencies to find (give base_omega and frequencies)");
  // Hann-windowed spectrum, bins 1 … N/2 − 1.
  std::vector<double> windowed(n);
  for (int i = 0; i < n; ++i) windowed[i] = x(i) * (0.5 - 0.5 * std::cos(kTwoPi * i / n));
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> spectrum;
  fft.fwd(spectrum, windowed);
  const int half = n / 2;
  std::vector<double> mag(half, 0.0);
  for (int b = 1; b < half; ++b) mag[b] = std::abs(spectrum[b]);
  const double top = *std::max_element(mag.begin(), mag.end());
  const double bin = kTwoPi / (n * h);  // rad/s per bin
  // Local maxima above the threshold, at least 3 bins apart (the Hann main lobe is ±2 bins).
  std::vector<int> peaks;
  for (int b = 1; b + 1 < half; ++b) {
    if (mag[b] < options.peak_threshold * top || mag[b] < mag[b - 1] || mag[b] < mag[b + 1]) continue;
    if (!peaks.empty() && b - peaks.back() < 3) {
      if (mag[b] > mag[peaks.back()]) peaks.back() = b;
      continue;
    }
    peaks.push_back(b);
  }
  if (peaks.empty()) Fail("no spectral peak in the input: give base_omega and frequencies");
  if (static_cast<int>(peaks.size()) > options.max_lines)
    Fail("the input has " + std::to_string(peaks.size()) + " spectral peaks (more than " +
         std::to_string(options.max_lines) + "): it is not a multisine test signal (5); give base_omega and frequencies");
  // Each peak refined by a parabola through the log magnitudes of its bin and neighbours.
  std::vector<double> omega;
  for (int b : peaks) {
    const double l = std::log(mag[b - 1] + 1e-300), c = std::log(mag[b] + 1e-300), r = std::log(mag[b + 1] + 1e-300);
    const double denom = l - 2 * c + r;
    const double shift = denom < 0 ? 0.5 * (l - r) / denom : 0.0;
    omega.push_back((b + std::clamp(shift, -0.5, 0.5)) * bin);
  }
  // Largest base frequency of which every peak is a multiple (within two bins).
  double base = 0.0;
  std::vector<int> multiples;
  for (int m = 1; m <= options.max_base_divisor && base == 0.0; ++m) {
    const double candidate = omega[0] / m;
    std::vector<int> mult;
    bool fits = true;
    for (double w : omega) {
      const long k = std::lround(w / candidate);
      if (k < 1 || std::abs(w - k * candidate) > 2.0 * bin ||
          (!mult.empty() && k == mult.back())) {
        fits = false;
        break;
      }
      mult.push_back(static_cast<int>(k));
    }
    if (fits) {
      double num = 0.0, den = 0.0;  // least-squares ω_b of ω_i ≈ n_i ω_b
      for (size_t i = 0; i < omega.size(); ++i) {
        num += mult[i] * omega[i];
        den += static_cast<double>(mult[i]) * mult[i];
      }
      base = num / den;
      multiples = mult;
    }
  }
  if (base == 0.0) {
    std::string list;
    for (double w : omega) list += (list.empty() ? "" : ", ") + Num(w);
    Fail("the input's spectral peaks (" + list + " rad/s) are not multiples of one base frequency ω_b = ω_1/m, m <= " +
         std::to_string(options.max_base_divisor) + "; give base_omega and frequencies");
  }
  // ω_b by least squares on the samples: golden section within half a bin of the highest line.
  const double span = 0.5 * bin / multiples.back();
  double lo = base - span, hi = base + span;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = hi - g * (hi - lo), d = lo + g * (hi - lo);
  double fc = MultisineResidual(x, h, c, multiples), fd = MultisineResidual(x, h, d, multiples);
  for (int it = 0; it < 100 && hi - lo > 1e-13 * base; ++it) {
    if (fc < fd) {
      hi = d;
      d = c;
      fd = fc;
      c = hi - g * (hi - lo);
      fc = MultisineResidual(x, h, c, multiples);
    } else {
      lo = c;
      c = d;
      fc = fd;
      d = lo + g * (hi - lo);
      fd = MultisineResidual(x, h, d, multiples);
    }
  }
  base = 0.5 * (lo + hi);
  Eigen::VectorXd coef;
  const double residual = MultisineResidual(x, h, base, multiples, &coef);
  FoundTestSignal found;
  found.explained = 1.0 - residual / variance;
  if (found.explained < options.min_explained)
    Fail("the input is not a multisine test signal (5): lines at multiples of ω_b = " + Num(base) +
         " rad/s explain " + Num(100.0 * found.explained) + " % of its variance (at least " +
         Num(100.0 * options.min_explained) + " % needed); give base_omega and frequencies");
  found.signal.base_omega = base;
  found.signal.multiples = multiples;
  for (size_t l = 0; l < multiples.size(); ++l) {
    const double a = coef(2 * l), b = coef(2 * l + 1);  // a sin + b cos = ρ sin(· + φ)
    found.signal.amplitudes.push_back(std::hypot(a, b));
    found.phases.push_back(std::atan2(b, a));
  }
  return found;
}

NumeratorDegreeChoice ChooseNumeratorDegree(const IoRecord& record, const FiniteFrequencyOptions& options,
                                            double tolerance) {
  const int n = options.order, lines = static_cast<int>(options.signal.multiples.size());
  const int top = std::min(n - 1, 2 * lines - n - 1);
  if (n < 1) Fail("set the plant order n (options.order >= 1)");
  if (top < 0)
    Fail(std::to_string(lines) + " test frequencies are fewer than order " + std::to_string(n) + " needs (" +
         std::to_string((n + 2) / 2) + " at least)");
  NumeratorDegreeChoice choice;
  double best = std::numeric_limits<double>::infinity();
  for (int gamma = 0; gamma <= top; ++gamma) {
    FiniteFrequencyOptions o = options;
    o.numerator_degree = gamma;
    const FiniteFrequencyResult r = IdentifyFiniteFrequency(record, o);
    NumeratorDegreeRow row;
    row.numerator_degree = gamma;
    row.residual = r.status == SolverStatus::kFailed ? std::numeric_limits<double>::infinity() : r.final_cost;
    row.status = ToString(r.status);
    best = std::min(best, row.residual);
    choice.table.push_back(row);
  }
  choice.numerator_degree = top;
  for (const auto& row : choice.table)
    if (row.residual <= std::max(2.0 * best, tolerance)) {
      choice.numerator_degree = row.numerator_degree;
      break;
    }
  return choice;
}

}  // namespace idrig
