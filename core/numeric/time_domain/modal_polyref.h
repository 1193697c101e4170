#pragma once
// MIMO modal identification from a matrix time series of impulse responses, [Balda] (seed 002)
// section 5, Eqs. (38)–(52):
//
//   G(kT) = V exp(k S T) W^H,  k = 0..N−1                                  Eq. (38)
//   G_k ∈ R^{m×n} (m outputs × n inputs), S = diag(s_j) (n_e eigenvalues, conjugate pairs),
//   V ∈ C^{m×n_e} (mode shapes), W ∈ C^{n×n_e} (participation), T = 1/f_s.
//
// A fictitious excitation F_1…F_p (n×n each) brings the impulse-excited system to rest after p
// periods (43); it is the least-squares solution (44) (pseudoinverse). The block companion
// matrix built from −F_κ^T (47) has the eigenvalues Z = exp(S T) (48)–(49), so S = f_s ln Z (50);
// W follows from the eigenvectors (51) and V from the whole record by least squares (52).
// p ≥ n_e/n (42). Spurious eigenvalues (from a p larger than needed, or from noise) are told
// from physical ones by a stabilisation diagram over p.
//
// Units: T [s]; s [1/s]; natural frequency ω_n = |s| [rad/s] and f_n = ω_n/2π [Hz];
// damping ratio ζ = −Re s/|s|.
#include <Eigen/Dense>
#include <complex>
#include <string>
#include <vector>

#include "core/numeric/io_record.h"
#include "core/numeric/model/lti_model.h"
#include "core/numeric/result.h"

namespace idrig {

struct ModalPolyrefOptions {
  int modes = 0;         // n_f expected in the band (0: unknown)
  int p = 0;             // order of the fictitious excitation; 0: from the stabilisation diagram
                         // (the highest order, p_max)
  int p_min = 1;
  int p_max = 0;         // 0: max(4 p_(42), 20) (p_(42) = 0 when `modes` is not given); with
                         // noise the least-squares (44) is biased at low p and settles as p grows
  int first_sample = 1;  // first G_k used (k = 1: skips a direct term G_0 = D of sampled data)
  double max_damping = 0.5;        // poles with a larger ζ (or ζ <= 0) are not modes
  double max_frequency_hz = 0.0;   // band limit; 0: Nyquist
  double frequency_tolerance = 0.01;  // stabilisation: relative change of f_n between orders
  double damping_tolerance = 0.05;    // stabilisation: |Δζ| <= this·ζ + 0.001
  int min_stable_orders = 3;       // a physical mode is found at >= this many orders
  double min_stable_fraction = 0.5;  // ... and at >= this fraction of the orders p_min..p_max
  int als_iterations = 0;  // after W (51) and V (52): alternating least-squares refinements of
                           // W and V on all G_k (beyond the paper; 0 = the paper's estimates)
};

struct StabilisationPoint {
  int p = 0;
  double frequency_hz = 0.0, damping_ratio = 0.0;
  bool stable_frequency = false;  // a pole at p − 1 within the frequency tolerance
  bool stable = false;            // ... and within the damping tolerance
};

struct Mode {
  std::complex<double> s;        // eigenvalue (50), Im s > 0 (its conjugate is implied)
  double natural_frequency_hz = 0.0;
  double natural_frequency_rad_s = 0.0;
  double damping_ratio = 0.0;
  int orders_found = 0;          // orders p of the diagram holding this mode
  Eigen::VectorXcd shape;        // column of V (52), m, scaled so its largest entry is 1
  Eigen::VectorXcd participation;  // column of W (51), n, scaled consistently with `shape`
};

struct ModalPolyrefResult : ResultBase {
  int p = 0;                      // order used for the modes
  int p_eq42 = 0;                 // minimum p by (42) (0 when `modes` is not given)
  double sample_time = 0.0;
  int outputs = 0, inputs = 0, samples = 0;
  double excitation_condition_number = 0.0;  // of the block Hankel matrix in (44)
  Eigen::VectorXcd eigenvalues_z; // all p·n eigenvalues of (49) at the chosen p
  std::vector<Mode> modes;        // physical modes, by increasing frequency
  Eigen::MatrixXd mac;            // MAC between the identified mode shapes
  std::vector<StabilisationPoint> stabilisation;  // every candidate pole at every p
  double fit_percent_impulse = 0.0;  // fit of the modal model (38) to G over all entries
  std::string impulse_response_source = "given";  // or how G was estimated
  std::vector<std::string> warnings;
};

// G: N matrices m×n, equally spaced by sample_time. Throws std::invalid_argument for an empty
// series, inconsistent sizes (naming the first offending k), NaN, or too few samples for p.
ModalPolyrefResult IdentifyModalPolyref(const std::vector<Eigen::MatrixXd>& impulse_responses,
                                        double sample_time, const ModalPolyrefOptions& options = {});

// Discrete real modal realisation of the identified modes, sample time T: its impulse response
// (Markov parameters) h_k = C A^(k−1) B reproduces the modal model (38) of G(kT) for k >= 1
// (D = 0). Each mode gives the 2×2 block [[Re z, −Im z], [Im z, Re z]], z = exp(s T).
StateSpace ModalStateSpace(const ModalPolyrefResult& result, int first_sample = 1);

// Regularised FIR least squares: y(t) = Σ_{k=0}^{L−1} G_k u(t − k) + e, ridge parameter λ
// chosen by generalised cross-validation (or given, λ > 0), shared by all outputs.
struct FirEstimate {
  std::vector<Eigen::MatrixXd> impulse_responses;  // L matrices ny×nu, per unit sample (×1/T
                                                   // would be the continuous impulse density)
  double lambda = 0.0;
  double condition_number = 0.0;  // of Φ^T Φ
  double fit_percent = 0.0;       // one-step FIR fit on the record (mean over outputs)
  std::string method;             // text for reports
};
FirEstimate EstimateImpulseResponseFir(const IoRecord& record, int length, double lambda = 0.0);

// Modal assurance criterion |a^H b|² / ((a^H a)(b^H b)).
double Mac(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b);

}  // namespace idrig
