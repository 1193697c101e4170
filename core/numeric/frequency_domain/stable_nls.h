#pragma once
// SISO nonlinear regression that is stable by construction, section 2.2 of [Balda]:
//   G_m(p) = G_m(0) ∏_j (1 + c_j p + d_j p²) / ∏_j (1 + a_j p + b_j p²)       (9)
// with a_j = α_j², b_j = β_j² (and, following (12), c_j = γ_j², d_j = δ_j² unless
// square_numerator = false), minimising S_2 = rᴴr, r_k = w_k (G_m(p_k) − G_k)  (10)–(12).
// Positive a_j, b_j make every denominator section Hurwitz, so the model is stable for
// every parameter value. An odd degree adds one first-order section 1 + a p.
//
// Solver: Eigen's unsupported LevenbergMarquardt (MINPACK lmder) with the analytic Jacobian
//   ∂G/∂α = −G·2αp̃/D, ∂G/∂β = −G·2βp̃²/D, ∂G/∂γ = G·2γp̃/N, ∂G/∂δ = G·2δp̃²/N, ∂G/∂G(0) = G/G(0),
// in the scaled variable p̃ = p/ω_s (ω_s = max ω). Started from the Levy/SK fit with its
// unstable poles (and, when squared, right-half-plane zeros) reflected into the left half-plane.
#include "core/numeric/frequency_domain/levy.h"

namespace idrig {

struct StableNlsOptions {
  int denominator_degree = 2;   // n
  int numerator_degree = 1;     // m (<= n for a proper model)
  bool square_numerator = true; // (12) for c, d too (minimum-phase zeros); false: c, d free
  int sk_iterations = 30;       // for the Levy/SK start
  int max_function_evaluations = 2000;
  double tolerance = 1e-10;     // LM ftol = xtol
  Eigen::VectorXd weights;      // optional w_k > 0
};

struct StableNlsResult : ResultBase {
  TransferFunction model;       // monic denominator, descending powers
  Eigen::VectorXcd poles;
  bool stable = false;          // true by construction unless a section degenerated (b = 0)
  double start_cost = 0.0;      // Σ w²|r|² of the (reflected) Levy/SK start
  LevyResult start;             // the Levy/SK fit used as the start (before reflection)
  int function_evaluations = 0;
  int lm_status = 0;            // Eigen::LevenbergMarquardtSpace::Status
};

// Throws std::invalid_argument as FitLevy does. Non-convergence (function-evaluation limit)
// is reported as kNotConverged.
StableNlsResult FitStableNls(const Frf& frf, const StableNlsOptions& options);

}  // namespace idrig
