#pragma once
// Prediction-error identification of discrete-time SISO and MISO polynomial models:
// output error (OE), ARMAX and Box–Jenkins (BJ), members of the general family
//   A(q) y(t) = Σ_j [B_j(q)/F_j(q)] u_j(t − nk_j) + [C(q)/D(q)] e(t)
// of [Ljung] §4.2, Eq. (4.33), with monic A, C, D, F_j in q⁻¹ and B_j = b_j0 + b_j1 q⁻¹ + …:
//   OE:    A = C = D = 1        y = Σ B_j/F_j u_j + e
//   ARMAX: F_j = D = 1          A y = Σ B_j u_j + C e
//   BJ:    A = 1                y = Σ B_j/F_j u_j + C/D e
// The prediction error ε(t, θ) = (D/C)[A y − Σ B_j/F_j u_j] ([Ljung] Eq. (4.36)) is minimised
// in the least-squares sense by Levenberg–Marquardt on the Gauss–Newton Hessian JᵀJ; the
// gradient ψ = −∂ε/∂θ is computed exactly by filtering ([Ljung] §10.3, Eqs. (10.52)–(10.55)):
//   ∂ε/∂a_k = (D/C) y(t−k)            ∂ε/∂b_jk = −D/(C F_j) u_j(t−nk_j−k)
//   ∂ε/∂f_jk = D/(C F_j) w_j(t−k)      ∂ε/∂c_k = −(1/C) ε(t−k)       ∂ε/∂d_k = (1/C) v(t−k)
// with w_j = B_j/F_j u_j and v = A y − Σ w_j. Covariance σ²(JᵀJ)⁻¹ at the minimum ([Ljung]
// Eq. (9.18)), σ² = Σε²/(N − p).
// Starts: Steiglitz–McBride iterations ([Ljung] §10.4; K. Steiglitz, L. McBride, IEEE TAC
// 10, 1965), the subspace estimate (subspace.h) and, for the noise models, Hannan–Rissanen
// long-AR regressions (E. J. Hannan, J. Rissanen, Biometrika 69, 1982). Every start is refined;
// the stable refinement with the smallest cost is kept.
//
// [Ljung] L. Ljung, System Identification: Theory for the User, 2nd ed., Prentice Hall 1999.
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "core/numeric/io_record.h"
#include "core/numeric/model/lti_model.h"
#include "core/numeric/result.h"

namespace idrig {

enum class PemStructure { kOutputError, kArmax, kBoxJenkins };
const char* ToString(PemStructure structure);

struct PemOptions {
  PemStructure structure = PemStructure::kOutputError;
  int order = 0;        // n for every polynomial the structure has; 0: chosen on held-out data
  int max_order = 8;
  int nb = -1, nf = -1, na = -1, nc = -1, nd = -1;  // overrides (−1: n)
  int input_delay = 1;  // nk >= 0 samples, every input
  int output = 0;       // which output column of the record (MISO per output)
  int max_iterations = 200;
  double tolerance = 1e-10;  // relative cost decrease and step size at convergence
  bool subspace_start = true;
  bool steiglitz_mcbride_start = true;
};

struct PemStart {
  std::string name;        // "steiglitz-mcbride", "subspace", "hannan-rissanen", …
  double initial_cost = 0.0, final_cost = 0.0;
  int iterations = 0;
  bool stable = false;
  bool chosen = false;
};

struct PemOrderCandidate {
  int order = 0;
  double validation_fit_percent = 0.0;  // simulation fit on the held-out last third
};

struct PemResult : ResultBase {
  PemStructure structure = PemStructure::kOutputError;
  int order = 0;
  int input_delay = 1;
  double sample_time = 0.0;
  // Polynomials in ascending powers of q⁻¹ (monic ones start with 1).
  Eigen::VectorXd a, c, d;
  std::vector<Eigen::VectorXd> b, f;  // one per input
  Eigen::VectorXd theta, theta_std;   // (a, b_1…b_nu, c, d, f_1…f_nu) without the leading 1s
  std::vector<std::string> parameter_names;
  Eigen::MatrixXd covariance;
  double noise_variance = 0.0;
  std::vector<TransferFunction> input_tfs;  // G_j(z) = B_j/(A F_j) z^{−nk}, descending z
  StateSpace model;                         // the deterministic part Σ G_j u_j, ny = 1
  std::vector<PemStart> starts;
  std::vector<PemOrderCandidate> order_table;
  std::vector<std::string> warnings;
};

// Throws std::invalid_argument: no input, an output index out of range, NaN/Inf, fewer samples
// than 3× the parameters, a constant input, linearly dependent inputs, invalid orders.
PemResult IdentifyPem(const IoRecord& record, const PemOptions& options = {});

// Deterministic part Σ_j B_j/(A F_j) u_j(t − nk) from rest: N×1.
Eigen::VectorXd SimulatePem(const PemResult& result, const Eigen::MatrixXd& u);

// y = (num/den) x from rest, num and den ascending in q⁻¹, den(0) = 1.
Eigen::VectorXd FilterPolynomial(const Eigen::VectorXd& num, const Eigen::VectorXd& den,
                                 const Eigen::VectorXd& x);

}  // namespace idrig
