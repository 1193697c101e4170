#pragma once
// Regularised least-squares ARX with exact return to continuous time, section 2 of
// [Ivanovsky] (seed 001).
//
// Model (2.1)/(2.7), SISO, sample time T [s], input delay nk >= 1 samples (nk = 1 in the paper):
//   y_k + c_1 y_{k−1} + … + c_n y_{k−n} = d_1 u_{k−nk} + … + d_n u_{k−nk−n+1} + e_k
// Parameters g = (−c; d), Eq. (2.2), estimated from L equations taken every q samples,
// Eqs. (2.9)–(2.10), by the regularised solution (2.11):
//   ĝ = (ε E_2n + F_Lᵀ F_L)⁻¹ F_Lᵀ Y_L.
// F_L is never formed: it is reduced to a (2n+1)×(2n+1) triangle by QR in blocks, so memory
// does not grow with the number of samples. ε is the user's, or chosen by generalised
// cross-validation (GCV) on the singular values of that triangle.
// Steps 2–7 then give every equivalent form: Rd1 (1.12)–(1.13), W(z) (1.14), the difference
// equation (2.1), R* by the logarithmic series (1.16), R1* by (1.7), and W(p) by (1.3)–(1.4).
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "core/numeric/io_record.h"
#include "core/numeric/model/lti_model.h"
#include "core/numeric/model/realisation.h"
#include "core/numeric/result.h"
#include "core/numeric/validation.h"

namespace idrig {

struct ArxOptions {
  int order = 0;            // n; 0 chooses n in [1, max_order] by cross-validation
  int max_order = 8;
  int input_delay = 1;      // nk >= 1 samples (the continuous model gets delay (nk − 1)·T)
  int decimation = 1;       // q of Eq. (2.10): one equation every q samples
  int first_equation = -1;  // index k of the first predicted sample y_k; −1: the first possible
  int max_equations = 0;    // L; 0: as many as the record allows
  double epsilon = -1.0;    // ε of Eq. (2.11); < 0: chosen by GCV
  // Output-error refinement by Steiglitz–McBride iterations (refit on data prefiltered by
  // 1/Â(q)): removes the bias of equation-error ARX under output noise. 0: plain ARX.
  int oe_iterations = 0;
  double oe_tolerance = 1e-6;  // converged when the last fit changes g by less (relative)
  bool recover_continuous = true;
  int log_series_terms = 0;  // terms of (1.16); 0: sum to machine precision
  // Simulation fit and residual tests on the record (skip for raw estimation speed).
  bool validate = true;
  ResidualTestOptions residual_test;
};

struct ArxOrderCandidate {
  int order = 0;
  int equations = 0;
  double residual_sum_squares = 0.0;
  double mdl = 0.0;          // L·ln(RSS/L) + 2n·ln(L)
  double epsilon = 0.0;
  double validation_nrmse = 0.0;  // simulation NRMSE on the held-out last third
  double fit_percent = 0.0;       // 100·(1 − validation_nrmse)
};

struct ArxResult : ResultBase {
  int order = 0;
  int input_delay = 1;
  int equations = 0;          // L
  double sample_time = 0.0;
  double epsilon = 0.0;       // ε used in (2.11)
  std::string epsilon_rule;   // "user" or "gcv"
  double condition_number = 0.0;  // of F_L (ratio of extreme singular values)
  Eigen::VectorXd g;          // (2.2): (−c_1 … −c_n, d_1 … d_n)
  Eigen::VectorXd c, d;       // difference equation (2.1)
  Eigen::MatrixXd covariance; // of g (σ² (F'F+εE)⁻¹ F'F (F'F+εE)⁻¹)
  Eigen::VectorXd g_std;      // square roots of the diagonal
  double noise_variance = 0.0;
  double oe_relative_change = 0.0;  // of g in the last Steiglitz–McBride fit (arx-oe)

  // The five equivalent forms.
  TransferFunction discrete_tf;     // W(z), Eq. (1.14)
  CompactForm discrete_compact;     // Rd1 = (Φ1, Γ1, H1), Eqs. (1.12)–(1.13): difference system
  bool continuous_recovered = false;
  std::string continuous_message;
  SeriesLogarithm log_series;       // R* = (A*, B*, H), Eq. (1.16), with its truncation error
  CompactForm continuous_compact;   // R1* = (L, K, M), Eq. (1.7): Cauchy form
  TransferFunction continuous_tf;   // W(p), Eqs. (1.2)–(1.4)

  double y_inf_sum = 0.0;     // y(∞) by (2.4)
  double y_inf_matrix = 0.0;  // y(∞) by (1.15)

  ResidualTest residuals;     // one-step prediction errors
  std::vector<ArxOrderCandidate> order_table;
  std::vector<std::string> warnings;

  std::string DifferenceEquation() const;  // "y[k] + c1 y[k-1] … = d1 u[k-1] + …"
};

// Throws std::invalid_argument for MIMO records, NaN/Inf, fewer equations than 2n, a constant
// input (not persistently exciting), or invalid options.
ArxResult IdentifyArx(const IoRecord& record, const ArxOptions& options = {});

// The regularised solve (2.11) alone, for given F (L×p) and Y (L): the paper's Fig. 8.
struct RegularisedSolution {
  Eigen::VectorXd g;
  double epsilon = 0.0;
  double condition_number = 0.0;
  double residual_sum_squares = 0.0;
  SolverStatus status = SolverStatus::kOk;
};
RegularisedSolution SolveRegularised(const Eigen::MatrixXd& F, const Eigen::VectorXd& Y,
                                     double epsilon);

// Step-only data through the auxiliary link, Eqs. (2.5)–(2.6): the measured step response
// h(kT) of amplitude `step_amplitude` is turned into the response f = U·h to the input
// u(t) = 1 − e^(−t/T_a) held on the sample grid, f_k = Σ_j (u_j − u_{j−1}) h_{k−j} (exact for
// a zero-order-hold input), and (u, f) is identified by IdentifyArx.
struct StepArxOptions {
  double step_amplitude = 1.0;
  double auxiliary_time_constant = 0.0;  // T_a [s]; 0: one tenth of the record length
  ArxOptions arx;
};
ArxResult IdentifyArxFromStep(const Eigen::VectorXd& step_response, double sample_time,
                              const StepArxOptions& options = {});

}  // namespace idrig
