// Noise floor without candidates (gap_noise.h): variance across periods, or the de-biased
// one-step error of a high-order ARX predictor.
#include "core/numeric/gap/gap_noise.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/numeric/gap/gap_diagnosis.h"

namespace idrig {

Periodicity FindPeriod(const Eigen::VectorXd& u, int min_period) {
  Periodicity p;
  const long n = u.size();
  const double mean = u.mean();
  const double energy = (u.array() - mean).square().sum();
  if (!(energy > 0) || n < 2 * min_period) return p;
  const double tolerance = 0.02 * 0.02;  // (RMS of u(k+P) − u(k)) / RMS(u), squared
  // A slowly varying input is "periodic" at every short lag: search from twice the lag where its
  // autocorrelation first falls below 1/2.
  long decorrelated = 1;
  for (; 2 * decorrelated <= n; ++decorrelated) {
    double c = 0;
    for (long k = 0; k + decorrelated < n; ++k) c += (u(k) - mean) * (u(k + decorrelated) - mean);
    if (c < 0.5 * energy) break;
  }
  for (long period = std::max<long>(std::max(2, min_period), 2 * decorrelated); 2 * period <= n; ++period) {
    const long overlap = n - period;
    const double budget = tolerance * 2 * energy * overlap / n;  // white difference of two copies
    double sum = 0;
    long k = 0;
    for (; k < overlap && sum <= budget; ++k) {
      const double d = u(k + period) - u(k);
      sum += d * d;
    }
    if (k == overlap && sum <= budget) {
      p.period = static_cast<int>(period);
      p.periods = static_cast<int>(n / period);
      return p;
    }
  }
  return p;
}

Eigen::VectorXd PeriodLevels(const Eigen::VectorXd& y, const Periodicity& p) {
  Eigen::VectorXd level(p.periods);
  for (int j = 0; j < p.periods; ++j) level(j) = y.segment(static_cast<long>(j) * p.period, p.period).mean();
  return level;
}

double PeriodDrift(const Eigen::VectorXd& y, const Periodicity& p, int first) {
  const int m = p.periods - first;
  if (m < 2) return 0;
  const Eigen::VectorXd level = PeriodLevels(y, p).tail(m);
  const double j_mean = (m - 1) / 2.0, level_mean = level.mean();
  double sxy = 0, sxx = 0;
  for (int j = 0; j < m; ++j) {
    sxy += (j - j_mean) * (level(j) - level_mean);
    sxx += (j - j_mean) * (j - j_mean);
  }
  return sxy / sxx / p.period;
}

int SteadyPeriodStart(const Eigen::VectorXd& y, const Periodicity& p) {
  if (p.periods < 3) return 0;
  // Compared without each period's level, so that the ramp of an integrated offset (the same
  // shift from every period to the next) does not hide the transient.
  const Eigen::VectorXd level = PeriodLevels(y, p);
  std::vector<double> change(p.periods - 1);
  for (int j = 0; j + 1 < p.periods; ++j) {
    double d = 0;
    for (int k = 0; k < p.period; ++k) {
      const double step = y(static_cast<long>(j + 1) * p.period + k) - level(j + 1) -
                          y(static_cast<long>(j) * p.period + k) + level(j);
      d += step * step;
    }
    change[j] = d;
  }
  std::vector<double> sorted = change;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double median = sorted[sorted.size() / 2];
  int first = 0;
  for (int j = 0; j + 2 < p.periods; ++j)
    if (change[j] > 1.5 * median) first = j + 1;
  return first;
}

namespace {

// ARX(n, n+1) regressors of one record at sample k: −y(k−1..k−n), u(k..k−n), 1.
void Regressor(const GapRecord& r, long k, int n, double* row) {
  int j = 0;
  for (int i = 1; i <= n; ++i) row[j++] = -r.y(k - i);
  for (int i = 0; i <= n; ++i) row[j++] = r.u(k - i);
  row[j] = 1.0;
}

}  // namespace

NoiseFloor EstimateNoiseFloor(const std::vector<GapRecord>& estimation,
                              const std::vector<GapRecord>& validation) {
  NoiseFloor floor;
  // Periodic records (either set): variance across periods.
  double ss = 0;
  long dof = 0, samples = 0;
  std::vector<const GapRecord*> all;
  for (const auto& r : estimation) all.push_back(&r);
  for (const auto& r : validation) all.push_back(&r);
  for (const GapRecord* r : all) {
    const Periodicity p = FindPeriod(r->u);
    if (p.period == 0) continue;
    const int first = SteadyPeriodStart(r->y, p);
    const int m = p.periods - first;
    // Each period's own mean comes off first: an integrating plant turns an actuator offset into
    // a ramp, which shifts every period by a constant (y_j(k) = m(k) + j·D) without being noise.
    // That costs m − 1 degrees of freedom and leaves a periodic output untouched.
    const Eigen::VectorXd level = PeriodLevels(r->y, p);
    Eigen::VectorXd shape = Eigen::VectorXd::Zero(p.period);  // the mean period without its level
    for (int j = first; j < p.periods; ++j)
      shape += (r->y.segment(static_cast<long>(j) * p.period, p.period).array() - level(j)).matrix() / m;
    // A ramp that moves the output by more than 5 % of the period's own swing moves the state:
    // a nonlinear rig then answers each period differently, and that difference is not noise.
    // Such a record is left to the predictor below.
    const double moved = std::abs(PeriodDrift(r->y, p, first)) * p.period * (m - 1);
    if (moved > 0.05 * (shape.maxCoeff() - shape.minCoeff())) {
      ++floor.drifting_records;
      continue;
    }
    for (int j = first; j < p.periods; ++j)
      ss += (r->y.segment(static_cast<long>(j) * p.period, p.period).array() - level(j) - shape.array())
                .square()
                .sum();
    dof += static_cast<long>(p.period - 1) * (m - 1);
    samples += static_cast<long>(p.period) * m;
    if (floor.period == 0) {
      floor.period = p.period;
      floor.periods = p.periods;
    }
  }
  if (dof > 0) {
    floor.method = "periods";
    floor.sigma = std::sqrt(ss / dof);
    floor.samples = samples;
    return floor;
  }

  // ARX prediction: fit on the estimation records, score on the validation records.
  long n_est = 0, shortest = std::numeric_limits<long>::max();
  for (const auto& r : estimation) {
    n_est += r.u.size();
    shortest = std::min<long>(shortest, r.u.size());
  }
  for (const auto& r : validation) shortest = std::min<long>(shortest, r.u.size() - r.score_from);
  double best = std::numeric_limits<double>::infinity();
  for (int n = 4;; n *= 2) {
    const int p = 2 * n + 2;
    if (20L * p > n_est || 4L * n > shortest) break;
    Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(p, p);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(p);
    Eigen::VectorXd row(p);
    // Normal equations accumulated in blocks (the regressor matrix is never formed whole).
    const int block = 512;
    Eigen::MatrixXd phi(block, p);
    Eigen::VectorXd target(block);
    for (const auto& r : estimation) {
      for (long start = n; start < r.u.size(); start += block) {
        const long rows = std::min<long>(block, r.u.size() - start);
        for (long i = 0; i < rows; ++i) {
          Regressor(r, start + i, n, row.data());
          phi.row(i) = row.transpose();
          target(i) = r.y(start + i);
        }
        normal.noalias() += phi.topRows(rows).transpose() * phi.topRows(rows);
        rhs.noalias() += phi.topRows(rows).transpose() * target.head(rows);
      }
    }
    // Column scaling keeps the solve well conditioned whatever the units of u and y.
    Eigen::VectorXd scale = normal.diagonal().cwiseSqrt();
    for (int i = 0; i < p; ++i) if (!(scale(i) > 0)) scale(i) = 1;
    const Eigen::MatrixXd scaled = scale.cwiseInverse().asDiagonal() * normal * scale.cwiseInverse().asDiagonal();
    const Eigen::VectorXd theta =
        scale.cwiseInverse().asDiagonal() *
        scaled.completeOrthogonalDecomposition().solve(scale.cwiseInverse().asDiagonal() * rhs);
    double sum = 0;
    long count = 0;
    for (const auto& r : validation)
      for (long k = std::max<long>(n, r.score_from); k < r.u.size(); ++k) {
        Regressor(r, k, n, row.data());
        const double e = r.y(k) - row.dot(theta);
        sum += e * e;
        ++count;
      }
    if (count == 0) break;
    const double ar_gain = 1 + theta.head(n).squaredNorm();
    const double variance = sum / count / ar_gain;
    if (variance < best) {
      best = variance;
      floor.method = "arx_prediction";
      floor.sigma = std::sqrt(variance);
      floor.order = n;
      floor.ar_gain = ar_gain;
      floor.samples = count;
    }
  }
  if (floor.method.empty())
    throw std::invalid_argument("gap diagnosis: the records are too short to estimate the noise "
                                "floor (an ARX(4, 5) predictor needs 200 estimation samples)");
  return floor;
}

void ApplyNoiseFloor(double floor_nrmse, GapVerdict& v) {
  v.noise_nrmse = floor_nrmse;
  // A model that beats the floor shows that at least before − after was explainable: the floor
  // is then taken at the model (shrink 1), not left to inflate the share (a coarse quantiser,
  // whose rounding the floor counts as noise, read 9.75 on a 20000-sample record).
  const double explainable = v.nrmse_before - std::min(floor_nrmse, v.nrmse_after);
  v.shrink = explainable > 0 ? (v.nrmse_before - v.nrmse_after) / explainable : 0.0;
  v.remaining_gap_to_noise = v.nrmse_after - floor_nrmse;
  v.below_noise_floor = v.nrmse_after < floor_nrmse;
}

}  // namespace idrig
