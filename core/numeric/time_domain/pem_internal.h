#pragma once
// Internals of pem.cc shared with pem_start.cc: parameter layout, polynomial helpers, starts.
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "core/numeric/time_domain/pem.h"

namespace idrig::pem_internal {

struct Layout {
  int na = 0, nb = 0, nc = 0, nd = 0, nf = 0, nu = 1, nk = 1;
  int Size() const { return na + nu * nb + nc + nd + nu * nf; }
  int B(int j) const { return na + j * nb; }
  int C() const { return na + nu * nb; }
  int D() const { return C() + nc; }
  int F(int j) const { return D() + nd + j * nf; }
};

struct Polys {
  Eigen::VectorXd a, c, d;            // monic, ascending in q⁻¹
  std::vector<Eigen::VectorXd> b, f;  // b: nb coefficients; f monic
};

Polys Unpack(const Layout& layout, const Eigen::VectorXd& theta);
Eigen::VectorXd Pack(const Layout& layout, const Polys& polys);
// x(t − k), zero before the start.
Eigen::VectorXd Shifted(const Eigen::VectorXd& x, int k);
// Monic polynomial (ascending q⁻¹) with every root inside the unit circle.
bool IsStablePolynomial(const Eigen::VectorXd& monic);
// Roots outside the unit circle reflected to 1/conj(z); resized to `degree` (+1 for the 1).
Eigen::VectorXd StabilisedMonic(const Eigen::VectorXd& monic, int degree);

// Least squares y ≈ Φ θ (QR with column pivoting).
Eigen::VectorXd LeastSquares(const Eigen::MatrixXd& phi, const Eigen::VectorXd& y);

struct Start {
  std::string name;
  Polys polys;
};
// Steiglitz–McBride, subspace and Hannan–Rissanen starts for the structure of `options`.
std::vector<Start> MakeStarts(const Layout& layout, const Eigen::VectorXd& y, const Eigen::MatrixXd& u,
                              double sample_time, const PemOptions& options);

}  // namespace idrig::pem_internal
