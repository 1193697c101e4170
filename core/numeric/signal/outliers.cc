#include "core/numeric/signal/outliers.h"

#include <algorithm>
#include <cmath>

#include "core/numeric/signal/robust_stats.h"

namespace idrig {
namespace {

constexpr long kHalfWindow = 5;
constexpr double kScaleMultiple = 12.0;
constexpr double kSpanShare = 0.25;

double QuantileOf(std::vector<double> v, double p) {
  const auto at = v.begin() + static_cast<long>(std::lround(p * static_cast<double>(v.size() - 1)));
  std::nth_element(v.begin(), at, v.end());
  return *at;
}

// x_t minus the median of x over t − h … t + h (clipped at the ends).
Eigen::VectorXd RunningMedianResidual(const Eigen::VectorXd& x) {
  const long n = x.size();
  Eigen::VectorXd r(n);
  std::vector<double> window;
  for (long t = 0; t < n; ++t) {
    const long a = std::max<long>(0, t - kHalfWindow), b = std::min<long>(n - 1, t + kHalfWindow);
    window.assign(x.data() + a, x.data() + b + 1);
    r(t) = x(t) - Median(window);
  }
  return r;
}

double Span(const Eigen::VectorXd& x) {
  std::vector<double> v(x.data(), x.data() + x.size());
  return QuantileOf(v, 0.995) - QuantileOf(v, 0.005);
}

}  // namespace

GlitchScan BridgeOutputGlitches(Eigen::VectorXd& y, const Eigen::MatrixXd& inputs) {
  GlitchScan scan;
  const long n = y.size();
  if (n < 4 * kHalfWindow) return scan;
  const Eigen::VectorXd r = RunningMedianResidual(y);
  std::vector<double> abs_r(static_cast<size_t>(n));
  for (long t = 0; t < n; ++t) abs_r[static_cast<size_t>(t)] = std::abs(r(t));
  const double scale = 1.4826 * Median(abs_r);
  const double span = Span(y);
  if (!(span > 0)) return scan;
  const double threshold = std::max(kScaleMultiple * scale, kSpanShare * span);

  // An isolated input excursion at t or t − 1 may be what the output shows at t. Measured
  // against the input's whole range: its isolated pulses are what this looks for, so they must
  // not fall outside the span they are measured against (the output's span leaves its glitches out).
  std::vector<bool> input_event(static_cast<size_t>(n), false);
  if (inputs.rows() == n)
    for (long c = 0; c < inputs.cols(); ++c) {
      const Eigen::VectorXd u = inputs.col(c);
      const Eigen::VectorXd ru = RunningMedianResidual(u);
      const double u_span = u.maxCoeff() - u.minCoeff();
      for (long t = 0; t < n; ++t)
        if (u_span > 0 && std::abs(ru(t)) > kSpanShare * u_span) {
          input_event[static_cast<size_t>(t)] = true;
          if (t + 1 < n) input_event[static_cast<size_t>(t + 1)] = true;
        }
    }
  std::vector<bool> marked(static_cast<size_t>(n), false);
  for (long t = 0; t < n; ++t)
    if (std::abs(r(t)) > threshold && !input_event[static_cast<size_t>(t)]) {
      marked[static_cast<size_t>(t)] = true;
      ++scan.excursions;
    }
  if (scan.excursions == 0) return scan;
  // Rarity counts events (runs of marked samples), not samples: a glitch of three samples is one
  // fault, and three such faults in 4000 samples are still rare.
  for (long t = 0; t < n; ++t)
    if (marked[static_cast<size_t>(t)] && (t == 0 || !marked[static_cast<size_t>(t - 1)])) ++scan.events;
  const long limit = std::max<long>(2, static_cast<long>(0.002 * static_cast<double>(n)));
  if (scan.events > limit || scan.excursions > kHalfWindow * limit) {
    scan.too_many = true;
    return scan;
  }
  // Bridge each run of marked samples between its unmarked neighbours (held at an end).
  for (long t = 0; t < n;) {
    if (!marked[static_cast<size_t>(t)]) {
      ++t;
      continue;
    }
    long end = t;
    while (end < n && marked[static_cast<size_t>(end)]) ++end;
    const bool has_left = t > 0, has_right = end < n;
    const double left = has_left ? y(t - 1) : y(end), right = has_right ? y(end) : y(t - 1);
    for (long k = t; k < end; ++k) {
      const double w = static_cast<double>(k - t + 1) / static_cast<double>(end - t + 1);
      const double bridged = (has_left && has_right) ? left + w * (right - left) : (has_left ? left : right);
      scan.glitches.push_back({k, y(k), bridged});
      y(k) = bridged;
    }
    t = end;
  }
  return scan;
}

}  // namespace idrig
