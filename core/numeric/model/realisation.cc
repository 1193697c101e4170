#include "core/numeric/model/realisation.h"

#include <unsupported/Eigen/MatrixFunctions>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace idrig {

CompactForm CompactObservableForm(const Eigen::VectorXd& numerator,
                                  const Eigen::VectorXd& monic_denominator) {
  const int n = static_cast<int>(monic_denominator.size()) - 1;
  if (n < 1) throw std::invalid_argument("compact form: denominator must have degree >= 1");
  if (numerator.size() != n)
    throw std::invalid_argument("compact form: numerator needs " + std::to_string(n) +
                                " coefficients (strictly proper, descending), got " +
                                std::to_string(numerator.size()));
  if (monic_denominator(0) != 1.0)
    throw std::invalid_argument("compact form: denominator must be monic");
  CompactForm form;
  // A1 (1.3): superdiagonal identity, last row −b_II^T = −(b_1 … b_n).
  form.A = Eigen::MatrixXd::Zero(n, n);
  if (n > 1) form.A.topRightCorner(n - 1, n - 1).setIdentity();
  for (int j = 0; j < n; ++j) form.A(n - 1, j) = -monic_denominator(n - j);
  // C (1.4): unit lower-triangular Toeplitz with b_n, b_{n−1}, … below the diagonal.
  Eigen::MatrixXd c = Eigen::MatrixXd::Identity(n, n);
  for (int i = 1; i < n; ++i)
    for (int j = 0; j < i; ++j) c(i, j) = monic_denominator(i - j);
  // B1 = C⁻¹ a_I (1.3); C is unit lower triangular, so forward substitution is exact.
  form.B = c.triangularView<Eigen::UnitLower>().solve(numerator);
  form.H = Eigen::RowVectorXd::Zero(n);
  form.H(0) = 1.0;
  return form;
}

void CompactFormCoefficients(const CompactForm& form, Eigen::VectorXd* numerator,
                             Eigen::VectorXd* monic_denominator) {
  const int n = static_cast<int>(form.A.rows());
  Eigen::VectorXd den(n + 1);
  den(0) = 1.0;
  for (int j = 0; j < n; ++j) den(n - j) = -form.A(n - 1, j);
  Eigen::MatrixXd c = Eigen::MatrixXd::Identity(n, n);
  for (int i = 1; i < n; ++i)
    for (int j = 0; j < i; ++j) c(i, j) = den(i - j);
  *numerator = c * form.B;  // a_I = C B1, from (1.3)
  *monic_denominator = den;
}

Eigen::MatrixXd ObservabilityMatrix(const Eigen::MatrixXd& A, const Eigen::RowVectorXd& H) {
  const int n = static_cast<int>(A.rows());
  Eigen::MatrixXd N(n, n);
  Eigen::RowVectorXd row = H;
  for (int i = 0; i < n; ++i) {  // Eq. (1.6): rows H, HA, …, HA^{n−1}
    N.row(i) = row;
    row = row * A;
  }
  return N;
}

CompactForm ToCompactForm(const Eigen::MatrixXd& A, const Eigen::VectorXd& B,
                          const Eigen::RowVectorXd& H) {
  const Eigen::MatrixXd N = ObservabilityMatrix(A, H);
  Eigen::FullPivLU<Eigen::MatrixXd> lu(N);
  lu.setThreshold(1e-13);
  if (!lu.isInvertible())
    throw std::invalid_argument(
        "compact form: the realisation is not observable (observability matrix rank " +
        std::to_string(lu.rank()) + " < " + std::to_string(A.rows()) + ")");
  CompactForm form;
  // Eq. (1.7): A1 = N A N⁻¹, B1 = N B, H1 = H N⁻¹.
  form.A = (N * A) * lu.inverse();
  form.B = N * B;
  form.H = H * lu.inverse();
  // The structure is exact in theory (Property 1): clean the rounding in the fixed entries.
  const int n = static_cast<int>(A.rows());
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j < n; ++j) form.A(i, j) = (j == i + 1) ? 1.0 : 0.0;
  form.H.setZero();
  form.H(0) = 1.0;
  return form;
}

SeriesDiscretisation DiscretiseBySeries(const Eigen::MatrixXd& A, const Eigen::VectorXd& B,
                                        double sample_time, int terms) {
  if (terms < 1) throw std::invalid_argument("series discretisation: need at least one term");
  if (!(sample_time > 0.0)) throw std::invalid_argument("series discretisation: T must be positive");
  const int n = static_cast<int>(A.rows());
  SeriesDiscretisation out;
  out.terms = terms;
  out.Phi = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd gamma_matrix = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd term = Eigen::MatrixXd::Identity(n, n);  // (AT)^k / k!
  for (int k = 0; k < terms; ++k) {
    out.Phi += term;                                  // Eq. (1.8): Σ (AT)^k / k!
    gamma_matrix += term * (sample_time / (k + 1));   // Σ A^k T^{k+1} / (k+1)!
    term = term * A * (sample_time / (k + 1));
  }
  out.Gamma = gamma_matrix * B;
  out.first_omitted_term = term.cwiseAbs().maxCoeff();
  Eigen::MatrixXd aug = Eigen::MatrixXd::Zero(n + 1, n + 1);
  aug.topLeftCorner(n, n) = A * sample_time;
  aug.topRightCorner(n, 1) = B * sample_time;
  const Eigen::MatrixXd e = aug.exp();
  out.truncation_error = std::max((out.Phi - e.topLeftCorner(n, n)).cwiseAbs().maxCoeff(),
                                  (out.Gamma - e.topRightCorner(n, 1)).cwiseAbs().maxCoeff());
  return out;
}

SeriesLogarithm ContinuousFromDiscreteBySeries(const Eigen::MatrixXd& Phi,
                                               const Eigen::VectorXd& Gamma, double sample_time,
                                               int terms) {
  if (!(sample_time > 0.0)) throw std::invalid_argument("series logarithm: T must be positive");
  // Eigen's matrix logarithm (the cross-check below) reads past its buffer on a NaN entry.
  if (!Phi.allFinite() || !Gamma.allFinite())
    throw std::invalid_argument("series logarithm: Phi or Gamma has a NaN or Inf entry");
  const int n = static_cast<int>(Phi.rows());
  const Eigen::MatrixXd E = Eigen::MatrixXd::Identity(n, n);
  SeriesLogarithm out;
  Eigen::PartialPivLU<Eigen::MatrixXd> plus(Phi + E);
  const Eigen::MatrixXd X = (Phi - E) * plus.inverse();  // Eq. (1.16)
  out.spectral_radius_x = Eigen::EigenSolver<Eigen::MatrixXd>(X, false).eigenvalues().cwiseAbs().maxCoeff();
  const Eigen::MatrixXd X2 = X * X;
  Eigen::MatrixXd power = X;  // X^{2k+1}
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(n, n);
  // Automatic (terms <= 0): to machine precision, at most 10 000 terms; a series that diverges
  // (rho(X) >= 1, or not a number) is not summed: its terms grow, and 10 000 of them only
  // overflowed (most of a worker's job on such a model, tests/fuzz/fuzz_worker_logger).
  const bool divergent = !(out.spectral_radius_x < 1.0);
  const int max_terms = terms > 0 ? terms : (divergent ? 1 : 10000);
  int k = 0;
  for (; k < max_terms; ++k) {
    const Eigen::MatrixXd term = power / (2.0 * k + 1.0);
    sum += term;
    power = power * X2;
    if (terms <= 0 && term.cwiseAbs().maxCoeff() <= 1e-16 * std::max(1.0, sum.cwiseAbs().maxCoeff())) {
      ++k;
      break;
    }
  }
  out.terms = k;
  out.A = (2.0 / sample_time) * sum;
  const double norm_x = X.norm();  // Frobenius norm bounds the spectral norm
  out.converged = out.spectral_radius_x < 1.0;
  out.tail_bound = norm_x < 1.0 ? (2.0 / sample_time) * std::pow(norm_x, 2 * k + 1) /
                                      ((2.0 * k + 1.0) * (1.0 - norm_x * norm_x))
                                : std::numeric_limits<double>::infinity();
  // B* = (Φ − E)⁻¹ A* Γ, Eq. (1.16).
  out.B = (Phi - E).fullPivLu().solve(out.A * Gamma);
  // Cross-check against Eigen's matrix logarithm (principal branch), where the series converged:
  // rho(X) < 1 puts every eigenvalue of Phi in the open right half-plane, where the principal
  // logarithm exists. On a singular Phi Eigen's square-root loop (matrix_log_compute_big) never
  // ends (tests/fuzz/fuzz_worker_logger timeout-351249dd: a worker held by one request).
  out.truncation_error = std::numeric_limits<double>::infinity();
  if (out.converged) {
    const Eigen::MatrixXd log_phi = Phi.log() / sample_time;
    if (log_phi.allFinite()) out.truncation_error = (out.A - log_phi).cwiseAbs().maxCoeff();
  }
  return out;
}

}  // namespace idrig
