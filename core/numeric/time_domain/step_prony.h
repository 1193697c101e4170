#pragma once
// Continuous LTI model with multiple (generally complex) poles from a step response, by the
// method of [Vidinčev] (seed 000, Kybernetika 1965):
//
//   K(p) = Σ_v Σ_{j=1..N_v} A_vj / (p + b_v)^(N_v+1−j)                    Eq. (1)
//   order m = Σ_v N_v; poles of K are −b_v (Re b_v > 0); complex b_v come in conjugate pairs.
//
// A step of size C at t = 0 (zero initial conditions) gives x(t) (5) with x(∞) (6). With
// x̄(t) = x(∞) − x(t) (7) sampled every h seconds, the linear prediction
//   x̄(αh) + Σ_{s=1..m} D_s x̄(αh + sh) = 0                                Eqs. (10)–(11), (20)
// holds for every α; the roots z of 1 + Σ D_s z^s = 0 (18) give b_v = −ln(z_v)/h (16), and a
// pole of multiplicity N_v is an N_v-fold root. Against noise the samples are replaced by block
// averages over B sub-intervals of h (25) (system (30); residues by (32)–(35)) or by integrals
// over each interval of length h; the order comes from the residuals (36)–(41).
//
// Beyond the paper (each switchable): the LP may be solved in the rank-m signal subspace of an
// extended matrix, written at every sample shift, with x(∞) re-estimated from the first fit;
// the LP poles are refined by variable projection before multiplicities are decided by a
// noise-level test on the fit (see docs/step_modal.md).
//
// Units: time [s]; b_v [1/s]; A_vj in units of K(p) times (1/s)^(N_v+1−j).
#include <Eigen/Dense>
#include <complex>
#include <limits>
#include <string>
#include <vector>

#include "core/numeric/io_record.h"
#include "core/numeric/model/lti_model.h"
#include "core/numeric/result.h"

namespace idrig {

enum class StepAveraging {
  kNone,      // point samples x̄(αh), systems (20)/(23)
  kBlock,     // block means over B sub-intervals of h, Eq. (25), systems (30)/(35)
  kIntegral,  // ∫_{αh}^{αh+h} x̄(t) dt (trapezoid on the samples), the integral variant
};
const char* ToString(StepAveraging averaging);

enum class StepLpSolver {
  kQr,        // least squares with D_0 = 1 by column-pivoted Householder QR
  kTls,       // total least squares: right singular vector of [x̄(αh) … x̄(αh+mh)] (D_0 = 1)
  kSubspace,  // SVD of the extended matrix [x̄(αh) … x̄(αh+Lh)], L > m, truncated to rank m;
              // the roots of (18) are the eigenvalues of its shift-invariant row space and
              // D_s follow from them (noise outside the rank-m signal space is discarded)
};
const char* ToString(StepLpSolver solver);

struct StepPronyOptions {
  int order = 0;          // m; 0: chosen over 1..max_order from the order table (36)–(41): the
                          // smallest m whose fitted residual is within σ²χ²_0.999 of the minimum
  int max_order = 8;
  int spacing = 0;        // h in samples (h = spacing·Ts); 0: automatic (about 4·max_order
                          // intervals over the transient)
  int blocks = 0;         // B sub-intervals of h for (25); 0: B = spacing (every sample)
  StepAveraging averaging = StepAveraging::kBlock;
  StepLpSolver solver = StepLpSolver::kSubspace;
  int columns = 0;        // L for kSubspace; 0: 3m
  double x_inf = std::numeric_limits<double>::quiet_NaN();  // NaN: estimated from the tail
  double tail_fraction = 0.1;     // last part of the record used for x(∞) and the noise level
  double settle_tolerance = 0.02; // allowed drift over the tail, relative to the response range
  double horizon_factor = 3.0;    // LP rows up to horizon_factor × transient duration
  double max_cluster_distance = 0.5;  // roots farther apart than this (z-plane) never merge
  bool refit_x_inf = true; // after a first pass, take x(∞) of the fitted model (6) and redo the LP
  bool sliding = true;     // LP equations at every sample shift; false: only at α h (paper)
  bool refine = true;  // refine the LP poles by variable-projection least squares on all samples
                       // (Levenberg–Marquardt; beyond the paper), before deciding multiplicities
};

// One distinct pole −b_v with multiplicity N_v; for a complex pair only the member with
// Im(−b) > 0 is listed (its conjugate is implied, with conjugate residues).
struct StepPole {
  std::complex<double> b;      // Eq. (16): b = −ln(z)/h; the pole of K(p) is −b
  int multiplicity = 1;        // N_v
  bool complex_pair = false;
  Eigen::VectorXcd residues;   // A_v1 … A_vN (A_vj multiplies 1/(p + b)^(N+1−j)), chosen set
  Eigen::VectorXcd residues_eq20;  // by the m-point system (20)/(23) (or (35) when averaged)
  Eigen::VectorXcd residues_ls;    // by least squares over all samples
  std::complex<double> Pole() const { return -b; }
  double NaturalFrequency() const { return std::abs(b); }            // rad/s
  double DampingRatio() const { return b.real() / std::abs(b); }
};

struct StepOrderRow {
  int order = 0;
  double residual = 0.0;          // RMS of (38)/(39) over the LP equations, / |(1, D)|
  double condition_number = 0.0;  // of the LP problem (see StepPronyResult)
  double fit_rss = 0.0;           // Σ (x − x̂)² of the fitted order-m model over all samples
};

struct StepPronyResult : ResultBase {
  int order = 0;                   // m (with multiplicities)
  double sample_time = 0.0;        // Ts of the record [s]
  double h = 0.0;                  // LP spacing [s]
  int spacing = 0;                 // h / Ts
  int blocks = 1;                  // B
  StepAveraging averaging = StepAveraging::kBlock;
  StepLpSolver solver = StepLpSolver::kSubspace;
  double step_amplitude = 0.0;     // C
  double step_time = 0.0;          // time of the step in the record [s]
  double x_inf = 0.0;              // x(∞) used to form x̄ (7) (tail mean, or the first-pass model)
  double x_inf_tail = 0.0;         // x(∞) read off the tail
  bool x_inf_estimated = true;
  double x_inf_model = 0.0;        // C·K(0) of the identified model, Eq. (6)
  double noise_sigma = 0.0;        // output noise std estimated from the tail
  int lp_equations = 0;            // rows of the LP system
  Eigen::VectorXd lp_coefficients; // D_1 … D_m (D_0 = 1)
  double lp_condition_number = 0.0;
  Eigen::VectorXcd roots_z;        // all m roots of (18)
  Eigen::VectorXcd lp_poles;       // −b of every root by (16), before refinement
  bool refined = false;            // poles refined by variable projection (iterations = LM steps)
  double cluster_tolerance = 0.0;  // z-plane distance below which roots were merged (0: none)
  std::vector<StepPole> poles;
  std::string residue_method;      // "eq20" or "least_squares": the better fit
  double residue_rss_eq20 = 0.0, residue_rss_ls = 0.0;  // Σ (x − x̂)² over all samples
  double residue_condition_eq20 = 0.0, residue_condition_ls = 0.0;
  std::vector<StepOrderRow> order_table;
  TransferFunction tf;             // continuous K(p) (num/den, descending powers of s)
  Eigen::VectorXd t;               // sample times from the step [s]
  Eigen::VectorXd measured;        // x(t) (baseline removed)
  Eigen::VectorXd fitted;          // C·L⁻¹{K(p)/p} at t
  std::vector<std::string> warnings;
};

// x: step response samples x(kTs), k = 0..N−1, with the step of size C applied at t = 0 and
// zero initial conditions. Throws std::invalid_argument for NaN, too few samples for the
// order, a zero step, or a record that never settles (x(∞) not estimable).
StepPronyResult IdentifyStepResponse(const Eigen::VectorXd& x, double sample_time,
                                     double step_amplitude, const StepPronyOptions& options = {});

// SISO record t,u,y holding a step: the step time and C are read from u (initial level
// before, final level after), the output baseline before the step is removed.
StepPronyResult IdentifyStepResponse(const IoRecord& record, const StepPronyOptions& options = {});

// C·L⁻¹{K(p)/p} at times t for a pole–residue model (Eq. (5)).
Eigen::VectorXd StepPronyResponse(const std::vector<StepPole>& poles, double step_amplitude,
                                  const Eigen::VectorXd& t);

// K(p) as num/den from the pole–residue form (1) (real coefficients).
TransferFunction StepPolesToTransferFunction(const std::vector<StepPole>& poles);

}  // namespace idrig
