#pragma once
// SISO rational fit of a measured FRF, section 2.1 of [Balda]:
//   G_m(p) = Σ_{j=0}^{m} b_j p^j / Σ_{j=0}^{n} a_j p^j,  p = iω   (1)
// Levy's linearisation (4)–(7): multiplying the residual (3) by the denominator makes the
// problem linear in a, b; it is solved by Householder QR (reduced in blocks of lines) on the real and
// imaginary parts stacked (the pseudoinverse solution (7)). Then the Sanathanan–Koerner
// iterations (8): equation k is divided by the previous denominator |A^(l)(p_k)|, so that at
// convergence the minimised quantity is the true output error G_m − G.
//
// Normalisation: [Balda] fixes b_0 = 1, which fails for systems with zero DC gain
// (accelerances, differentiators); we fix a_n = 1 (monic denominator), as invfreqs does.
// Conditioning: p is scaled, p̃ = p/ω_s with ω_s = max ω, before forming the regressor; the
// coefficients are unscaled at the end.
#include <Eigen/Dense>
#include <vector>

#include "core/numeric/signal/frf.h"
#include "core/numeric/model/lti_model.h"
#include "core/numeric/result.h"

namespace idrig {

struct LevyOptions {
  int denominator_degree = 2;          // n (>= 1)
  int numerator_degree = 1;            // m (>= 0)
  int max_sk_iterations = 30;          // 0: plain Levy only
  double coefficient_tolerance = 1e-9; // stop when the scaled coefficients change less (relative)
  Eigen::VectorXd weights;             // optional measurement weights w_k > 0 (empty: all 1)
  // After SK, minimise the weighted output error Σ w_k²|B/A(p_k) − G_k|² itself by
  // Levenberg–Marquardt (analytic Jacobian) from the SK coefficients. The SK fixed point is not
  // the minimum of that cost (the weight 1/|A_prev| is held fixed in each step, so its
  // derivative is missing from the normal equations); with w_k = 1/σ_k the minimum is the
  // maximum-likelihood estimate under complex Gaussian noise and reaches the Cramér–Rao bound
  // (docs/frequency.md). Kept only when it lowers the cost.
  bool refine_output_error = false;
  int max_function_evaluations = 2000;
};

struct LevyResult : ResultBase {
  TransferFunction model;       // continuous, num/den in descending powers, den monic
  Eigen::VectorXcd poles;
  bool stable = false;          // all poles with Re s < 0
  int sk_iterations = 0;        // reweighting iterations done (iterations = 1 + this)
  bool sk_converged = false;    // coefficients settled within coefficient_tolerance
  double relative_change = 0.0; // last relative coefficient change
  // Output error Σ w_k²|G_m(p_k) − G_k|² after each stage: [0] plain Levy, [l] SK iteration l.
  std::vector<double> cost_history;
  bool refined = false;         // the output-error refinement ran and lowered the cost
  double sk_cost = 0.0;         // Σ w²|r|² at the SK solution (before the refinement)
  int refine_iterations = 0;
  // final_cost = Σ w²|r|²; fit_percent = 100(1 − ‖w·r‖/‖w·g‖) on the FRF itself, weighted
  // like the cost (with w = 1/σ, lines the input did not excite count as little as they should).
};

// Throws std::invalid_argument for an invalid FRF (not SISO, ω <= 0, NaN), degrees < 0 / n < 1,
// fewer equations (2 per line) than unknowns n + m + 1, weights of the wrong size or <= 0.
// Non-convergence of SK is reported (status kNotConverged), never thrown.
LevyResult FitLevy(const Frf& frf, const LevyOptions& options);

// Output error helpers shared by the frequency methods.
double FrfCost(const Frf& frf, const Eigen::VectorXcd& model_response, const Eigen::VectorXd& weights);
double FrfFitPercent(const Frf& frf, const Eigen::VectorXcd& model_response,
                     const Eigen::VectorXd& weights = Eigen::VectorXd());

}  // namespace idrig
