#pragma once
// Model validation used by every identification method:
//  - simulation fit 100·(1 − ‖y − ŷ‖/‖y − mean(y)‖) per output (MATLAB `compare` convention);
//  - residual whiteness (autocorrelation with a confidence band and a portmanteau test);
//  - input–residual cross-correlation (same band; independence of past inputs).
#include <Eigen/Dense>
#include <string>

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

// Standard normal quantile (inverse CDF), for confidence bands.
double NormalQuantile(double p);
// χ² quantile with `dof` degrees of freedom, Wilson–Hilferty approximation.
double ChiSquareQuantile(double p, int dof);

}  // namespace idrig
