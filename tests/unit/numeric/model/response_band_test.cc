// The ARX frequency-response band: |W| and ∠W against the model's own frequency response
// (lti_model's FrequencyResponse, independent code), and the delta-method standard deviations
// against a Monte Carlo over parameters drawn from the same covariance (seeded).
#include "core/numeric/model/response_band.h"

#include <gtest/gtest.h>

#include <random>

#include "core/numeric/model/lti_model.h"

namespace idrig {
namespace {

TEST(ResponseBand, MatchesFrequencyResponseAndMonteCarlo) {
  // Second-order ARX: y_k − 1.5 y_{k−1} + 0.7 y_{k−2} = 0.1 u_{k−1} + 0.05 u_{k−2}; g = (−c; d).
  Eigen::VectorXd g(4);
  g << 1.5, -0.7, 0.1, 0.05;
  const double ts = 0.1;
  Eigen::MatrixXd L(4, 4);
  L << 1e-3, 0, 0, 0, 5e-4, 8e-4, 0, 0, 0, 1e-4, 5e-4, 0, 1e-4, 0, 2e-4, 4e-4;
  const Eigen::MatrixXd cov = L * L.transpose();
  Eigen::VectorXd omega(4);
  omega << 0.3, 2.0, 5.0, 20.0;
  const ResponseBand band = ArxResponseBand(g, cov, ts, 1, omega);

  TransferFunction tf;
  tf.num = Eigen::Vector2d(0.1, 0.05);
  tf.den = Eigen::Vector3d(1.0, -1.5, 0.7);
  tf.sample_time = ts;
  const Eigen::VectorXcd w = FrequencyResponse(tf, omega);
  for (int k = 0; k < omega.size(); ++k) {
    EXPECT_NEAR(band.magnitude(k), std::abs(w(k)), 1e-12 * std::abs(w(k)));
    EXPECT_NEAR(std::remainder(band.phase_rad(k) - std::arg(w(k)), 2 * M_PI), 0.0, 1e-12);
  }
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  const int draws = 20000;
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(4), sum2 = sum, psum = sum, psum2 = sum;
  for (int i = 0; i < draws; ++i) {
    Eigen::VectorXd e(4);
    for (int j = 0; j < 4; ++j) e(j) = normal(rng);
    const Eigen::VectorXd gi = g + L * e;
    TransferFunction ti;
    ti.num = gi.tail(2);
    ti.den = Eigen::Vector3d(1.0, -gi(0), -gi(1));
    ti.sample_time = ts;
    const Eigen::VectorXcd wi = FrequencyResponse(ti, omega);
    for (int k = 0; k < 4; ++k) {
      const double m = std::abs(wi(k));
      const double p = std::remainder(std::arg(wi(k)) - std::arg(w(k)), 2 * M_PI);
      sum(k) += m, sum2(k) += m * m, psum(k) += p, psum2(k) += p * p;
    }
  }
  for (int k = 0; k < 4; ++k) {
    const double sd = std::sqrt(sum2(k) / draws - std::pow(sum(k) / draws, 2));
    const double psd = std::sqrt(psum2(k) / draws - std::pow(psum(k) / draws, 2));
    // Monte Carlo standard error of a standard deviation ~ 1/sqrt(2·draws) = 0.5 %; the
    // linearisation error is of the order of the relative spread (a few %): 10 % tolerance.
    EXPECT_NEAR(band.magnitude_std(k), sd, 0.1 * sd) << "omega " << omega(k);
    EXPECT_NEAR(band.phase_std_rad(k), psd, 0.1 * psd) << "omega " << omega(k);
  }
}

TEST(ResponseBand, DelayShiftsPhaseOnly) {
  Eigen::VectorXd g(2);
  g << 0.8, 0.2;
  Eigen::MatrixXd cov = Eigen::MatrixXd::Identity(2, 2) * 1e-4;
  Eigen::VectorXd omega(1);
  omega << 1.0;
  const auto a = ArxResponseBand(g, cov, 0.1, 1, omega), b = ArxResponseBand(g, cov, 0.1, 3, omega);
  EXPECT_DOUBLE_EQ(a.magnitude(0), b.magnitude(0));
  EXPECT_NEAR(a.phase_rad(0) - b.phase_rad(0), 2 * 1.0 * 0.1, 1e-12);
}

TEST(ResponseBand, BadInputIsNamed) {
  Eigen::VectorXd omega(1);
  omega << 1.0;
  EXPECT_THROW(ArxResponseBand(Eigen::VectorXd::Ones(3), Eigen::MatrixXd::Identity(3, 3), 0.1, 1, omega),
               std::invalid_argument);
  EXPECT_THROW(ArxResponseBand(Eigen::VectorXd::Ones(2), Eigen::MatrixXd::Identity(3, 3), 0.1, 1, omega),
               std::invalid_argument);
  omega << 100.0;  // above π/Ts
  EXPECT_THROW(ArxResponseBand(Eigen::VectorXd::Ones(2), Eigen::MatrixXd::Identity(2, 2), 0.1, 1, omega),
               std::invalid_argument);
}

}  // namespace
}  // namespace idrig
