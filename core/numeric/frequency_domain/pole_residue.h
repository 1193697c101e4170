#pragma once
// SISO indirect identification by pole–residue fitting, section 4 of [Balda] (`ideSISO`):
//   g(p) ≐ Σ_{ν=ν_a−1}^{ν_b+1} a_ν/(p − s_ν) + h_o,   p = iω                   (25), (35)
// 1. resonance peaks of the smoothed |g| as in `peaks` (3-point smoothing (1,3,1)/5, local
//    maxima whose relative prominence (drop on BOTH sides before |g| rises above the peak)
//    exceeds a tolerance — the listing compares with the adjacent minima and takes the larger
//    drop, which lets noise wiggles pass), or given lines;
// 2. for each peak a 5-point estimate of s_ν, a_ν and the local offset g_ν from (29)–(31),
//    first with s_ν ≈ p_m (the peak line) in the third column, then refined once with ŝ_ν;
// 3. one fictitious pole at each end of the band (ν_a−1, ν_b+1), estimated the same way from
//    the five end lines, correcting for modes outside the band;
// 4. residues a and h_o by linear least squares given s (35), then Levenberg–Marquardt
//    (Eigen unsupported, MINPACK lmder) on the weighted residuals (26) with the analytic
//    Jacobian (28) built from A1 (33) and A2 = A1∘A1 (34): ∂r/∂s = A2·diag(a), ∂r/∂a = A1,
//    ∂r/∂h_o = 1 (complex parameters split into real and imaginary parts);
// 5. as in `ideSISO`, s ← −|Re s| + i Im s at the end.
// With conjugate_pairs (default) every term a/(p − s) comes with conj(a)/(p − conj s), i.e. a
// real system; conjugate_pairs = false fits (26) exactly as printed (complex terms only).
#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <vector>

#include "core/numeric/signal/frf.h"
#include "core/numeric/model/lti_model.h"
#include "core/numeric/result.h"

namespace idrig {

struct PoleResidueOptions {
  double peak_tolerance = 0.05;      // `peaks` tol: relative drop of |g| to the neighbouring minima
  std::vector<double> peak_omegas;   // explicit peak frequencies [rad/s]; empty: detect
  bool fictitious_poles = true;      // the two out-of-band correction poles
  bool conjugate_pairs = true;
  bool origin_correction = true;     // h_o
  Eigen::VectorXd weights;           // measurement weights w_k > 0 (empty: 1); Balda uses w = f
  // Poles the peaks missed, added one at a time from the residual's largest resonance while
  // the BIC falls (0: the peaks and the fictitious poles only, as in `ideSISO`).
  int max_residual_poles = 2;
  int max_function_evaluations = 4000;   // per Levenberg–Marquardt run
  double tolerance = 1e-12;          // LM ftol = xtol
};

struct Mode {
  std::complex<double> eigenvalue;   // s [rad/s]
  std::complex<double> residue;      // a
  double natural_frequency = 0.0;    // ω_n = |s| [rad/s]
  double damping_ratio = 0.0;        // ζ = −Re s/|s|
  double q = 0.0;                    // Q = |s|/(−2 Re s) = 1/(2ζ)
  bool fictitious = false;           // started as an out-of-band correction pole
  bool from_residual = false;        // added from the residual (max_residual_poles)
  // Standard errors from the Jacobian at the optimum, Cov = σ̂²·(JᵀJ)⁺ with
  // σ̂² = cost/(2L − P) (weighted residuals, L lines, P real parameters). With weights
  // w_k = 1/σ_k (the noise's standard deviation per line) this is the Cramér–Rao bound
  // evaluated at the estimate; NaN when the fit has no spare equations.
  double std_real = NAN;              // of Re s [rad/s]
  double std_imag = NAN;              // of Im s [rad/s]
  double std_natural_frequency = NAN; // of ω_n (first-order propagation)
  double std_damping_ratio = NAN;     // of ζ
};

struct PoleResidueResult : ResultBase {
  std::vector<Mode> modes;           // sorted by Im s
  std::complex<double> origin_correction = 0.0;  // h_o
  std::vector<int> peak_lines;       // lines used as peaks (without the two ends)
  std::vector<Mode> initial_modes;   // the 5-point estimates (29)–(31)
  Eigen::VectorXcd fitted;           // model on the FRF lines
  int function_evaluations = 0;
  int residual_poles = 0;            // poles added from the residual
  int lm_status = 0;                 // Eigen::LevenbergMarquardtSpace::Status
};

// `peaks` of [Balda]: indices of local maxima of the smoothed |g| whose relative drop to a
// neighbouring minimum exceeds `tolerance`.
std::vector<int> FindPeaks(const Eigen::VectorXd& magnitude, double tolerance);

// Throws std::invalid_argument for an invalid FRF (not SISO, ω <= 0, NaN), fewer than 5 lines,
// a peak frequency outside the band, fewer real equations than unknowns, bad weights, or no
// pole at all (no peak and no fictitious poles). Non-convergence is reported, not thrown.
PoleResidueResult FitPoleResidue(const Frf& frf, const PoleResidueOptions& options);

// The real rational model Σ (a/(p−s) + ā/(p−s̄)) + Re h_o (conjugate_pairs fits only).
TransferFunction PoleResidueTransferFunction(const PoleResidueResult& result);

}  // namespace idrig
