// Pole–residue fitting (section 4 of [Balda], `ideSISO`) on an FRF synthesised from Balda's
// printed table of seven eigenvalues (PAPER_NUMBERS.md), residues of our choice.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "core/numeric/pole_residue.h"

namespace idrig {
namespace {

using Complex = std::complex<double>;
constexpr double kPi = 3.14159265358979323846;

// Balda's table, section 4.1: (Re s, Im s, printed Q).
const double kTable[7][3] = {{-1.33, 71.94, 27.14},  {-18.24, 70.53, 2.00},  {-2.05, 104.57, 25.55},
                             {-2.28, 110.53, 24.20}, {-22.37, 251.90, 5.65}, {-19.84, 315.03, 7.96},
                             {-32.15, 314.88, 4.92}};
// Our residues: a_ν = −i·σ_ν·h_ν (mechanical receptance form, peak height ≈ h_ν).
const double kHeight[7] = {1.0, 0.8, 0.6, 0.7, 0.9, 0.8, 0.6};

Eigen::VectorXcd Truth(const Eigen::VectorXd& omega) {
  Eigen::VectorXcd g = Eigen::VectorXcd::Zero(omega.size());
  for (int v = 0; v < 7; ++v) {
    const Complex s(kTable[v][0], kTable[v][1]), a(0.0, kTable[v][0] * kHeight[v]);
    for (int k = 0; k < omega.size(); ++k) {
      const Complex p(0.0, omega(k));
      g(k) += a / (p - s) + std::conj(a) / (p - std::conj(s));
    }
  }
  return g;
}

// Balda's band: his eigenvalues span 11.2–50.1 Hz (table, Re f column); we use 10–52 Hz.
Eigen::VectorXd BaldaBand(int lines) {
  return Eigen::VectorXd::LinSpaced(lines, 2 * kPi * 10.0, 2 * kPi * 52.0);
}

Frf Noisy(const Eigen::VectorXd& omega, double relative_noise, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  Eigen::VectorXcd g = Truth(omega);
  for (int k = 0; k < g.size(); ++k)
    g(k) += relative_noise * std::abs(g(k)) * Complex(n01(rng), n01(rng)) / std::sqrt(2.0);
  return MakeSisoFrf(omega, g);
}

// Balda's seven eigenvalues, 500 lines over 10–52 Hz, 1 % complex noise (relative, per line).
// Modes 1–5 (incl. the close pair 70.53/71.94 rad/s) meet the tolerances (Re s 5 %,
// Im s 0.5 %). The pair 315.03/314.88 rad/s (0.15 rad/s apart, half-bandwidths 20 and 32
// rad/s) does NOT at 1 % noise: the fit's cost is below the cost of the true parameters, so
// the optimiser found the least-squares minimum and the scatter is the noise's (it scales
// linearly: ~5 % at 0.1 % noise, see docs/frequency.md). We assert that, and a loose bound.
TEST(PoleResidue, RecoversBaldasSevenEigenvaluesWithOnePercentNoise) {
  const Eigen::VectorXd omega = BaldaBand(500);
  const Frf frf = Noisy(omega, 0.01, 20261123);
  PoleResidueOptions options;
  const PoleResidueResult r = FitPoleResidue(frf, options);
  std::printf("status %s, %s, %d LM iterations, fit %.2f %%\n", ToString(r.status), r.message.c_str(),
              r.iterations, r.fit_percent);
  std::printf(" k   Re s     Im s      Q     (printed Re s, Im s, Q)  err Re  err Im\n");
  ASSERT_EQ(r.modes.size(), 7u);
  for (int v = 0; v < 7; ++v) {
    const Complex truth(kTable[v][0], kTable[v][1]);
    const Mode* best = &r.modes[0];
    for (const auto& m : r.modes)
      if (std::abs(m.eigenvalue - truth) < std::abs(best->eigenvalue - truth)) best = &m;
    const double err_re = std::abs(best->eigenvalue.real() - truth.real()) / std::abs(truth.real());
    const double err_im = std::abs(best->eigenvalue.imag() - truth.imag()) / truth.imag();
    std::printf("%2d %7.2f %8.2f %6.2f   (%7.2f %8.2f %6.2f)  %5.1f %% %5.2f %%%s\n", v + 1,
                best->eigenvalue.real(), best->eigenvalue.imag(), best->q, kTable[v][0], kTable[v][1],
                kTable[v][2], 100 * err_re, 100 * err_im, best->fictitious ? "  (fictitious start)" : "");
    const bool pair_315 = v >= 5;
    EXPECT_LT(err_re, pair_315 ? 0.40 : 0.05) << "mode " << v + 1;
    EXPECT_LT(err_im, pair_315 ? 0.015 : 0.005) << "mode " << v + 1;
    // Q = |s|/(−2 Re s) reproduces the printed Q within the rounding of the printed Re s.
    EXPECT_NEAR(std::abs(truth) / (-2.0 * truth.real()), kTable[v][2],
                0.01 + kTable[v][2] * 0.005 / std::abs(kTable[v][0]));
  }
  EXPECT_TRUE(r.ok()) << r.message;
  // The least-squares minimum was reached: cost(fit) <= cost(true parameters).
  const Eigen::VectorXcd truth = Truth(omega);
  double truth_cost = 0.0;
  for (int k = 0; k < omega.size(); ++k) truth_cost += std::norm(truth(k) - frf.h[k](0, 0));
  std::printf("cost: fit %.5g, true parameters %.5g\n", r.final_cost, truth_cost);
  EXPECT_LE(r.final_cost, truth_cost);
}

TEST(PoleResidue, NoiseFreeIsExact) {
  const Frf frf = Noisy(BaldaBand(500), 0.0, 1);
  const PoleResidueResult r = FitPoleResidue(frf, {});
  ASSERT_EQ(r.modes.size(), 7u);
  for (int v = 0; v < 7; ++v) {
    const Complex truth(kTable[v][0], kTable[v][1]);
    double best = 1e300;
    for (const auto& m : r.modes) best = std::min(best, std::abs(m.eigenvalue - truth));
    EXPECT_LT(best, 1e-6 * std::abs(truth)) << "mode " << v + 1;
  }
  EXPECT_NEAR(std::abs(r.origin_correction), 0.0, 1e-8);
}

TEST(PoleResidue, PeaksFindsTheSharpResonances) {
  const Frf frf = Noisy(BaldaBand(500), 0.0, 1);
  const std::vector<int> peaks = FindPeaks(frf.Element().cwiseAbs(), 0.05);
  std::vector<double> at;
  for (int i : peaks) at.push_back(frf.omega(i));
  // The three lightly damped modes near 72, 105 and 111 rad/s are separate peaks.
  for (double expected : {71.94, 104.57, 110.53}) {
    bool found = false;
    for (double w : at) found |= std::abs(w - expected) < 2.0;
    EXPECT_TRUE(found) << "peak near " << expected;
  }
}

TEST(PoleResidue, SingleModeClosedForm) {
  // g = a/(p − s) + ā/(p − s̄): one peak, no fictitious poles, no h_o: exact from the start.
  const Complex s(-0.5, 10.0), a(0.0, -0.25);
  Eigen::VectorXd omega = Eigen::VectorXd::LinSpaced(200, 5.0, 15.0);
  Eigen::VectorXcd g(200);
  for (int k = 0; k < 200; ++k) {
    const Complex p(0.0, omega(k));
    g(k) = a / (p - s) + std::conj(a) / (p - std::conj(s));
  }
  PoleResidueOptions options;
  options.fictitious_poles = false;
  options.origin_correction = false;
  const PoleResidueResult r = FitPoleResidue(MakeSisoFrf(omega, g), options);
  ASSERT_EQ(r.modes.size(), 1u);
  EXPECT_NEAR(std::abs(r.modes[0].eigenvalue - s), 0.0, 1e-9);
  EXPECT_NEAR(std::abs(r.modes[0].residue - a), 0.0, 1e-9);
  EXPECT_NEAR(r.modes[0].q, std::abs(s) / 1.0, 1e-7);  // |s|/(−2 Re s)
  EXPECT_NEAR(r.modes[0].damping_ratio, 0.5 / std::abs(s), 1e-10);
  // The 5-point start (29)–(31) alone is already close for an isolated peak.
  EXPECT_NEAR(std::abs(r.initial_modes[0].eigenvalue - s), 0.0, 0.05);
}

TEST(PoleResidue, LiteralEquation26WithoutConjugates) {
  // (26)/(35) as printed: g = Σ a_ν/(p − s_ν) + h_o with complex h_o, no conjugate terms.
  const Eigen::VectorXd omega = BaldaBand(500);
  const Complex h_o(0.01, -0.02);
  Eigen::VectorXcd g = Eigen::VectorXcd::Constant(omega.size(), h_o);
  for (int v = 0; v < 7; ++v) {
    const Complex s(kTable[v][0], kTable[v][1]), a(0.0, kTable[v][0] * kHeight[v]);
    for (int k = 0; k < omega.size(); ++k) g(k) += a / (Complex(0.0, omega(k)) - s);
  }
  PoleResidueOptions options;
  options.conjugate_pairs = false;
  const PoleResidueResult r = FitPoleResidue(MakeSisoFrf(omega, g), options);
  ASSERT_EQ(r.modes.size(), 7u);
  for (int v = 0; v < 7; ++v) {
    const Complex truth(kTable[v][0], kTable[v][1]);
    double best = 1e300;
    for (const auto& m : r.modes) best = std::min(best, std::abs(m.eigenvalue - truth));
    EXPECT_LT(best, 1e-6 * std::abs(truth)) << "mode " << v + 1;
  }
  EXPECT_LT(std::abs(r.origin_correction - h_o), 1e-8);
}

TEST(PoleResidue, BadInput) {
  Eigen::VectorXd omega = BaldaBand(50);
  Eigen::VectorXcd g = Truth(omega);
  EXPECT_THROW(FitPoleResidue(MakeSisoFrf(omega, g.head(3)), {}), std::invalid_argument);  // 50 ω, 3 values
  Eigen::VectorXcd bad = g;
  bad(7) = Complex(NAN, 0.0);
  EXPECT_THROW(FitPoleResidue(MakeSisoFrf(omega, bad), {}), std::invalid_argument);
  Eigen::VectorXd neg = omega;
  neg(0) = 0.0;
  EXPECT_THROW(FitPoleResidue(MakeSisoFrf(neg, g), {}), std::invalid_argument);
  PoleResidueOptions outside;
  outside.peak_omegas = {1000.0};
  EXPECT_THROW(FitPoleResidue(MakeSisoFrf(omega, g), outside), std::invalid_argument);
  // 6 lines cannot carry 7 poles (30 unknowns).
  PoleResidueOptions many;
  many.peak_omegas = {omega(0), omega(1), omega(2), omega(3), omega(4)};
  EXPECT_THROW(FitPoleResidue(MakeSisoFrf(omega.head(6), g.head(6)), many), std::invalid_argument);
  PoleResidueOptions weights;
  weights.weights = Eigen::VectorXd::Ones(3);
  EXPECT_THROW(FitPoleResidue(MakeSisoFrf(omega, g), weights), std::invalid_argument);
  // Non-convergence is reported, not thrown.
  PoleResidueOptions short_run;
  short_run.max_function_evaluations = 2;
  const PoleResidueResult r = FitPoleResidue(Noisy(BaldaBand(500), 0.01, 3), short_run);
  EXPECT_EQ(r.status, SolverStatus::kNotConverged);
  EXPECT_FALSE(r.message.empty());
}

}  // namespace
}  // namespace idrig
