#include "core/numeric/frequency_domain/mbk.h"

#include <stdexcept>
#include <string>

namespace idrig {

MbkResult IdentifyMbk(const Frf& frf, MbkMethod method) {
  ValidateFrf(frf, /*allow_zero_frequency=*/true);
  const int n = frf.NumOutputs(), lines = frf.NumLines();
  if (frf.NumInputs() != n)
    throw std::invalid_argument("M,B,K: the FRF matrix must be square (" + std::to_string(n) + "x" +
                                std::to_string(frf.NumInputs()) + " given)");
  if (2 * lines < 3)
    throw std::invalid_argument("M,B,K: at least 2 lines are needed (3n unknowns per column, 2n equations per line)");
  const double ws = frf.omega.maxCoeff() > 0.0 ? frf.omega.maxCoeff() : 1.0;
  using Complex = std::complex<double>;
  const Eigen::MatrixXcd I = Eigen::MatrixXcd::Identity(n, n);
  Eigen::MatrixXd A(2 * n * lines, 3 * n), Y(2 * n * lines, n);
  for (int k = 0; k < lines; ++k) {
    const Complex p(0.0, frf.omega(k) / ws);  // scaled: unknowns [ω_s²M; ω_sB; K]
    Eigen::MatrixXcd row(n, 3 * n), rhs(n, n);
    if (method == MbkMethod::kProduct) {
      const Eigen::MatrixXcd& G = frf.h[k];
      row << p * p * G, p * G, G;  // Eq. (17) of [Balda]
      rhs = I;
    } else {
      Eigen::FullPivLU<Eigen::MatrixXcd> lu(frf.h[k]);
      if (!lu.isInvertible())
        throw std::invalid_argument("M,B,K difference method: G is singular at line " + std::to_string(k) +
                                    " (ω = " + std::to_string(frf.omega(k)) + " rad/s)");
      row << p * p * I, p * I, I;  // Eq. (21)
      rhs = lu.inverse();          // G⁻¹(p_k)
    }
    A.middleRows(2 * n * k, n) = row.real();
    A.middleRows(2 * n * k + n, n) = row.imag();
    Y.middleRows(2 * n * k, n) = rhs.real();
    Y.middleRows(2 * n * k + n, n) = rhs.imag();
  }
  Eigen::VectorXd col = A.colwise().norm();
  for (int j = 0; j < col.size(); ++j) col(j) = col(j) > 0.0 ? col(j) : 1.0;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A * col.cwiseInverse().asDiagonal());
  const Eigen::MatrixXd C = col.cwiseInverse().asDiagonal() * qr.solve(Y);  // Eq. (19): C = A⁺Y
  MbkResult result;
  result.mass = C.topRows(n) / (ws * ws);
  result.damping = C.middleRows(n, n) / ws;
  result.stiffness = C.bottomRows(n);
  result.residual_norm = (A * (col.cwiseInverse().asDiagonal() * qr.solve(Y)) - Y).norm();
  result.final_cost = result.residual_norm * result.residual_norm;
  result.iterations = 1;
  if (!C.allFinite()) {
    result.status = SolverStatus::kFailed;
    result.message = "the least-squares solve produced non-finite values";
  } else if (qr.rank() < 3 * n) {
    result.status = SolverStatus::kIllConditioned;
    result.message = "the stacked system is rank deficient (rank " + std::to_string(qr.rank()) + " of " +
                     std::to_string(3 * n) + "): measure more lines";
  } else {
    result.status = SolverStatus::kOk;
    result.message = method == MbkMethod::kProduct ? "product method (16)-(19)" : "difference method (20)-(22)";
  }
  return result;
}

}  // namespace idrig
