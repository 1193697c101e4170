#pragma once
// Model validation used by every identification method:
//  - simulation fit 100·(1 − ‖y − ŷ‖/‖y − mean(y)‖) per output (MATLAB `compare` convention);
//  - residual whiteness (autocorrelation with a confidence band and a portmanteau test);
//  - input–residual cross-correlation (same band; independence of past inputs).
#include <Eigen/Dense>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace idrig {

// NRMSE = ‖y − ŷ‖ / ‖y − mean(y)‖ per column.
Eigen::VectorXd Nrmse(const Eigen::MatrixXd& measured, const Eigen::MatrixXd& simulated);
// 100·(1 − NRMSE) per column.
Eigen::VectorXd FitPercent(const Eigen::MatrixXd& measured, const Eigen::MatrixXd& simulated);

struct ResidualTestOptions {
  int max_lag = 25;           // lags 1..max_lag (autocorrelation), −max_lag..max_lag (cross)
  double confidence = 0.99;   // two-sided band ±z/√N for the normalised correlations
};

struct ResidualTest {
  Eigen::VectorXd autocorrelation;    // r_ee(k)/r_ee(0), k = 0..max_lag
  Eigen::VectorXd crosscorrelation;   // r_ue(k)/√(r_uu(0) r_ee(0)), k = −max_lag..max_lag
  double band = 0.0;                  // z_{(1+conf)/2}/√N
  int autocorrelation_outside = 0;    // lags 1..max_lag outside the band
  int crosscorrelation_outside = 0;   // lags −max_lag..max_lag outside the band
  double portmanteau_q = 0.0;         // Ljung–Box Q on lags 1..max_lag
  double portmanteau_threshold = 0.0; // χ²_{conf}(max_lag) (Wilson–Hilferty)
  double cross_q = 0.0;               // N Σ_{k=0..max_lag} r_ue(k)² (past inputs)
  double cross_threshold = 0.0;       // χ²_{conf}(max_lag + 1)
  bool white = false;                 // portmanteau_q <= portmanteau_threshold
  bool independent = false;           // cross_q <= cross_threshold
  std::string Summary() const;
};

// e and u are length-N residual and input sequences. Throws std::invalid_argument if
// N <= max_lag + 1 or the sizes differ.
ResidualTest TestResiduals(const Eigen::VectorXd& residual, const Eigen::VectorXd& input,
                           const ResidualTestOptions& options = {});

// Is a residual explained by past inputs, whatever the colour of either? The residual's own
// AR(p) polynomial A (least squares, pooled over the segments) whitens it, e' = A(q)e, and
// filters the input alike, u' = A(q)u; e' is then regressed on u'(t − k) and a constant, once
// for the near lags k = 0..d and once for far lags (geometric, ×1.25, from 1.25·d up to a
// quarter of the shortest segment), each at half the level. Under independence e' is (nearly)
// white and uncorrelated with every lag whatever u's colour, so N·R² follows χ²(number of
// lags) (the Lagrange-multiplier form of Ljung's cross-correlation test, [Ljung] §16.6, after
// Box–Jenkins prewhitening); the plain test above assumes a white residual or a white input
// and calls coloured noise "correlated" when the input is coloured. Segments (records) are
// filtered and lagged separately.
struct InputCorrelationTest {
  double statistic = 0.0, threshold = 0.0;          // near lags: N·R², χ²_{level}(lags)
  double far_statistic = 0.0, far_threshold = 0.0;  // far lags (0 when the records are too short)
  double explained_share = 0.0;                     // R² on the near lags
  long samples = 0;                                 // rows of the near regression
  int ar_order = 0, lags = 0, far_lags = 0;         // p, the number of near and far lags
  long max_lag = 0;                                 // the farthest lag tested
  bool correlated = false;                          // either statistic above its threshold
};
// segments: (residual, input) pairs of equal length. Throws std::invalid_argument when they
// differ in length or leave fewer than 10 (p + d + 2) rows for the near lags.
InputCorrelationTest TestInputCorrelationPrewhitened(
    const std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>>& segments, int ar_order = 10, int dense_lags = 20,
    double confidence = 0.999);

// Standard normal quantile (inverse CDF), for confidence bands.
double NormalQuantile(double p);
// χ² quantile with `dof` degrees of freedom, Wilson–Hilferty approximation.
double ChiSquareQuantile(double p, int dof);
// Whether a mean square `ratio` (mean of e², over the noise variance σ²) of `n` samples is more
// than noise: N·ratio above N + 3√(2N), the χ²_N sample variance three of its standard deviations
// up (one-sided, ≈ 99.9 %).
inline bool AboveNoiseVariance(double ratio, double n) { return n * ratio > n + 3 * std::sqrt(2.0 * n); }

}  // namespace idrig
