// The prewhitened input–residual test (validation.h): its false-alarm rate under coloured noise
// and a coloured input is the nominal level (a closed form: χ²(m + 1)), where the plain
// cross-correlation test, which assumes whiteness, calls most such residuals correlated; and it
// finds a small linear model error under the same noise.
#include <gtest/gtest.h>

#include <random>

#include "core/numeric/validation.h"

namespace idrig {
namespace {

// A first-order filter x(t) = pole·x(t−1) + w(t) of white noise.
Eigen::VectorXd Ar1(std::mt19937& rng, long n, double pole) {
  std::normal_distribution<double> w;
  Eigen::VectorXd x(n);
  double s = 0;
  for (long t = 0; t < n; ++t) x(t) = s = pole * s + w(rng);
  return x;
}

TEST(InputCorrelationTest, ColouredNoiseUnderAColouredInputIsNotCalledCorrelated) {
  const int runs = 200;
  int prewhitened_alarms = 0, plain_alarms = 0;
  for (int seed = 0; seed < runs; ++seed) {
    std::mt19937 rng(seed);
    const Eigen::VectorXd u = Ar1(rng, 2000, 0.95), e = Ar1(rng, 2000, 0.9);
    if (TestInputCorrelationPrewhitened({{e, u}}).correlated) ++prewhitened_alarms;
    if (!TestResiduals(e, u, {20, 0.999}).independent) ++plain_alarms;
  }
  // Nominal 0.1 %: at most 2 of 200 allows for the approximation (P(Binomial(200, 0.001) > 2) ≈ 0.1 %,
  // with an AR(10) fitted on 2000 samples the level is a little above nominal).
  EXPECT_LE(prewhitened_alarms, 3);
  EXPECT_GT(plain_alarms, runs / 4) << "the plain test is expected to be fooled by the colours";
}

TEST(InputCorrelationTest, FindsASmallLinearModelErrorUnderColouredNoise) {
  int found = 0;
  for (int seed = 0; seed < 50; ++seed) {
    std::mt19937 rng(1000 + seed);
    const Eigen::VectorXd u = Ar1(rng, 2000, 0.95), noise = Ar1(rng, 2000, 0.9);
    // A model error of 5 % of the input's response through a lag, under noise whose RMS is
    // about twice that error's.
    Eigen::VectorXd e = noise;
    double s = 0;
    for (long t = 1; t < u.size(); ++t) e(t) += 0.05 * (s = 0.8 * s + 0.2 * u(t - 1)) * 10;
    if (TestInputCorrelationPrewhitened({{e, u}}).correlated) ++found;
  }
  EXPECT_GE(found, 49);
}

TEST(InputCorrelationTest, SegmentsAreLaggedSeparatelyAndBadInputIsRefused) {
  std::mt19937 rng(7);
  const Eigen::VectorXd u1 = Ar1(rng, 600, 0.5), e1 = Ar1(rng, 600, 0.5);
  const Eigen::VectorXd u2 = Ar1(rng, 600, 0.5), e2 = Ar1(rng, 600, 0.5);
  const InputCorrelationTest two = TestInputCorrelationPrewhitened({{e1, u1}, {e2, u2}});
  EXPECT_EQ(two.samples, 2 * (600 - 10 - 20));
  EXPECT_GT(two.far_lags, 5);  // geometric lags up to (600 - 10) / 4
  EXPECT_THROW(TestInputCorrelationPrewhitened({{e1, u1.head(500)}}), std::invalid_argument);
  EXPECT_THROW(TestInputCorrelationPrewhitened({{e1.head(100), u1.head(100)}}), std::invalid_argument);
}

}  // namespace
}  // namespace idrig
