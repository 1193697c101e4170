// Levy (4)–(7), Sanathanan–Koerner reweighting (8) and the stable nonlinear regression
// (9)–(12) of [Balda], section 2.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "core/numeric/frequency_domain/stable_nls.h"
#include "tests/unit/numeric/seed001_plant.h"

namespace idrig {
namespace {

using Complex = std::complex<double>;

// "x % noise": additive complex Gaussian noise with σ = x·max|G| on every line (the usual
// measurement situation: the noise floor does not follow the response down).
Frf PlantFrf(const TransferFunction& tf, const Eigen::VectorXd& omega, double noise, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  Eigen::VectorXcd g = FrequencyResponse(tf, omega);
  const double sigma = noise * g.cwiseAbs().maxCoeff();
  for (int k = 0; k < g.size(); ++k) g(k) += sigma * Complex(n01(rng), n01(rng)) / std::sqrt(2.0);
  return MakeSisoFrf(omega, g);
}

Eigen::VectorXd LogLines(int lines, double lo, double hi) {
  Eigen::VectorXd w(lines);
  for (int k = 0; k < lines; ++k) w(k) = lo * std::pow(hi / lo, k / (lines - 1.0));
  return w;
}

TEST(Levy, NoiseFreeRecoversSeed001PlantExactly) {
  const TransferFunction plant = testing::PlantTf();
  const Frf frf = PlantFrf(plant, LogLines(100, 0.05, 20.0), 0.0, 1);
  LevyOptions options;
  options.denominator_degree = 3;
  options.numerator_degree = 1;
  for (int sk : {0, 30}) {
    options.max_sk_iterations = sk;
    const LevyResult r = FitLevy(frf, options);
    ASSERT_TRUE(r.ok()) << r.message;
    EXPECT_LT((r.model.den - plant.den).norm(), 1e-9);
    EXPECT_LT((r.model.num - plant.num).norm(), 1e-9);
    EXPECT_TRUE(r.stable);
  }
}

// Issue acceptance: 1 % noise on the plant's FRF; the reweighted fit's pole error is at least
// 5× smaller than plain Levy's.
TEST(Levy, SanathananKoernerRemovesLevysBias) {
  const TransferFunction plant = testing::PlantTf();
  const Eigen::VectorXcd true_poles = Poles(plant);
  const Frf frf = PlantFrf(plant, LogLines(200, 0.05, 20.0), 0.01, 20261123);
  LevyOptions options;
  options.denominator_degree = 3;
  options.numerator_degree = 1;
  options.max_sk_iterations = 0;
  const LevyResult levy = FitLevy(frf, options);
  options.max_sk_iterations = 50;
  const LevyResult sk = FitLevy(frf, options);
  const double e_levy = testing::MaxPoleDistance(true_poles, levy.poles);
  const double e_sk = testing::MaxPoleDistance(true_poles, sk.poles);
  std::printf("pole error: plain Levy %.4g, SK %.4g (%d iterations, %s), ratio %.1f\n", e_levy, e_sk,
              sk.sk_iterations, sk.message.c_str(), e_levy / e_sk);
  EXPECT_TRUE(sk.ok()) << sk.message;
  EXPECT_TRUE(sk.sk_converged);
  EXPECT_LE(5.0 * e_sk, e_levy);
  EXPECT_LT(sk.cost_history.back(), sk.cost_history.front());
}

// A noisy, over-parameterised fit: Levy/SK place spurious right-half-plane poles; the stable
// regression (9)/(12) stays stable and fits at least as well.
TEST(StableNls, StableWhereLevyAndSkAreNot) {
  const TransferFunction plant = testing::PlantTf();
  const Frf frf = PlantFrf(plant, LogLines(120, 0.05, 20.0), 0.02, 2);  // 2 % noise, order 5/4 for a 3/1 plant
  LevyOptions lo;
  lo.denominator_degree = 5;
  lo.numerator_degree = 4;
  lo.max_sk_iterations = 0;
  const LevyResult levy = FitLevy(frf, lo);
  lo.max_sk_iterations = 30;
  const LevyResult sk = FitLevy(frf, lo);
  StableNlsOptions so;
  so.denominator_degree = 5;
  so.numerator_degree = 4;
  so.square_numerator = false;
  const StableNlsResult nls = FitStableNls(frf, so);
  std::printf("Levy: stable %d cost %.5g | SK: stable %d cost %.5g | stable NLS: stable %d cost %.5g (%s, start %.5g)\n",
              levy.stable, levy.final_cost, sk.stable, sk.final_cost, nls.stable, nls.final_cost,
              nls.message.c_str(), nls.start_cost);
  std::printf("SK poles:");
  for (int i = 0; i < sk.poles.size(); ++i) std::printf(" (%.3g,%.3g)", sk.poles(i).real(), sk.poles(i).imag());
  std::printf("\nNLS poles:");
  for (int i = 0; i < nls.poles.size(); ++i) std::printf(" (%.3g,%.3g)", nls.poles(i).real(), nls.poles(i).imag());
  std::printf("\n");
  EXPECT_FALSE(levy.stable);
  EXPECT_FALSE(sk.stable);
  EXPECT_TRUE(nls.stable);
  EXPECT_TRUE(nls.ok()) << nls.message;
  EXPECT_LT(nls.poles.real().maxCoeff(), 0.0);
  EXPECT_LE(nls.final_cost, sk.final_cost * (1.0 + 1e-9));
  EXPECT_LE(nls.final_cost, levy.final_cost * (1.0 + 1e-9));
}

TEST(StableNls, NoiseFreeRecoversPlant) {
  const TransferFunction plant = testing::PlantTf();
  const Frf frf = PlantFrf(plant, LogLines(100, 0.05, 20.0), 0.0, 1);
  StableNlsOptions so;
  so.denominator_degree = 3;
  so.numerator_degree = 1;
  const StableNlsResult r = FitStableNls(frf, so);
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_TRUE(r.stable);
  EXPECT_LT(testing::MaxPoleDistance(Poles(plant), r.poles), 1e-6);
  EXPECT_LT((r.model.num - plant.num).norm(), 1e-6);
}

TEST(RationalFit, BadInput) {
  const Eigen::VectorXd omega = LogLines(20, 0.1, 10.0);
  const Eigen::VectorXcd g = FrequencyResponse(testing::PlantTf(), omega);
  LevyOptions o;
  o.denominator_degree = 3;
  o.numerator_degree = 1;
  EXPECT_NO_THROW(FitLevy(MakeSisoFrf(omega, g), o));
  // mismatched lengths
  EXPECT_THROW(MakeSisoFrf(omega, g.head(10)), std::invalid_argument);
  Frf mismatched = MakeSisoFrf(omega, g);
  mismatched.h.pop_back();
  EXPECT_THROW(FitLevy(mismatched, o), std::invalid_argument);
  // zero / negative frequency
  Eigen::VectorXd zero = omega;
  zero(0) = 0.0;
  EXPECT_THROW(FitLevy(MakeSisoFrf(zero, g), o), std::invalid_argument);
  zero(0) = -1.0;
  EXPECT_THROW(FitStableNls(MakeSisoFrf(zero, g), {}), std::invalid_argument);
  // NaN in the FRF
  Eigen::VectorXcd nan = g;
  nan(5) = Complex(0.0, NAN);
  try {
    FitLevy(MakeSisoFrf(omega, nan), o);
    ADD_FAILURE() << "NaN accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("line 5"), std::string::npos) << e.what();
  }
  // fewer lines than parameters: 2 lines = 4 equations for 5 unknowns
  EXPECT_THROW(FitLevy(MakeSisoFrf(omega.head(2), g.head(2)), o), std::invalid_argument);
  // bad degrees, weights
  LevyOptions bad = o;
  bad.denominator_degree = 0;
  EXPECT_THROW(FitLevy(MakeSisoFrf(omega, g), bad), std::invalid_argument);
  bad = o;
  bad.weights = Eigen::VectorXd::Ones(3);
  EXPECT_THROW(FitLevy(MakeSisoFrf(omega, g), bad), std::invalid_argument);
  StableNlsOptions improper;
  improper.denominator_degree = 2;
  improper.numerator_degree = 3;
  EXPECT_THROW(FitStableNls(MakeSisoFrf(omega, g), improper), std::invalid_argument);
  // Non-convergence reported, not thrown.
  const Frf noisy = PlantFrf(testing::PlantTf(), LogLines(100, 0.05, 20.0), 0.05, 3);
  LevyOptions one = o;
  one.max_sk_iterations = 1;
  const LevyResult r = FitLevy(noisy, one);
  EXPECT_EQ(r.status, SolverStatus::kNotConverged);
  EXPECT_FALSE(r.sk_converged);
  StableNlsOptions so;
  so.denominator_degree = 3;
  so.max_function_evaluations = 2;
  const StableNlsResult n = FitStableNls(noisy, so);
  EXPECT_EQ(n.status, SolverStatus::kNotConverged);
}

}  // namespace
}  // namespace idrig
