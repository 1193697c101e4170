// FRF estimation from simulated time records, against the exact FRF of the sampled plant
// (seed 001's plant under a zero-order hold: H(e^{iωTs}) of its ZOH discretisation).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "core/numeric/signal/frf.h"
#include "tests/unit/numeric/seed001_plant.h"

namespace idrig {
namespace {

using Complex = std::complex<double>;
constexpr double kTs = 0.1;

StateSpace SampledPlant() { return DiscretizeZoh(ToStateSpace(testing::PlantTf()), kTs); }

Complex Exact(const StateSpace& d, double omega) { return FrequencyResponse(d, omega)(0, 0); }

TEST(FrfEstimation, PeriodicNoiseFreeIsExact) {
  // A random-phase periodic input (period 256 samples) repeated 6 times; the first period is
  // the transient. In periodic steady state Ȳ/Ū equals H(e^{iωTs}) exactly.
  const int np = 256, periods = 6;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n01;
  Eigen::VectorXd one(np);
  for (int i = 0; i < np; ++i) one(i) = n01(rng);
  Eigen::MatrixXd u(np * periods, 1);
  for (int p = 0; p < periods; ++p) u.block(p * np, 0, np, 1) = one;
  const StateSpace d = SampledPlant();
  // Start in periodic steady state: simulate one extra lead-in by skipping periods.
  const Eigen::MatrixXd y = Simulate(d, u, kTs);
  PeriodicOptions o;
  o.period_samples = np;
  o.skip_periods = 3;  // transient decays as e^{−0.5 t}: 3·25.6 s → 1e-17
  const Frf frf = EstimateFrfPeriodic(MakeIoRecord(u, y, kTs), o);
  ASSERT_EQ(frf.NumLines(), np / 2);
  EXPECT_EQ(frf.averages, 3);
  double worst = 0.0;
  for (int k = 0; k < frf.NumLines(); ++k) {
    const Complex h = Exact(d, frf.omega(k));
    worst = std::max(worst, std::abs(frf.h[k](0, 0) - h) / std::abs(h));
  }
  EXPECT_LT(worst, 1e-8);
  EXPECT_NEAR(frf.omega(0), 2 * M_PI / (np * kTs), 1e-12);  // rad/s
}

TEST(FrfEstimation, PeriodicNoiseVarianceMatchesScatter) {
  const int np = 128, periods = 40;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n01;
  Eigen::VectorXd one(np);
  for (int i = 0; i < np; ++i) one(i) = n01(rng);
  Eigen::MatrixXd u(np * periods, 1);
  for (int p = 0; p < periods; ++p) u.block(p * np, 0, np, 1) = one;
  const StateSpace d = SampledPlant();
  Eigen::MatrixXd y = Simulate(d, u, kTs);
  for (int i = 0; i < y.rows(); ++i) y(i, 0) += 0.02 * n01(rng);
  PeriodicOptions o;
  o.period_samples = np;
  o.skip_periods = 4;
  const Frf frf = EstimateFrfPeriodic(MakeIoRecord(u, y, kTs), o);
  // Σ|Ĥ − H|²/var over the lines is a χ² sum with mean = lines: the ratio is near 1.
  double ratio = 0.0;
  for (int k = 0; k < frf.NumLines(); ++k)
    ratio += std::norm(frf.h[k](0, 0) - Exact(d, frf.omega(k))) / frf.variance(k, 0);
  ratio /= frf.NumLines();
  std::printf("periodic: mean |H^-H|^2/var = %.3f over %d lines\n", ratio, frf.NumLines());
  EXPECT_GT(ratio, 0.7);
  EXPECT_LT(ratio, 1.4);
}

TEST(FrfEstimation, WelchH1MatchesExactFrf) {
  const int n = 1 << 15;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01;
  Eigen::MatrixXd u(n, 1);
  for (int i = 0; i < n; ++i) u(i, 0) = n01(rng);
  const StateSpace d = SampledPlant();
  Eigen::MatrixXd y = Simulate(d, u, kTs);
  Eigen::MatrixXd y_noisy = y;
  for (int i = 0; i < n; ++i) y_noisy(i, 0) += 0.01 * n01(rng);
  WelchOptions o;
  o.segment_length = 1024;
  const Frf clean = EstimateFrfWelch(MakeIoRecord(u, y, kTs), o);
  const Frf noisy = EstimateFrfWelch(MakeIoRecord(u, y_noisy, kTs), o);
  ASSERT_EQ(clean.NumLines(), 512);
  EXPECT_EQ(clean.averages, 1 + (n - 1024) / 512);
  double worst_clean = 0.0, worst_noisy = 0.0, min_coh_clean = 1.0;
  for (int k = 0; k < clean.NumLines(); ++k) {
    if (clean.omega(k) < 0.3 || clean.omega(k) > 3.0) continue;  // |H| > 0.04: above the noise
    const Complex h = Exact(d, clean.omega(k));
    worst_clean = std::max(worst_clean, std::abs(clean.h[k](0, 0) - h) / std::abs(h));
    worst_noisy = std::max(worst_noisy, std::abs(noisy.h[k](0, 0) - h) / std::abs(h));
    min_coh_clean = std::min(min_coh_clean, clean.coherence(k, 0));
  }
  std::printf("Welch H1 on 0.3-3 rad/s: worst relative error %.2e noise-free, %.2e with output noise\n",
              worst_clean, worst_noisy);
  // Hann-window leakage of the slow pole (0.5 rad/s) over 102 s segments bounds the error.
  EXPECT_LT(worst_clean, 0.03);  // leakage of a random, non-periodic input (measured 1.5e-2)
  EXPECT_LT(worst_noisy, 0.05);
  EXPECT_GT(min_coh_clean, 0.99);
  // With output noise the coherence drops where |H| is small.
  EXPECT_LT(noisy.coherence(noisy.NumLines() - 1, 0), 0.5);
}

TEST(FrfEstimation, WelchTwoInputsSeparatesTheChannels) {
  // y = W1 u1 + W2 u2 with independent white inputs: H1 = S_yu S_uu⁻¹ recovers both columns.
  const int n = 1 << 15;
  std::mt19937_64 rng(9);
  std::normal_distribution<double> n01;
  Eigen::MatrixXd u(n, 2);
  for (int i = 0; i < n; ++i) u.row(i) << n01(rng), n01(rng);
  const StateSpace d1 = SampledPlant();
  TransferFunction second;
  second.num = Eigen::VectorXd::Constant(1, 2.0);
  second.den = Eigen::Vector2d(1.0, 2.0);  // 2/(s + 2)
  const StateSpace d2 = DiscretizeZoh(ToStateSpace(second), kTs);
  const Eigen::MatrixXd y = Simulate(d1, u.col(0), kTs) + Simulate(d2, u.col(1), kTs);
  WelchOptions o;
  o.segment_length = 1024;
  const Frf frf = EstimateFrfWelch(MakeIoRecord(u, y, kTs), o);
  ASSERT_EQ(frf.NumInputs(), 2);
  double worst = 0.0;
  for (int k = 0; k < frf.NumLines(); ++k) {
    if (frf.omega(k) < 0.3 || frf.omega(k) > 3.0) continue;
    const Complex h1 = Exact(d1, frf.omega(k)), h2 = FrequencyResponse(d2, frf.omega(k))(0, 0);
    worst = std::max({worst, std::abs(frf.h[k](0, 0) - h1) / std::abs(h1), std::abs(frf.h[k](0, 1) - h2) / std::abs(h2)});
    EXPECT_GT(frf.coherence(k, 0), 0.99);  // noise-free: the two inputs explain y
  }
  std::printf("Welch H1, two inputs, 0.3-3 rad/s: worst relative error %.2e\n", worst);
  EXPECT_LT(worst, 0.03);
}

TEST(FrfEstimation, BadInput) {
  Eigen::MatrixXd u = Eigen::MatrixXd::Random(100, 1), y = Eigen::MatrixXd::Random(100, 1);
  IoRecord r = MakeIoRecord(u, y, 0.1);
  WelchOptions w;
  w.segment_length = 200;
  EXPECT_THROW(EstimateFrfWelch(r, w), std::invalid_argument);  // segment longer than record
  w.segment_length = 32;
  w.overlap = 1.0;
  EXPECT_THROW(EstimateFrfWelch(r, w), std::invalid_argument);
  IoRecord mismatched = r;
  mismatched.y = Eigen::MatrixXd::Random(90, 1);
  EXPECT_THROW(EstimateFrfWelch(mismatched, {}), std::invalid_argument);
  IoRecord nan = r;
  nan.y(10, 0) = NAN;
  EXPECT_THROW(EstimateFrfWelch(nan, {}), std::invalid_argument);
  PeriodicOptions p;
  p.period_samples = 60;  // fewer than 2 periods
  EXPECT_THROW(EstimateFrfPeriodic(r, p), std::invalid_argument);
  p.period_samples = 0;
  EXPECT_THROW(EstimateFrfPeriodic(r, p), std::invalid_argument);
  p.period_samples = 10;
  IoRecord zero_input = r;
  zero_input.u.setZero();
  EXPECT_THROW(EstimateFrfPeriodic(zero_input, p), std::invalid_argument);
  // ValidateFrf
  Frf f = MakeSisoFrf(Eigen::Vector3d(1, 2, 2), Eigen::Vector3cd(1, 1, 1));
  EXPECT_THROW(ValidateFrf(f), std::invalid_argument);  // not increasing
  f = MakeSisoFrf(Eigen::Vector3d(0, 1, 2), Eigen::Vector3cd(1, 1, 1));
  EXPECT_THROW(ValidateFrf(f), std::invalid_argument);  // ω = 0 not allowed by default
  EXPECT_NO_THROW(ValidateFrf(f, true));
}

}  // namespace
}  // namespace idrig
