#include "core/numeric/signal/frf.h"

#include <unsupported/Eigen/FFT>

#include <cmath>
#include <stdexcept>
#include <string>

namespace idrig {

namespace {
constexpr double kPi = 3.14159265358979323846;
using Complex = std::complex<double>;

// DFT of a windowed segment of every column: returns nfft/2+1 rows × columns.
Eigen::MatrixXcd SegmentSpectra(Eigen::FFT<double>& fft, const Eigen::MatrixXd& x, int begin,
                                int nfft, const Eigen::VectorXd& window) {
  Eigen::MatrixXcd out(nfft / 2 + 1, x.cols());
  std::vector<double> in(nfft);
  std::vector<Complex> spectrum;
  for (int c = 0; c < x.cols(); ++c) {
    for (int i = 0; i < nfft; ++i) in[i] = window(i) * x(begin + i, c);
    fft.fwd(spectrum, in);
    for (int k = 0; k <= nfft / 2; ++k) out(k, c) = spectrum[k];
  }
  return out;
}
}  // namespace

Eigen::VectorXcd Frf::Element(int out, int in) const {
  Eigen::VectorXcd v(NumLines());
  for (int k = 0; k < NumLines(); ++k) v(k) = h[k](out, in);
  return v;
}

Frf MakeSisoFrf(const Eigen::VectorXd& omega, const Eigen::VectorXcd& h) {
  if (omega.size() != h.size())
    throw std::invalid_argument("FRF: " + std::to_string(omega.size()) + " frequencies but " +
                                std::to_string(h.size()) + " response values");
  Frf frf;
  frf.omega = omega;
  frf.h.resize(h.size());
  for (int k = 0; k < h.size(); ++k) frf.h[k] = Eigen::MatrixXcd::Constant(1, 1, h(k));
  return frf;
}

void ValidateFrf(const Frf& frf, bool allow_zero_frequency) {
  const int lines = frf.NumLines();
  if (lines == 0) throw std::invalid_argument("FRF: no frequency lines");
  if (static_cast<int>(frf.h.size()) != lines)
    throw std::invalid_argument("FRF: " + std::to_string(lines) + " frequencies but " +
                                std::to_string(frf.h.size()) + " response matrices");
  const int ny = frf.NumOutputs(), nu = frf.NumInputs();
  if (ny == 0 || nu == 0) throw std::invalid_argument("FRF: empty response matrix");
  for (int k = 0; k < lines; ++k) {
    if (frf.h[k].rows() != ny || frf.h[k].cols() != nu)
      throw std::invalid_argument("FRF: line " + std::to_string(k) + " has a " +
                                  std::to_string(frf.h[k].rows()) + "x" + std::to_string(frf.h[k].cols()) +
                                  " matrix, line 0 a " + std::to_string(ny) + "x" + std::to_string(nu));
    if (!std::isfinite(frf.omega(k)))
      throw std::invalid_argument("FRF: frequency of line " + std::to_string(k) + " is NaN or Inf");
    if (!frf.h[k].allFinite())
      throw std::invalid_argument("FRF: response at line " + std::to_string(k) + " (ω = " +
                                  std::to_string(frf.omega(k)) + " rad/s) is NaN or Inf");
    if (!allow_zero_frequency && frf.omega(k) <= 0.0)
      throw std::invalid_argument("FRF: line " + std::to_string(k) + " has ω = " +
                                  std::to_string(frf.omega(k)) +
                                  " rad/s; this method needs strictly positive frequencies (drop the DC line)");
    if (allow_zero_frequency && frf.omega(k) < 0.0)
      throw std::invalid_argument("FRF: line " + std::to_string(k) + " has a negative frequency");
    if (k > 0 && !(frf.omega(k) > frf.omega(k - 1)))
      throw std::invalid_argument("FRF: frequencies must be strictly increasing (line " +
                                  std::to_string(k) + ")");
  }
  if (frf.variance.size() && (frf.variance.rows() != lines || frf.variance.cols() != ny * nu))
    throw std::invalid_argument("FRF: variance must be lines x (outputs*inputs)");
  if (frf.variance.size() && !frf.variance.allFinite())
    throw std::invalid_argument("FRF: variance holds NaN or Inf");
  if (frf.coherence.size() && (frf.coherence.rows() != lines || frf.coherence.cols() != ny))
    throw std::invalid_argument("FRF: coherence must be lines x outputs");
}

Frf EstimateFrfWelch(const IoRecord& record, const WelchOptions& options) {
  ValidateIoRecord(record, 16);
  const int n = record.NumSamples(), nu = record.NumInputs(), ny = record.NumOutputs();
  int nfft = options.segment_length > 0 ? options.segment_length : (n / 8) & ~1;
  if (nfft < 8) throw std::invalid_argument("Welch: segment_length must be at least 8 samples");
  if (nfft > n)
    throw std::invalid_argument("Welch: segment_length " + std::to_string(nfft) +
                                " exceeds the record length " + std::to_string(n));
  if (!(options.overlap >= 0.0 && options.overlap < 1.0))
    throw std::invalid_argument("Welch: overlap must be in [0, 1)");
  const int step = std::max(1, static_cast<int>(std::lround(nfft * (1.0 - options.overlap))));
  const int segments = 1 + (n - nfft) / step;
  if (segments < nu)
    throw std::invalid_argument("Welch: " + std::to_string(segments) + " segments for " +
                                std::to_string(nu) + " inputs: S_uu is singular; use shorter segments");
  Eigen::VectorXd window = Eigen::VectorXd::Ones(nfft);
  if (options.hann_window)  // periodic Hann
    for (int i = 0; i < nfft; ++i) window(i) = 0.5 - 0.5 * std::cos(2.0 * kPi * i / nfft);

  const int bins = nfft / 2 + 1;
  std::vector<Eigen::MatrixXcd> suu(bins, Eigen::MatrixXcd::Zero(nu, nu));
  std::vector<Eigen::MatrixXcd> syu(bins, Eigen::MatrixXcd::Zero(ny, nu));
  std::vector<Eigen::VectorXd> syy(bins, Eigen::VectorXd::Zero(ny));
  Eigen::FFT<double> fft;
  for (int s = 0; s < segments; ++s) {
    // Detrend each segment by its mean (the DC line is usually dropped anyway).
    Eigen::MatrixXd useg = record.u.middleRows(s * step, nfft);
    Eigen::MatrixXd yseg = record.y.middleRows(s * step, nfft);
    useg.rowwise() -= useg.colwise().mean();
    yseg.rowwise() -= yseg.colwise().mean();
    const Eigen::MatrixXcd U = SegmentSpectra(fft, useg, 0, nfft, window);
    const Eigen::MatrixXcd Y = SegmentSpectra(fft, yseg, 0, nfft, window);
    for (int k = 0; k < bins; ++k) {
      const Eigen::VectorXcd uk = U.row(k).transpose(), yk = Y.row(k).transpose();
      suu[k] += uk * uk.adjoint();
      syu[k] += yk * uk.adjoint();
      syy[k] += yk.cwiseAbs2();
    }
  }
  Frf frf;
  frf.averages = segments;
  const int first = options.keep_dc ? 0 : 1;
  const int lines = bins - first;
  frf.omega.resize(lines);
  frf.h.resize(lines);
  frf.coherence.resize(lines, ny);
  frf.variance.resize(lines, ny * nu);
  const double dw = 2.0 * kPi / (nfft * record.sample_time);
  for (int k = first; k < bins; ++k) {
    const int line = k - first;
    frf.omega(line) = k * dw;
    const auto lu = suu[k].ldlt();
    const Eigen::MatrixXcd h = lu.solve(syu[k].adjoint()).adjoint();  // S_yu S_uu⁻¹
    frf.h[line] = h.allFinite() ? h : Eigen::MatrixXcd::Zero(ny, nu);
    for (int i = 0; i < ny; ++i) {
      const Complex explained = (syu[k].row(i) * lu.solve(syu[k].row(i).adjoint()))(0, 0);
      double g2 = syy[k](i) > 0.0 ? explained.real() / syy[k](i) : 0.0;
      if (!std::isfinite(g2)) g2 = 0.0;
      g2 = std::min(1.0, std::max(0.0, g2));
      frf.coherence(line, i) = g2;
      for (int j = 0; j < nu; ++j) {
        const double v = g2 > 0.0 ? (1.0 - g2) * std::norm(frf.h[line](i, j)) / (segments * g2) : 1e300;
        frf.variance(line, i + ny * j) = v;
      }
    }
  }
  return frf;
}

Frf EstimateFrfPeriodic(const IoRecord& record, const PeriodicOptions& options) {
  ValidateIoRecord(record, 4);
  if (record.NumInputs() != 1)
    throw std::invalid_argument("periodic FRF: one input expected, the record has " +
                                std::to_string(record.NumInputs()));
  const int np = options.period_samples;
  if (np < 4) throw std::invalid_argument("periodic FRF: period_samples must be at least 4");
  const int periods = record.NumSamples() / np - options.skip_periods;
  if (options.skip_periods < 0 || periods < 2)
    throw std::invalid_argument("periodic FRF: need at least 2 full periods of " +
                                std::to_string(np) + " samples after skipping " +
                                std::to_string(options.skip_periods));
  const int ny = record.NumOutputs(), bins = np / 2 + 1;
  Eigen::FFT<double> fft;
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(np);
  std::vector<Eigen::MatrixXcd> U, Y;
  Eigen::VectorXcd u_mean = Eigen::VectorXcd::Zero(bins);
  Eigen::MatrixXcd y_mean = Eigen::MatrixXcd::Zero(bins, ny);
  for (int p = 0; p < periods; ++p) {
    const int begin = (options.skip_periods + p) * np;
    U.push_back(SegmentSpectra(fft, record.u, begin, np, ones));
    Y.push_back(SegmentSpectra(fft, record.y, begin, np, ones));
    u_mean += U.back().col(0);
    y_mean += Y.back();
  }
  u_mean /= periods;
  y_mean /= periods;
  const double umax = u_mean.cwiseAbs().maxCoeff();
  std::vector<int> keep;
  for (int k = options.keep_dc ? 0 : 1; k < bins; ++k)
    if (umax > 0.0 && std::abs(u_mean(k)) > options.excited_threshold * umax) keep.push_back(k);
  if (keep.empty()) throw std::invalid_argument("periodic FRF: the input excites no frequency line");
  Frf frf;
  frf.averages = periods;
  const int lines = static_cast<int>(keep.size());
  frf.omega.resize(lines);
  frf.h.resize(lines);
  frf.variance.resize(lines, ny);
  const double dw = 2.0 * kPi / (np * record.sample_time);
  for (int line = 0; line < lines; ++line) {
    const int k = keep[line];
    frf.omega(line) = k * dw;
    frf.h[line].resize(ny, 1);
    double var_u = 0.0;
    for (int p = 0; p < periods; ++p) var_u += std::norm(U[p](k, 0) - u_mean(k));
    var_u /= periods - 1;
    for (int i = 0; i < ny; ++i) {
      const Complex h = y_mean(k, i) / u_mean(k);
      frf.h[line](i, 0) = h;
      double var_y = 0.0;
      Complex cov_yu = 0.0;
      for (int p = 0; p < periods; ++p) {
        const Complex dy = Y[p](k, i) - y_mean(k, i), du = U[p](k, 0) - u_mean(k);
        var_y += std::norm(dy);
        cov_yu += dy * std::conj(du);
      }
      var_y /= periods - 1;
      cov_yu /= static_cast<double>(periods - 1);
      const double v = (var_y + std::norm(h) * var_u - 2.0 * std::real(std::conj(h) * cov_yu)) /
                       (periods * std::norm(u_mean(k)));
      frf.variance(line, i) = std::max(0.0, v);
    }
  }
  return frf;
}

}  // namespace idrig
