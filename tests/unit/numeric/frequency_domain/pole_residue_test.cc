// Pole–residue fitting (section 4 of [Balda], `ideSISO`) on an FRF synthesised from Balda's
// printed table of seven eigenvalues (PAPER_NUMBERS.md), residues of our choice.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/numeric/frequency_domain/pole_residue.h"

namespace idrig {
namespace {

using Complex = std::complex<double>;
constexpr double kPi = 3.14159265358979323846;

// Balda's table, section 4.1: (Re s, Im s, printed Q).
const double kTable[7][3] = {{-1.33, 71.94, 27.14},  {-18.24, 70.53, 2.00},  {-2.05, 104.57, 25.55},
                             {-2.28, 110.53, 24.20}, {-22.37, 251.90, 5.65}, {-19.84, 315.03, 7.96},
                             {-32.15, 314.88, 4.92}};
// Residues are ours to choose (the issue; Balda's data are unpublished). a_ν = −i·σ_ν·h_ν is
// the mechanical receptance form, peak height ≈ h_ν. All of the same sign, the pair near
// 315 rad/s (0.15 rad/s apart, half-bandwidths 20 and 32 rad/s) sums to one smooth hump and
// is not identifiable at 1 % noise: its Cramér–Rao bound on Re s exceeds the 5 % asked (test
// SameSignPairIsLimitedByTheCramerRaoBound). Close modes at a point away from the drive
// often have modal constants of opposite sign; with a₆ 4× stronger and a₇ = −1.5·a₆ the
// bound is 1.4 % / 2.0 % and the tolerances are 3.5σ / 2.5σ away.
const double kHeight[7] = {1.0, 0.8, 0.6, 0.7, 0.9, 0.8, 0.6};
using Residues = std::array<Complex, 7>;

Residues SameSign() {
  Residues a;
  for (int v = 0; v < 7; ++v) a[v] = Complex(0.0, kTable[v][0] * kHeight[v]);
  return a;
}

Residues OppositePair() {
  Residues a = SameSign();
  a[5] *= 4.0;
  a[6] = -1.5 * a[5];
  return a;
}

Eigen::VectorXcd Truth(const Eigen::VectorXd& omega, const Residues& a = SameSign()) {
  Eigen::VectorXcd g = Eigen::VectorXcd::Zero(omega.size());
  for (int v = 0; v < 7; ++v) {
    const Complex s(kTable[v][0], kTable[v][1]);
    for (int k = 0; k < omega.size(); ++k) {
      const Complex p(0.0, omega(k));
      g(k) += a[v] / (p - s) + std::conj(a[v]) / (p - std::conj(s));
    }
  }
  return g;
}

// Balda's band: his eigenvalues span 11.2–50.1 Hz (table, Re f column); we use 10–52 Hz.
Eigen::VectorXd BaldaBand(int lines) {
  return Eigen::VectorXd::LinSpaced(lines, 2 * kPi * 10.0, 2 * kPi * 52.0);
}

// Complex noise, relative to |g| on each line: variance (relative_noise·|g_k|)².
Frf Noisy(const Eigen::VectorXd& omega, double relative_noise, uint64_t seed, const Residues& a = SameSign()) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  Eigen::VectorXcd g = Truth(omega, a);
  for (int k = 0; k < g.size(); ++k)
    g(k) += relative_noise * std::abs(g(k)) * Complex(n01(rng), n01(rng)) / std::sqrt(2.0);
  return MakeSisoFrf(omega, g);
}

// The fitted mode nearest to table row v.
const Mode& Nearest(const PoleResidueResult& r, int v) {
  const Complex truth(kTable[v][0], kTable[v][1]);
  const Mode* best = &r.modes[0];
  for (const auto& m : r.modes)
    if (std::abs(m.eigenvalue - truth) < std::abs(best->eigenvalue - truth)) best = &m;
  return *best;
}

// Cramér–Rao bound of Re s_ν and Im s_ν for the model the method fits — seven modes and the
// origin correction h_o (25) — written out here independently of the fit: θ = (Re s, Im s,
// Re a, Im a) per mode and (Re h_o, Im h_o); ∂g/∂Re s = a/(p−s)² + ā/(p−s̄)², ∂g/∂Im s =
// i·a/(p−s)² − i·ā/(p−s̄)², ∂g/∂Re a = 1/(p−s) + 1/(p−s̄), ∂g/∂Im a = i/(p−s) − i/(p−s̄),
// ∂g/∂h_o = 1, i; circular complex noise of variance σ_k² gives the Fisher matrix
// F = Σ_k 2·Re(J_kᴴ J_k)/σ_k². Returns the standard deviations (7×2).
Eigen::MatrixXd CramerRao(const Eigen::VectorXd& omega, const Residues& a, double relative_noise) {
  const Eigen::VectorXcd g = Truth(omega, a);
  Eigen::MatrixXd fisher = Eigen::MatrixXd::Zero(30, 30);
  for (int k = 0; k < omega.size(); ++k) {
    const Complex p(0.0, omega(k));
    Eigen::VectorXcd j(30);
    j(28) = 1.0;
    j(29) = Complex(0, 1);
    for (int v = 0; v < 7; ++v) {
      const Complex s(kTable[v][0], kTable[v][1]), d1 = 1.0 / (p - s), d2 = 1.0 / (p - std::conj(s));
      j(4 * v) = a[v] * d1 * d1 + std::conj(a[v]) * d2 * d2;
      j(4 * v + 1) = Complex(0, 1) * (a[v] * d1 * d1 - std::conj(a[v]) * d2 * d2);
      j(4 * v + 2) = d1 + d2;
      j(4 * v + 3) = Complex(0, 1) * (d1 - d2);
    }
    const double variance = std::norm(relative_noise * std::abs(g(k)));
    fisher += 2.0 * (j.conjugate() * j.transpose()).real() / variance;
  }
  const Eigen::MatrixXd cov = fisher.inverse();
  Eigen::MatrixXd sd(7, 2);
  for (int v = 0; v < 7; ++v) sd.row(v) << std::sqrt(cov(4 * v, 4 * v)), std::sqrt(cov(4 * v + 1, 4 * v + 1));
  return sd;
}

// Measurement weights for relative noise: w_k = 1/|g_k| (maximum likelihood).
PoleResidueOptions RelativeNoiseWeights(const Frf& frf) {
  PoleResidueOptions options;
  options.weights = frf.Element().cwiseAbs().cwiseInverse();
  return options;
}

// The acceptance: Balda's seven eigenvalues, 500 lines over 10–52 Hz, 1 % complex
// noise, all seven within Re s 5 % and Im s 0.5 %, the close pairs near 71 and 315 rad/s
// included — on ten noise realisations, not one. `peaks` finds five resonances (the upper
// hump of the 315 pair lies at the band's edge and is no peak); the two fictitious poles
// converge to the broad modes under the 71.94 and 315 peaks (in Balda's table rows 2 and 7
// are most likely his fictitious poles too); the pole the peaks missed is taken from the
// residual (max_residual_poles).
TEST(PoleResidue, RecoversBaldasSevenEigenvaluesWithOnePercentNoise) {
  const Eigen::VectorXd omega = BaldaBand(500);
  const Eigen::MatrixXd bound = CramerRao(omega, OppositePair(), 0.01);
  for (int seed = 1; seed <= 10; ++seed) {
    const Frf frf = Noisy(omega, 0.01, seed, OppositePair());
    const PoleResidueResult r = FitPoleResidue(frf, RelativeNoiseWeights(frf));
    ASSERT_TRUE(r.ok()) << r.message;
    ASSERT_EQ(r.modes.size(), 7u) << "seed " << seed << ": " << r.message;
    if (seed == 1) {
      std::printf("seed 1: %s, %d LM iterations, fit %.2f %%\n", r.message.c_str(), r.iterations, r.fit_percent);
      std::printf(" k   Re s     Im s      Q     (printed Re s, Im s, Q)  err Re  err Im   std Re (CRB)\n");
    }
    for (int v = 0; v < 7; ++v) {
      const Mode& m = Nearest(r, v);
      const double err_re = std::abs(m.eigenvalue.real() - kTable[v][0]) / std::abs(kTable[v][0]);
      const double err_im = std::abs(m.eigenvalue.imag() - kTable[v][1]) / kTable[v][1];
      if (seed == 1)
        std::printf("%2d %7.2f %8.2f %6.2f   (%7.2f %8.2f %6.2f)  %5.1f %% %5.2f %%  %5.2f (%5.2f)%s\n", v + 1,
                    m.eigenvalue.real(), m.eigenvalue.imag(), m.q, kTable[v][0], kTable[v][1], kTable[v][2],
                    100 * err_re, 100 * err_im, m.std_real, bound(v, 0),
                    m.fictitious ? "  fictitious start" : m.from_residual ? "  from the residual" : "");
      EXPECT_LT(err_re, 0.05) << "seed " << seed << " mode " << v + 1;
      EXPECT_LT(err_im, 0.005) << "seed " << seed << " mode " << v + 1;
      // The reported standard error is the Cramér–Rao bound evaluated at the estimate.
      EXPECT_GT(m.std_real, 0.5 * bound(v, 0)) << "seed " << seed << " mode " << v + 1;
      EXPECT_LT(m.std_real, 2.0 * bound(v, 0)) << "seed " << seed << " mode " << v + 1;
    }
  }
  for (int v = 0; v < 7; ++v) {
    // Q = |s|/(−2 Re s) reproduces the printed Q within the rounding of the printed Re s.
    EXPECT_NEAR(std::hypot(kTable[v][0], kTable[v][1]) / (-2.0 * kTable[v][0]), kTable[v][2],
                0.01 + kTable[v][2] * 0.005 / std::abs(kTable[v][0]));
  }
}

// Same-sign residues: the 315 pair's Re s cannot be had within 5 % at 1 % noise by any
// unbiased estimator — the bound itself exceeds it. The fit is efficient there: its scatter
// over seeds agrees with the bound, and the standard errors it reports say that those two
// damping values are uncertain.
TEST(PoleResidue, SameSignPairIsLimitedByTheCramerRaoBound) {
  const Eigen::VectorXd omega = BaldaBand(500);
  const Eigen::MatrixXd bound = CramerRao(omega, SameSign(), 0.01);
  std::printf("Cramer-Rao bound, same-sign residues: Re s %.1f %% and %.1f %%, Im s %.2f %% and %.2f %%\n",
              100 * bound(5, 0) / 19.84, 100 * bound(6, 0) / 32.15, 100 * bound(5, 1) / 315.03,
              100 * bound(6, 1) / 314.88);
  EXPECT_GT(bound(5, 0), 0.05 * 19.84);
  EXPECT_GT(bound(6, 0), 0.05 * 32.15);
  const int seeds = 12;
  Eigen::Vector2d squared = Eigen::Vector2d::Zero(), reported = Eigen::Vector2d::Zero();
  for (int seed = 1; seed <= seeds; ++seed) {
    const Frf frf = Noisy(omega, 0.01, 100 + seed, SameSign());
    const PoleResidueResult r = FitPoleResidue(frf, RelativeNoiseWeights(frf));
    ASSERT_GE(r.modes.size(), 7u) << r.message;  // the nearest fitted pole to each eigenvalue
    for (int v = 5; v < 7; ++v) {
      const Mode& m = Nearest(r, v);
      squared(v - 5) += std::pow(m.eigenvalue.real() - kTable[v][0], 2) / seeds;
      reported(v - 5) += m.std_real / seeds;
    }
    for (int v = 0; v < 5; ++v) {  // the other five stay within the tolerances
      EXPECT_LT(std::abs(Nearest(r, v).eigenvalue.real() / kTable[v][0] - 1.0), 0.05) << "mode " << v + 1;
      EXPECT_LT(std::abs(Nearest(r, v).eigenvalue.imag() / kTable[v][1] - 1.0), 0.005) << "mode " << v + 1;
    }
  }
  for (int i = 0; i < 2; ++i) {
    const double rms = std::sqrt(squared(i)), crb = bound(5 + i, 0);
    std::printf("mode %d: rms error of Re s %.2f, mean reported std %.2f, bound %.2f rad/s\n", 6 + i, rms,
                reported(i), crb);
    EXPECT_GT(rms, 0.5 * crb);
    EXPECT_LT(rms, 2.0 * crb);
    // The reported standard error (at the estimate, where the problem is far from linear)
    // itself says that Re s is not known to 5 %.
    EXPECT_GT(reported(i), 0.05 * std::abs(kTable[5 + i][0]));
  }
}

// The opposite-sign pair's upper hump lies at the band's edge, so `peaks` sees four of the
// resonances and ideSISO's model (peaks + 2 fictitious poles) has a pole too few: its cost
// is far above the noise. The residual's largest resonance supplies the missing pole.
TEST(PoleResidue, ResidualSuppliesThePoleThePeaksMissed) {
  const Eigen::VectorXd omega = BaldaBand(500);
  const Frf frf = Noisy(omega, 0.01, 1, OppositePair());
  PoleResidueOptions literal = RelativeNoiseWeights(frf);
  literal.max_residual_poles = 0;
  const PoleResidueResult peaks_only = FitPoleResidue(frf, literal);
  const PoleResidueResult full = FitPoleResidue(frf, RelativeNoiseWeights(frf));
  EXPECT_EQ(peaks_only.modes.size(), 6u);
  EXPECT_EQ(full.modes.size(), 7u);
  EXPECT_EQ(full.residual_poles, 1);
  // Weighted cost with w = 1/|g| at the noise level: 2·500 equations · (1 %)²/2 ≈ 0.05.
  EXPECT_LT(full.final_cost, 0.08);
  EXPECT_GT(peaks_only.final_cost, 10.0 * full.final_cost);
  int added = 0;
  for (const auto& m : full.modes) added += m.from_residual;
  EXPECT_EQ(added, 1);
  EXPECT_NE(full.message.find("1 from the residual"), std::string::npos) << full.message;
  // Without noise the residual is empty and nothing is added.
  EXPECT_EQ(FitPoleResidue(Noisy(omega, 0.0, 1), {}).residual_poles, 0);
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
