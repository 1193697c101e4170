#pragma once
// The Cramér–Rao bound on the poles of a rational FRF model, from its definition, for the
// frequency-domain ML test and benchmark (issue 15); independent of the fitting code.
//   G = B/A (A monic of degree n, B of degree m), θ = (a₀ … a_{n−1}, b₀ … b_m),
//   J_kj = ∂G(jω_k)/∂θ_j: ∂G/∂a_j = −G s^j/A, ∂G/∂b_j = s^j/A;
//   complex noise with E|e_k|² = σ_k²: FIM = 2 Re(JᴴΣ⁻¹J), Σ = diag(σ_k²);
//   poles: Cov(p) = D·FIM⁻¹·Dᴴ with ∂p_i/∂a_j = −p_i^j/A′(p_i); the bound on the RMS pole
//   error is √trace Cov(p).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <random>

#include "core/numeric/model/lti_model.h"

namespace idrig::testing {

inline double PoleCrb(const TransferFunction& tf, const Eigen::VectorXd& omega, const Eigen::VectorXd& sigma) {
  using Complex = std::complex<double>;
  const int n = tf.Order(), m = static_cast<int>(tf.num.size()) - 1, q = n + m + 1;
  Eigen::MatrixXcd j(omega.size(), q);
  for (int k = 0; k < omega.size(); ++k) {
    const Complex s(0.0, omega(k)), a = PolyVal(tf.den, s), g = PolyVal(tf.num, s) / a;
    for (int i = 0; i < n; ++i) j(k, i) = -g * std::pow(s, i) / a / sigma(k);
    for (int i = 0; i <= m; ++i) j(k, n + i) = std::pow(s, i) / a / sigma(k);
  }
  const Eigen::MatrixXd cov = (2.0 * (j.adjoint() * j).real()).inverse();
  const Eigen::VectorXcd p = Poles(tf);
  Eigen::MatrixXcd d = Eigen::MatrixXcd::Zero(n, q);
  for (int i = 0; i < n; ++i) {
    Complex da = 0.0;  // A′(p) of the descending den
    for (int c = 0; c < n; ++c) da += tf.den(c) * double(n - c) * std::pow(p(i), n - c - 1);
    for (int c = 0; c < n; ++c) d(i, c) = -std::pow(p(i), c) / da;
  }
  return std::sqrt((d * cov.cast<Complex>() * d.adjoint()).trace().real());
}

// g0 plus complex noise with E|e_k|² = σ_k² (real and imaginary parts N(0, σ_k²/2)), seeded.
inline Eigen::VectorXcd WithComplexNoise(const Eigen::VectorXcd& g0, const Eigen::VectorXd& sigma, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  Eigen::VectorXcd g = g0;
  for (int k = 0; k < g.size(); ++k) g(k) += sigma(k) * std::complex<double>(n01(rng), n01(rng)) / std::sqrt(2.0);
  return g;
}

// Σ_i |p̂ − p_i|² with each true pole matched to the nearest estimate.
inline double SquaredPoleError(const Eigen::VectorXcd& truth, const Eigen::VectorXcd& est) {
  double sum = 0.0;
  for (int i = 0; i < truth.size(); ++i) {
    double best = 1e300;
    for (int j = 0; j < est.size(); ++j) best = std::min(best, std::norm(truth(i) - est(j)));
    sum += best;
  }
  return sum;
}

}  // namespace idrig::testing
