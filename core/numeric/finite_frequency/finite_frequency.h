#pragma once
// Finite-frequency identification of [Aleksandrov] (seed 003).
//
// Plant (1), SISO, continuous time, t >= t0:
//   d_n y^(n) + … + d_1 y' + y = k_γ u^(γ) + … + k_1 u' + k_0 u + f,      γ < n,
// w(s) = k(s)/d(s), Eq. (4), d(0) = 1. f is an unknown bounded disturbance.
//
// Test signal (5): u = Σ_k ρ_k sin ω_k (t − t0), ω_k = n_k·ω_b with integer n_k (ω_b: base
// frequency [rad/s], T_b = 2π/ω_b: base period [s]).
// Fourier filter (6): α_k(τ) = 2/(ρ_k τ) ∫ y sin ω_k(t−t0) dt, β_k(τ) = 2/(ρ_k τ) ∫ y cos …,
// over τ = q·T_b, integrated by the trapezoid rule on the samples (spectrally accurate for
// whole periods), with the end of τ interpolated linearly when it falls between samples.
// Frequency equations (12): k(jω_k) − (α_k + jβ_k)·d̄(jω_k) = α_k + jβ_k, d̄ = d − 1, solved
// for d_1..d_n, k_0..k_γ (least squares when 2·#lines > n + γ + 1).
// Stopping rule (13): successive base periods agree to the relative tolerances ε^d, ε^k.
// Filterability (7)–(8): the filter applied to the unexcited output ȳ.
// Natural-frequency range (section 4–5): T_lower (19) with halving (24), T_upper (25)/(26)
// with doubling; ω̂ = 1/T, Eqs. (23), (30).
// Unstable plants (section 6): the (+λ) block feeds ũ = u e^(λ(t−t0)) (32), the (−λ) block
// forms ỹ = y e^(−λ(t−t0)) (31); the identified w̃(s) = w(s + λ) (35) is shifted back.
// Measurement noise (section 6): y̌ = y + η replaces y in (6) and ȳ + η replaces ȳ in (7).
#include <Eigen/Dense>
#include <functional>
#include <string>
#include <vector>

#include "core/numeric/io_record.h"
#include "core/numeric/model/lti_model.h"
#include "core/numeric/result.h"

namespace idrig {

// The test signal (5): lines ω_k = multiples[k]·base_omega with amplitudes ρ_k (zero phases).
struct FiniteFrequencySignal {
  double base_omega = 0.0;          // ω_b [rad/s]
  std::vector<int> multiples;       // n_k >= 1, distinct
  std::vector<double> amplitudes;   // ρ_k > 0, one per line

  double BasePeriod() const;        // T_b = 2π/ω_b [s]
  Eigen::VectorXd Omegas() const;   // ω_k [rad/s]
  double ValueAt(double t) const;   // u(t0 + t), Eq. (5)
};
// Throws std::invalid_argument: empty, non-positive ω_b, multiples not positive integers or
// repeated, sizes differ, non-positive or non-finite amplitudes, lines above Nyquist (when
// sample_time > 0).
void ValidateSignal(const FiniteFrequencySignal& signal, double sample_time = 0.0);
// The same signal as a test frequency list: throws std::invalid_argument when an ω_k is not an
// integer multiple of ω_b (relative tolerance `tolerance`).
FiniteFrequencySignal MakeFiniteFrequencySignal(double base_omega, const Eigen::VectorXd& omegas,
                                                const std::vector<double>& amplitudes,
                                                double tolerance = 1e-9);

// Estimates of the frequency parameters (3) after q base periods.
struct FrequencyParameters {
  int base_periods = 0;   // q
  double tau = 0.0;       // q·T_b [s]
  Eigen::VectorXd alpha;  // α_k(τ) ≈ Re w(jω_k)
  Eigen::VectorXd beta;   // β_k(τ) ≈ Im w(jω_k)
};

// Streaming Fourier filter (6) for live use: feed output samples y(t0 + i·h); after each base
// period boundary qT_b it holds α_k(qT_b), β_k(qT_b). With lambda > 0 the (−λ) block (31) is
// applied to each sample first: ỹ = y·e^(−λ(t_start + t − t0)), where `block_time_offset` is
// the time of the first fed sample since the λ blocks started (whole base periods skipped).
class FourierFilter {
 public:
  FourierFilter(const FiniteFrequencySignal& signal, double sample_time, double lambda = 0.0,
                double block_time_offset = 0.0);
  // Adds the next sample; returns true when it completed one or more base periods.
  bool Add(double y);
  int completed_periods() const { return static_cast<int>(estimates_.size()); }
  const std::vector<FrequencyParameters>& estimates() const { return estimates_; }

 private:
  FiniteFrequencySignal signal_;
  Eigen::VectorXd omegas_, rho_;
  double sample_time_, lambda_, block_time_offset_, base_period_;
  long samples_ = 0;
  double last_value_ = 0.0;  // ỹ at the last sample
  Eigen::VectorXd sin_sum_, cos_sum_;  // trapezoid sums of ỹ·sin, ỹ·cos up to the last sample
  Eigen::VectorXd last_sin_, last_cos_;
  std::vector<FrequencyParameters> estimates_;
};

// Fourier filter (6) over τ = q·T_b for q = 1..max (all whole base periods in the record, or
// max_base_periods when > 0). `y` holds y(t0 + i·h).
std::vector<FrequencyParameters> FourierFilterPerBasePeriod(const Eigen::VectorXd& y,
                                                            double sample_time,
                                                            const FiniteFrequencySignal& signal,
                                                            double lambda = 0.0,
                                                            int max_base_periods = 0);

// Filterability functions (7) from the unexcited output ȳ (or ȳ + η), and condition (8).
struct FilterabilityOptions {
  double epsilon_alpha = 0.01;  // ε_k^α of (8), same for every line
  double epsilon_beta = 0.01;   // ε_k^β of (8)
};
struct FilterabilityResult : ResultBase {
  std::vector<FrequencyParameters> functions;  // ℓ_k^α(qT_b) in alpha, ℓ_k^β(qT_b) in beta
  // First q from which (8) holds up to the end of the record (0 if it never does).
  int filterable_from = 0;
};
FilterabilityResult CheckFilterability(const Eigen::VectorXd& natural_output, double sample_time,
                                       const FiniteFrequencySignal& signal,
                                       const FilterabilityOptions& options = {});

// The frequency equations (12) (or (11) with exact parameters).
struct FrequencyEquationsResult : ResultBase {
  Eigen::VectorXd d;  // d_1..d_n
  Eigen::VectorXd k;  // k_0..k_γ
  double condition_number = 0.0;  // of the column-equilibrated real system
  TransferFunction model;         // w(s) = k(s)/d(s), descending coefficients
};
// omegas: ω_k; alpha/beta: α̂_k, β̂_k. Needs 2·#lines >= n + γ + 1 and distinct non-zero ω_k.
FrequencyEquationsResult SolveFrequencyEquations(const Eigen::VectorXd& omegas,
                                                 const Eigen::VectorXd& alpha,
                                                 const Eigen::VectorXd& beta, int order,
                                                 int numerator_degree);

// Eq. (35): coefficients of w(s) from those of w̃(s) = w(s + λ) (both with d(0) = 1,
// d̃(0) = 1): d(s) = d̃(s − λ)/d̃(−λ), k(s) = k̃(s − λ)/d̃(−λ). Ascending d_1..d_n, k_0..k_γ.
void UnshiftCoefficients(double lambda, Eigen::VectorXd* d, Eigen::VectorXd* k);

struct FiniteFrequencyOptions {
  int order = 0;             // n (required)
  int numerator_degree = 0;  // γ < n
  FiniteFrequencySignal signal;  // the test signal (5) that was applied
  double epsilon_d = 0.005;  // ε_i^d of (13), relative
  double epsilon_k = 0.005;  // ε_j^k of (13), relative
  int consecutive = 2;       // (13) must hold for this many successive q (1: the paper's rule)
  int min_base_periods = 2;  // q before (13) is first checked
  int max_base_periods = 0;  // 0: every whole base period in the record
  // τ [s]: a fixed filter time instead of the stopping rule; must be q·T_b (0: rule decides).
  double filter_time = 0.0;
  int skip_base_periods = 0; // whole base periods discarded before t0 (transient); 0: paper
  // Unstable plants (section 6): λ > 0 means the record's input was ũ = u e^(λt) and the
  // (−λ) block is applied to y; the coefficients are shifted back by (35).
  double lambda = 0.0;
  // Note 6.1: bounds |ũ| <= input_bound, |y| <= output_bound (0: unchecked). The record is used
  // only up to the first violation. For λ = 0 a test signal whose peak bound Σρ_k exceeds
  // input_bound is rejected before anything else (std::invalid_argument).
  double input_bound = 0.0;
  double output_bound = 0.0;
  // The record's input was held between samples (a zero-order hold, as a rig's actuator or
  // `idrig simulate` holds it): the filter (6) then measures w(s)·Z(s) at s = λ + jω_k, with
  // Z(s) = (1 − e^(−sh))/(sh) (= e^(−jωh/2)·sin(ωh/2)/(ωh/2) for λ = 0), a half-sample delay.
  // true: α_k + jβ_k are divided by Z before (12), exactly per line. false: the paper's
  // continuous sine generators (no hold).
  bool zoh_correction = false;
};

struct FiniteFrequencyEstimate {
  int base_periods = 0;  // q
  double tau = 0.0;      // q·T_b
  Eigen::VectorXd alpha, beta, d, k;
  double condition_number = 0.0;
  bool rule_met = false;  // (13) against q − 1
};

struct FiniteFrequencyResult : ResultBase {
  Eigen::VectorXd d;     // d_1..d_n at the stopping q (or the last q)
  Eigen::VectorXd k;     // k_0..k_γ
  TransferFunction model;
  int base_periods = 0;  // q_1: base periods it took (τ = q_1·T_b)
  double tau = 0.0;
  bool stopping_rule_met = false;
  bool bound_reached = false;  // note 6.1: a bound cut the record short
  double record_used_s = 0.0;  // seconds of record before any bound violation
  std::vector<FiniteFrequencyEstimate> history;  // one per base period (live display); α, β
                                                 // after the ZOH correction when it is on
};

// Algorithm 2.1 of [Aleksandrov] on a record whose input is the test signal (5) (ũ for λ > 0)
// started at the record's first sample (t0). Throws std::invalid_argument on malformed input;
// reports kNotConverged when (13) is never met within the record.
FiniteFrequencyResult IdentifyFiniteFrequency(const IoRecord& record,
                                              const FiniteFrequencyOptions& options);
FiniteFrequencyResult IdentifyFiniteFrequency(const Eigen::VectorXd& y, double sample_time,
                                              const FiniteFrequencyOptions& options,
                                              const Eigen::VectorXd& u = Eigen::VectorXd());

// ---------------------------------------------------------------------------------------------
// Natural-frequency range: experiments 4.1 and 5.1.

// Eq. (19): T_lower = −β_1/(ω_1 α_1).
double LowerTimeConstant(double alpha, double beta, double omega);
// Eq. (25), n − γ even: T_upper = α_1/(ω_1 β_1); Eq. (26), n − γ odd: T_upper = −β_1/(ω_1 α_1)
// (the paper prints −β_1/(ω_1 β_1), a misprint: the imaginary part of (П.14) for odd n − γ
// gives −β/(ωα)).
double UpperTimeConstant(double alpha, double beta, double omega, int relative_degree);

// One sine experiment on the plant: apply u = amplitude·sin(omega·t) from t0 = 0 and return
// the measured output y(i·h), i = 0..samples−1 (a rig, or a simulation).
using SineExperimentRunner =
    std::function<Eigen::VectorXd(double amplitude, double omega, double sample_time,
                                  long samples)>;

struct RangeExperimentOptions {
  double initial_omega = 0.0;    // ω_1^[1] [rad/s]: small for 4.1, large for 5.1
  double amplitude = 1.0;        // ρ_1 (chosen by (14))
  double filter_time = 0.0;      // τ* [s], rounded to a whole number (>= 1) of periods 2π/ω_1
  double delta_t = 0.05;         // δ_T of (24)
  int max_experiments = 8;       // halvings/doublings before giving up
  int samples_per_period = 400;  // sampling of each experiment
  double max_sample_time = 0.0;  // cap on h [s] (0: none)
  int relative_degree = 1;       // n − γ, selects (25) or (26) for the upper bound
  int skip_periods = 0;          // periods discarded before t0 (transient)
};

struct RangeExperimentStep {
  double omega = 0.0, tau = 0.0, sample_time = 0.0;
  double alpha = 0.0, beta = 0.0;
  double time_constant = 0.0;  // T(ω_1, τ) of (19) or (25)/(26)
};

struct FrequencyBoundResult : ResultBase {
  double time_constant = 0.0;  // T at the accepted ω_1
  double omega_bound = 0.0;    // ω̂ = 1/T, Eqs. (23), (30)
  std::vector<RangeExperimentStep> steps;
};

// Experiment 4.1 with the halving check (24).
FrequencyBoundResult EstimateLowerFrequencyBound(const SineExperimentRunner& run,
                                                 const RangeExperimentOptions& options);
// Experiment 5.1 with the doubling check.
FrequencyBoundResult EstimateUpperFrequencyBound(const SineExperimentRunner& run,
                                                 const RangeExperimentOptions& options);
// One experiment (no repetition): T(ω_1, τ) for the lower (19) or upper (25)/(26) bound.
RangeExperimentStep RunRangeExperiment(const SineExperimentRunner& run, double omega,
                                       const RangeExperimentOptions& options, bool upper);

// n test frequencies inside [ω_lower, ω_upper], geometrically spaced, as integer multiples of
// the base ω_b = ω_lower/base_divisor (so that τ = q·T_b holds whole periods of every line).
FiniteFrequencySignal ChooseTestFrequencies(double omega_lower, double omega_upper, int count,
                                            double amplitude, int base_divisor = 1);

}  // namespace idrig
