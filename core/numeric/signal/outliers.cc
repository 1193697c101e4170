#include "core/numeric/signal/outliers.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/numeric/signal/robust_stats.h"

namespace idrig {
namespace {

constexpr long kHalfWindow = 5;
constexpr double kScaleMultiple = 12.0;
constexpr double kSpanShare = 0.25;
constexpr double kJumpMultiple = 1.5;

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

// Is the run y[a, b) entered and left by jumps sharper than the output's own motion around it?
// The run is taken with the samples beside it that are as far out (`far`: excused by an input
// excursion, or not), and each jump (into it from the sample before, out of it to the sample
// after, where they exist) must exceed half the threshold and kJumpMultiple times the largest
// |Δy| over the h samples on either side (steps touching another far sample left out: two
// glitches close together).
bool SharpRun(const Eigen::VectorXd& y, const std::vector<bool>& far, long a, long b, double threshold) {
  const long n = y.size();
  while (a > 0 && far[static_cast<size_t>(a - 1)]) --a;
  while (b < n && far[static_cast<size_t>(b)]) ++b;
  double motion = 0;
  const auto step = [&](long k) {  // |y_k − y_{k−1}| where neither is far out
    if (k >= 1 && k < n && !far[static_cast<size_t>(k)] && !far[static_cast<size_t>(k - 1)])
      motion = std::max(motion, std::abs(y(k) - y(k - 1)));
  };
  for (long k = a - kHalfWindow; k < a; ++k) step(k);
  for (long k = b + 1; k <= b + kHalfWindow; ++k) step(k);
  const double needed = std::max(0.5 * threshold, kJumpMultiple * motion);
  if (a > 0 && !(std::abs(y(a) - y(a - 1)) > needed)) return false;
  if (b < n && !(std::abs(y(b) - y(b - 1)) > needed)) return false;
  return a > 0 || b < n;
}

// The runs [a, b) of marked samples, in order.
std::vector<std::pair<long, long>> Runs(const std::vector<bool>& marked) {
  std::vector<std::pair<long, long>> runs;
  const long n = static_cast<long>(marked.size());
  for (long t = 0; t < n;) {
    if (!marked[static_cast<size_t>(t)]) {
      ++t;
      continue;
    }
    long end = t;
    while (end < n && marked[static_cast<size_t>(end)]) ++end;
    runs.emplace_back(t, end);
    t = end;
  }
  return runs;
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
  std::vector<bool> marked(static_cast<size_t>(n), false), far(static_cast<size_t>(n), false);
  for (long t = 0; t < n; ++t) {
    far[static_cast<size_t>(t)] = std::abs(r(t)) > threshold;
    if (far[static_cast<size_t>(t)] && !input_event[static_cast<size_t>(t)]) {
      marked[static_cast<size_t>(t)] = true;
      ++scan.excursions;
    }
  }
  if (scan.excursions == 0) return scan;
  // Rarity counts events (runs of marked samples), not samples: a glitch of three samples is one
  // fault, and three such faults in 4000 samples are still rare.
  const std::vector<std::pair<long, long>> runs = Runs(marked);
  scan.events = static_cast<long>(runs.size());
  const long limit = std::max<long>(2, static_cast<long>(0.002 * static_cast<double>(n)));
  if (scan.events > limit || scan.excursions > kHalfWindow * limit) {
    scan.too_many = true;
    return scan;
  }
  // Of the rare runs, a glitch leaves the signal in one sample and comes back in one: each
  // run's jump in and out is sharp against the output's own sample-to-sample motion around it.
  // The peaks of an oscillation a few samples long (a coarsely sampled rig: a mode of 12 rad/s at
  // Ts 0.05 s) stand as far from their running median, but are reached and left through samples
  // in between (`gap bench --ts 0.05`: such peaks were bridged as glitches, on 64 of 108 records).
  std::vector<std::pair<long, long>> glitches;
  for (const auto& [a, b] : runs)
    if (SharpRun(y, far, a, b, threshold)) glitches.emplace_back(a, b);
  // Bridge each glitch between its unmarked neighbours (held at an end).
  for (const auto& [t, end] : glitches) {
    const bool has_left = t > 0, has_right = end < n;
    const double left = has_left ? y(t - 1) : y(end), right = has_right ? y(end) : y(t - 1);
    for (long k = t; k < end; ++k) {
      const double w = static_cast<double>(k - t + 1) / static_cast<double>(end - t + 1);
      const double bridged = (has_left && has_right) ? left + w * (right - left) : (has_left ? left : right);
      scan.glitches.push_back({k, y(k), bridged});
      y(k) = bridged;
    }
  }
  return scan;
}

}  // namespace idrig
