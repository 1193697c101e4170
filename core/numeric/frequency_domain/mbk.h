#pragma once
// MIMO direct identification of M, B, K from a receptance FRF matrix, section 3 of [Balda]:
//   G(p) = Z⁻¹(p),  Z(p) = p²M + pB + K,  p = iω                               (13)–(15)
// Product method (16)–(19):   [p_k²G(p_k), p_kG(p_k), G(p_k)] [M; B; K] ≐ I
// Difference method (20)–(22): [p_k²I, p_kI, I] [M; B; K] ≐ G⁻¹(p_k)
// both stacked over all lines and solved in the least-squares sense (19) for real M, B, K
// (real and imaginary parts stacked, column-pivoting QR, p scaled by ω_s = max ω).
// G must be square (n outputs = n inputs = n coordinates), displacement per force.
#include <Eigen/Dense>

#include "core/numeric/signal/frf.h"
#include "core/numeric/result.h"

namespace idrig {

enum class MbkMethod { kProduct, kDifference };

struct MbkResult : ResultBase {
  Eigen::MatrixXd mass, damping, stiffness;  // M, B, K (n×n)
  double residual_norm = 0.0;                // ‖A C − Y‖_F of the stacked system (19)
};

// Throws std::invalid_argument for an invalid FRF (NaN, ω < 0), a non-square G, fewer than 2
// lines (3n unknowns per column, 2n real equations per line), or — difference method — a
// singular G(p_k) (line named).
MbkResult IdentifyMbk(const Frf& frf, MbkMethod method);

}  // namespace idrig
