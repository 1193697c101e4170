#pragma once
// Subspace identification of discrete-time MIMO state-space models from u/y records:
// MOESP, N4SID and CVA weightings of one algorithm.
//
// Model (nu inputs, ny outputs, order n, sample time Ts, input delay m samples):
//   x[k+1] = A x[k] + B u[k−m],   y[k] = C x[k] + D u[k−m] (+ noise),   x[0] = x0
//   A n×n, B n×nu, C ny×n, D ny×nu (D = 0 unless `feedthrough`).
//
// References:
//   [VODM] P. Van Overschee, B. De Moor, "Subspace Identification for Linear Systems", Kluwer
//          1996: block Hankel matrices (2.1)–(2.4), oblique projection O_i = Y_f /_{U_f} W_p
//          (Theorem 2, Eq. (2.23)), weightings W1, W2 of Table 3.1 (N4SID: I, I; MOESP: I,
//          Π_{U_f⊥}; CVA: (Y_f Π_{U_f⊥} Y_fᵀ)^(−1/2), Π_{U_f⊥}), A and C from the shift
//          invariance of the extended observability matrix Γ_i (§4.3.1, Eq. (4.16)).
//   [Verhaegen] M. Verhaegen, "Identification of the deterministic part of MIMO state space
//          models given in innovations form from input-output data", Automatica 30(1), 1994:
//          PO-MOESP — the LQ factorisation of [U_f; W_p; Y_f] and the SVD of L32.
//   [VV]   M. Verhaegen, V. Verdult, "Filtering and System Identification", CUP 2007, §9.2.4:
//          B, D and x0 by linear least squares on the output once A, C are known (Eq. (9.47)).
//
// The R factor of the Hankel matrix is the Cholesky factor of its Gram matrix HHᵀ, which is
// built from lagged products of the record in O(N·(nu+ny)²·i) without forming H (the Hankel
// structure gives every entry from its neighbour on the diagonal by two corrections).
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "core/numeric/io_record.h"
#include "core/numeric/model/lti_model.h"
#include "core/numeric/result.h"

namespace idrig {

enum class SubspaceWeighting { kMoesp, kN4sid, kCva };
const char* ToString(SubspaceWeighting weighting);
// "moesp" | "n4sid" | "cva"; throws std::invalid_argument otherwise.
SubspaceWeighting ParseSubspaceWeighting(const std::string& name);

struct SubspaceOptions {
  int order = 0;             // n; 0: from the largest gap of the singular values, n <= max_order
  int max_order = 10;
  int block_rows = 0;        // i (past and future horizons); 0: max(10, ⌈1.5(max_order+1)/ny⌉)
  SubspaceWeighting weighting = SubspaceWeighting::kCva;
  bool feedthrough = false;  // estimate D; false: D = 0
  bool enforce_stability = false;  // reflect eigenvalues of A outside the unit circle
  bool estimate_initial_state = true;
  int input_delay = 0;       // m >= 0 samples
};

struct SubspaceResult : ResultBase {
  StateSpace model;                 // discrete, Ts of the record, delay_s = m·Ts
  Eigen::VectorXd initial_state;    // x0 (zeros when not estimated)
  Eigen::VectorXd singular_values;  // of the weighted oblique projection, descending
  int order = 0;
  int block_rows = 0;
  double gap = 0.0;                 // s_n / s_{n+1} at the chosen order
  std::string order_rule;           // "user" or "largest singular-value gap"
  bool stabilised = false;          // eigenvalues were reflected into the unit circle
  double spectral_radius = 0.0;     // max |eig(A)| of the returned model
  Eigen::VectorXd fit_per_output;   // simulation fit [%] per output, from x0
  Eigen::MatrixXd parameter_covariance;  // of (vec B, vec D, x0) from the final least squares
  std::vector<std::string> warnings;
};

// Throws std::invalid_argument: no inputs or outputs, NaN/Inf, too few samples for the block
// rows (N − 2i + 1 must exceed 2i(nu+ny)), order above what i·ny allows, an input that is
// constant, inputs that are linearly dependent, or an input that is not persistently exciting
// of order 2i.
SubspaceResult IdentifySubspace(const IoRecord& record, const SubspaceOptions& options = {});

// B, D (optional) and x0 by least squares on the output for given A, C ([VV] Eq. (9.47)):
// y[k] = C A^k x0 + Σ_{j<k} C A^{k−1−j} B u[j] + D u[k]. `u` is N×nu, `y` N×ny. Fills B, D
// of `model` and returns x0 (zeros if !estimate_x0); `covariance` (optional) receives
// σ²(ΦᵀΦ)⁻¹ of (vec B, vec D, x0).
Eigen::VectorXd EstimateInputMatrices(const Eigen::MatrixXd& u, const Eigen::MatrixXd& y,
                                      bool feedthrough, bool estimate_x0, StateSpace* model,
                                      Eigen::MatrixXd* covariance = nullptr);

// Simulation of the discrete model from x0 (input delay applied): N×ny.
Eigen::MatrixXd SimulateFrom(const StateSpace& model, const Eigen::MatrixXd& u,
                             const Eigen::VectorXd& x0);

}  // namespace idrig
