#pragma once
// Mutually inverse transforms between continuous and discrete realisations, section 1 of
// [Ivanovsky] (seed 001).
//
//   continuous  x' = A x + B u,  y = H x           realisation R  = (A, B, H)
//   discrete    x[k+1] = Φ x[k] + Γ u[k], y = H x  realisation Rd = (Φ, Γ, H)
//
// The compact observable forms R1 (1.3)–(1.4) and Rd1 (1.12)–(1.13) carry only the 2n
// coefficients of W(p) or W(z); the chain R1 → Rd → Rd1 → R* → R1* of Figs. 4–5 goes from one
// to the other and back. SISO throughout (H is 1×n).
#include <Eigen/Dense>

namespace idrig {

// A compact observable realisation: A (or Φ) has ones on the superdiagonal and the negated
// denominator coefficients in its last row; H = (1 0 … 0); B = C⁻¹ a with C the lower
// triangular Toeplitz matrix of the denominator.
struct CompactForm {
  Eigen::MatrixXd A;  // n×n (Φ1 for a discrete system)
  Eigen::VectorXd B;  // n   (Γ1)
  Eigen::RowVectorXd H;
};

// Eqs. (1.3)–(1.4) (continuous) and (1.12)–(1.13) (discrete) of [Ivanovsky]:
// numerator a = (a_n … a_1) = coefficients of p^{n−1} … p^0 (length n, strictly proper part),
// denominator descending and monic: (1, b_n, …, b_1) — or for W(z), (1, c_1, …, c_n).
CompactForm CompactObservableForm(const Eigen::VectorXd& numerator,
                                  const Eigen::VectorXd& monic_denominator);

// Inverse of the above: reads the denominator from the last row of A and the numerator as
// C·B (Eq. (1.3): B1 = C⁻¹ a). Returns descending (num length n, den length n+1 monic).
void CompactFormCoefficients(const CompactForm& form, Eigen::VectorXd* numerator,
                             Eigen::VectorXd* monic_denominator);

// Observability matrix N = [H; H A; …; H A^{n−1}], Eq. (1.6).
Eigen::MatrixXd ObservabilityMatrix(const Eigen::MatrixXd& A, const Eigen::RowVectorXd& H);

// Change of basis by the observability matrix, Eq. (1.7) (and (1.10) for discrete systems):
// A1 = N A N⁻¹, B1 = N B, H1 = H N⁻¹. Throws std::invalid_argument if (A, H) is not
// observable (N singular to working precision).
CompactForm ToCompactForm(const Eigen::MatrixXd& A, const Eigen::VectorXd& B,
                          const Eigen::RowVectorXd& H);

// Φ(T) = Σ_{k=0}^{K−1} (A T)^k / k!,  Γ(T) = Σ_{k=0}^{K−1} A^k T^{k+1} B / (k+1)!,  Eq. (1.8)
// with K terms (the paper uses K = 8). The truncation error is measured against Eigen's
// matrix exponential of the augmented matrix [[A B],[0 0]]·T (max-abs difference).
struct SeriesDiscretisation {
  Eigen::MatrixXd Phi;
  Eigen::VectorXd Gamma;
  int terms = 0;
  double truncation_error = 0.0;  // max |series − expm| over Φ and Γ
  double first_omitted_term = 0.0;  // ‖(AT)^K/K!‖_max, the seed's own error indicator
};
SeriesDiscretisation DiscretiseBySeries(const Eigen::MatrixXd& A, const Eigen::VectorXd& B,
                                        double sample_time, int terms = 8);

// Back to continuous time, Eq. (1.16):
// A* = (2/T) Σ_{k=0}^{K−1} X^{2k+1}/(2k+1), X = (Φ − E)(Φ + E)⁻¹;  B* = (Φ − E)⁻¹ A* Γ.
// The series is log(Φ)/T in Gregory's form; it converges when every eigenvalue of Φ has a
// positive real part (spectral radius of X < 1). With terms <= 0 the series is summed until
// the next term is below 1e−16·‖A*‖ (at most 10 000 terms).
struct SeriesLogarithm {
  Eigen::MatrixXd A;
  Eigen::VectorXd B;
  int terms = 0;
  double spectral_radius_x = 0.0;  // ρ(X); the series diverges for ρ(X) >= 1
  bool converged = false;
  double tail_bound = 0.0;        // bound on the omitted tail: ‖X‖^{2K+1}/((2K+1)(1−‖X‖²))·2/T
  double truncation_error = 0.0;  // max |A* − log(Φ)/T| against Eigen's matrix logarithm
};
SeriesLogarithm ContinuousFromDiscreteBySeries(const Eigen::MatrixXd& Phi,
                                               const Eigen::VectorXd& Gamma, double sample_time,
                                               int terms = 0);

}  // namespace idrig
