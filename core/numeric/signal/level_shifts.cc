#include "core/numeric/signal/level_shifts.h"

#include <algorithm>
#include <cmath>

#include "core/numeric/signal/robust_stats.h"

namespace idrig {
namespace {

constexpr long kWindow = 8;
constexpr double kSpreadMultiple = 12.0;
constexpr double kNoiseMultiple = 6.0;
constexpr double kSharpShare = 0.5;
constexpr double kIncrementMultiple = 3.0;
constexpr double kPersistShare = 0.6;

double MedianOf(const Eigen::VectorXd& r, long a, long b) {  // [a, b)
  return Median(std::vector<double>(r.data() + a, r.data() + b));
}

}  // namespace

std::vector<LevelShift> FindSensorSteps(const Eigen::VectorXd& y, const Eigen::VectorXd& model_output,
                                        int max_shifts) {
  std::vector<LevelShift> found;
  const long n = y.size();
  if (model_output.size() != n || n < 8 * kWindow || !y.allFinite() || !model_output.allFinite()) return found;
  const Eigen::VectorXd r = y - model_output;
  Eigen::VectorXd prefix(n + 1);
  prefix(0) = 0;
  for (long k = 0; k < n; ++k) prefix(k + 1) = prefix(k) + r(k);
  const auto mean = [&](long a, long b) { return (prefix(b) - prefix(a)) / double(b - a); };
  std::vector<double> jumps, increments;
  Eigen::VectorXd j = Eigen::VectorXd::Zero(n);
  for (long t = kWindow; t + kWindow <= n; ++t) {
    j(t) = mean(t, t + kWindow) - mean(t - kWindow, t);
    jumps.push_back(j(t));
  }
  // What the model's error does to r's increments wherever the model moves: Δr ≈ β·Δŷ (least
  // squares over the record); e = Δr − β·Δŷ is what the model cannot account for.
  Eigen::VectorXd dr(n - 1), dm(n - 1);
  for (long k = 1; k < n; ++k) dr(k - 1) = r(k) - r(k - 1), dm(k - 1) = model_output(k) - model_output(k - 1);
  const double beta = dm.squaredNorm() > 0 ? dm.dot(dr) / dm.squaredNorm() : 0.0;
  const Eigen::VectorXd e = dr - beta * dm;
  for (long k = 0; k < e.size(); ++k) increments.push_back(e(k));
  const double spread = RobustSpread(jumps);
  const double sigma = RobustSpread(increments) / std::sqrt(2.0);
  const double scale = std::max({spread, 1e-12 * (1.0 + r.cwiseAbs().maxCoeff())});
  const long w_long = std::clamp<long>(n / 8, 4 * kWindow, 500);
  std::vector<LevelShift> candidates;
  for (long t = kWindow; t + kWindow <= n; ++t) {
    const double size = j(t);
    if (!(std::abs(size) > kSpreadMultiple * scale && std::abs(size) > kNoiseMultiple * sigma)) continue;
    // A local maximum of |J| (the triangle a step makes peaks at it).
    bool peak = true;
    for (long s = std::max<long>(kWindow, t - kWindow); s <= std::min<long>(n - kWindow, t + kWindow) && peak; ++s)
      if (std::abs(j(s)) > std::abs(size) || (std::abs(j(s)) == std::abs(size) && s < t)) peak = false;
    if (!peak) continue;
    // The jump's own sample: the largest increment near the peak.
    long at = t;
    for (long s = std::max<long>(1, t - kWindow / 2); s <= std::min<long>(n - 1, t + kWindow / 2); ++s)
      if (std::abs(r(s) - r(s - 1)) > std::abs(r(at) - r(at - 1))) at = s;
    const double step = r(at) - r(at - 1);
    if (!(std::abs(step) >= kSharpShare * std::abs(size)) || step * size <= 0) continue;
    // Not what the model's error does where the model moves as it does here.
    const double unexplained = e(at - 1);
    if (!(std::abs(unexplained) >= kSharpShare * std::abs(size) && std::abs(unexplained) > kIncrementMultiple * sigma * std::sqrt(2.0)))
      continue;
    bool persistent = true;
    for (const long w : {w_long, w_long / 4}) {
      const long before = std::max<long>(0, at - w), after = std::min<long>(n, at + w);
      if (at - before < kWindow || after - at < kWindow) { persistent = false; break; }
      const double held = MedianOf(r, at, after) - MedianOf(r, before, at);
      if (!(held * size > 0 && std::abs(held) >= kPersistShare * std::abs(size))) persistent = false;
    }
    if (!persistent) continue;
    candidates.push_back({at, size, std::abs(size) / scale});
  }
  std::sort(candidates.begin(), candidates.end(), [](const LevelShift& a, const LevelShift& b) { return a.score > b.score; });
  for (const auto& c : candidates) {
    if (static_cast<int>(found.size()) >= max_shifts) break;
    if (std::any_of(found.begin(), found.end(), [&](const LevelShift& f) { return std::abs(f.sample - c.sample) < 2 * w_long; }))
      continue;
    found.push_back(c);
  }
  std::sort(found.begin(), found.end(), [](const LevelShift& a, const LevelShift& b) { return a.sample < b.sample; });
  return found;
}

}  // namespace idrig
