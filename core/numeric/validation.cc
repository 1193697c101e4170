#include "core/numeric/validation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace idrig {

Eigen::VectorXd Nrmse(const Eigen::MatrixXd& measured, const Eigen::MatrixXd& simulated) {
  if (measured.rows() != simulated.rows() || measured.cols() != simulated.cols())
    throw std::invalid_argument("NRMSE: measured and simulated outputs differ in size");
  Eigen::VectorXd out(measured.cols());
  for (int c = 0; c < measured.cols(); ++c) {
    const double spread = (measured.col(c).array() - measured.col(c).mean()).matrix().norm();
    const double error = (measured.col(c) - simulated.col(c)).norm();
    out(c) = spread > 0.0 ? error / spread : (error == 0.0 ? 0.0 : std::numeric_limits<double>::infinity());
  }
  return out;
}

Eigen::VectorXd FitPercent(const Eigen::MatrixXd& measured, const Eigen::MatrixXd& simulated) {
  return (100.0 * (1.0 - Nrmse(measured, simulated).array())).matrix();
}

double NormalQuantile(double p) {
  if (!(p > 0.0 && p < 1.0)) throw std::invalid_argument("normal quantile: p must be in (0, 1)");
  // Acklam's rational approximation refined by one Halley step on erfc (|error| < 1e-15).
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                             1.383577518672690e+02, -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                             6.680131188771972e+01, -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                             -2.549732539343734e+00, 4.374664141464968e+00, 2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                             3.754408661907416e+00};
  double x;
  if (p < 0.02425) {
    const double q = std::sqrt(-2 * std::log(p));
    x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  } else if (p > 1 - 0.02425) {
    const double q = std::sqrt(-2 * std::log(1 - p));
    x = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  } else {
    const double q = p - 0.5, r = q * q;
    x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
  }
  const double e = 0.5 * std::erfc(-x / std::sqrt(2.0)) - p;
  const double u = e * std::sqrt(2 * M_PI) * std::exp(x * x / 2);
  return x - u / (1 + x * u / 2);
}

double ChiSquareQuantile(double p, int dof) {
  if (dof < 1) throw std::invalid_argument("chi-square quantile: need at least one degree of freedom");
  const double z = NormalQuantile(p);
  const double h = 2.0 / (9.0 * dof);
  return dof * std::pow(1.0 - h + z * std::sqrt(h), 3);
}

ResidualTest TestResiduals(const Eigen::VectorXd& residual, const Eigen::VectorXd& input,
                           const ResidualTestOptions& options) {
  const long n = residual.size();
  const int m = options.max_lag;
  if (input.size() != n) throw std::invalid_argument("residual test: residual and input lengths differ");
  if (m < 1 || n <= m + 1)
    throw std::invalid_argument("residual test: " + std::to_string(n) + " samples are too few for " +
                                std::to_string(m) + " lags");
  const Eigen::VectorXd e = residual.array() - residual.mean();
  const Eigen::VectorXd u = input.array() - input.mean();
  const double ree0 = e.squaredNorm() / n;
  const double ruu0 = u.squaredNorm() / n;
  ResidualTest out;
  out.band = NormalQuantile(0.5 + options.confidence / 2.0) / std::sqrt(static_cast<double>(n));
  out.autocorrelation.resize(m + 1);
  out.crosscorrelation.resize(2 * m + 1);
  for (int k = 0; k <= m; ++k) {
    const double r = e.head(n - k).dot(e.tail(n - k)) / n;
    out.autocorrelation(k) = ree0 > 0 ? r / ree0 : 0.0;
  }
  const double scale = std::sqrt(ruu0 * ree0);
  for (int k = -m; k <= m; ++k) {
    // r_ue(k) = (1/N) Σ e(t) u(t − k): k > 0 looks at past inputs.
    double r = 0.0;
    if (k >= 0) r = e.tail(n - k).dot(u.head(n - k)) / n;
    else r = e.head(n + k).dot(u.tail(n + k)) / n;
    out.crosscorrelation(k + m) = scale > 0 ? r / scale : 0.0;
  }
  double q = 0.0;
  for (int k = 1; k <= m; ++k) {
    const double r = out.autocorrelation(k);
    q += r * r / (n - k);
    if (std::abs(r) > out.band) ++out.autocorrelation_outside;
  }
  out.portmanteau_q = n * (n + 2.0) * q;  // Ljung–Box
  out.portmanteau_threshold = ChiSquareQuantile(options.confidence, m);
  double cq = 0.0;
  for (int k = -m; k <= m; ++k) {
    const double r = out.crosscorrelation(k + m);
    if (std::abs(r) > out.band) ++out.crosscorrelation_outside;
    if (k >= 0) cq += r * r;
  }
  out.cross_q = n * cq;
  out.cross_threshold = ChiSquareQuantile(options.confidence, m + 1);
  out.white = out.portmanteau_q <= out.portmanteau_threshold;
  out.independent = out.cross_q <= out.cross_threshold;
  return out;
}

InputCorrelationTest TestInputCorrelationPrewhitened(
    const std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>>& segments, int ar_order, int dense_lags,
    double confidence) {
  const int p = ar_order;
  if (p < 0 || dense_lags < 0) throw std::invalid_argument("input correlation test: negative order or lag");
  if (segments.empty()) throw std::invalid_argument("input correlation test: no samples");
  long shortest = std::numeric_limits<long>::max(), ar_rows = 0;
  for (const auto& [e, u] : segments) {
    if (e.size() != u.size()) throw std::invalid_argument("input correlation test: residual and input lengths differ");
    shortest = std::min<long>(shortest, e.size());
    ar_rows += std::max<long>(0, e.size() - p);
  }
  // Near lags 0..dense_lags; far lags geometric (×1.25) from there up to a quarter of the shortest
  // segment: a model error can sit far from lag 0 (an echo, a slow mode), and a sparse set still
  // meets it because the plant spreads it over neighbouring lags.
  std::vector<long> near, far;
  for (long k = 0; k <= dense_lags; ++k) near.push_back(k);
  for (double k = 1.25 * std::max(dense_lags, 4); k <= (shortest - p) / 4.0; k *= 1.25)
    if (far.empty() || std::lround(k) > far.back()) far.push_back(std::lround(k));
  auto rows_for = [&](const std::vector<long>& lags) {
    long rows = 0;
    for (const auto& [e, u] : segments) rows += std::max<long>(0, e.size() - p - lags.back());
    return rows;
  };
  const long near_rows = rows_for(near);
  if (near_rows < 10 * (p + static_cast<long>(near.size()) + 1))
    throw std::invalid_argument("input correlation test: " + std::to_string(near_rows) +
                                " usable samples are too few for AR(" + std::to_string(p) + ") and " +
                                std::to_string(near.size()) + " input lags");
  // AR(p) of the residual (with a constant): e(t) + a1 e(t−1) + … + ap e(t−p) = c + w(t).
  Eigen::VectorXd a = Eigen::VectorXd::Zero(p);
  if (p > 0) {
    Eigen::MatrixXd phi(ar_rows, p + 1);
    Eigen::VectorXd target(ar_rows);
    long r = 0;
    for (const auto& [e, u] : segments)
      for (long t = p; t < e.size(); ++t, ++r) {
        target(r) = e(t);
        phi(r, p) = 1.0;
        for (int i = 1; i <= p; ++i) phi(r, i - 1) = -e(t - i);
      }
    a = phi.colPivHouseholderQr().solve(target).head(p);
  }
  auto whiten = [&](const Eigen::VectorXd& x) {
    Eigen::VectorXd w = Eigen::VectorXd::Zero(x.size());
    for (long t = p; t < x.size(); ++t) {
      w(t) = x(t);
      for (int i = 1; i <= p; ++i) w(t) += a(i - 1) * x(t - i);
    }
    return w;
  };
  std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>> white;
  for (const auto& [e, u] : segments) white.emplace_back(whiten(e), whiten(u));
  // N·R² of e'(t) on u'(t − k), k in `lags`, and a constant.
  auto regress = [&](const std::vector<long>& lags, long rows) {
    const int columns = static_cast<int>(lags.size());
    Eigen::MatrixXd phi(rows, columns + 1);
    Eigen::VectorXd target(rows);
    long r = 0;
    for (const auto& [e, u] : white)
      for (long t = p + lags.back(); t < e.size(); ++t, ++r) {
        target(r) = e(t);
        phi(r, columns) = 1.0;
        for (int k = 0; k < columns; ++k) phi(r, k) = u(t - lags[k]);
      }
    const Eigen::VectorXd theta = phi.colPivHouseholderQr().solve(target);
    const double total = (target.array() - target.mean()).matrix().squaredNorm();
    const double residual = (target - phi * theta).squaredNorm();
    return total > 0 ? std::max(0.0, 1.0 - residual / total) : 0.0;
  };
  // Two sets, each at half the level (Bonferroni): the far lags do not dilute the near ones.
  const double level = 1.0 - (1.0 - confidence) / (far.size() >= 2 ? 2.0 : 1.0);
  InputCorrelationTest out;
  out.ar_order = p;
  out.lags = static_cast<int>(near.size());
  out.samples = near_rows;
  out.explained_share = regress(near, near_rows);
  out.statistic = static_cast<double>(near_rows) * out.explained_share;
  out.threshold = ChiSquareQuantile(level, out.lags);
  out.max_lag = near.back();
  out.correlated = out.statistic > out.threshold;
  const long far_rows = far.size() >= 2 ? rows_for(far) : 0;
  if (far_rows >= 10 * (p + static_cast<long>(far.size()) + 1)) {
    out.far_lags = static_cast<int>(far.size());
    out.max_lag = far.back();
    out.far_statistic = static_cast<double>(far_rows) * regress(far, far_rows);
    out.far_threshold = ChiSquareQuantile(level, out.far_lags);
    out.correlated = out.correlated || out.far_statistic > out.far_threshold;
  }
  return out;
}

std::string ResidualTest::Summary() const {
  std::ostringstream s;
  s << "residuals " << (white ? "white" : "NOT white") << " (Ljung-Box Q = " << portmanteau_q
    << ", threshold " << portmanteau_threshold << ", " << autocorrelation_outside
    << " lags outside ±" << band << "); input-residual correlation "
    << (independent ? "insignificant" : "SIGNIFICANT") << " (Q = " << cross_q << ", threshold "
    << cross_threshold << ", " << crosscorrelation_outside << " lags outside the band)";
  return s.str();
}

}  // namespace idrig
