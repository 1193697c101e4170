#pragma once
// Exact simulation of a continuous SISO plant in the finite-frequency experiments of
// [Aleksandrov]: plant (1) d(p) y = k(p) u + f, driven by the test signal (5) (or, for unstable
// plants, by the (+λ)-block output ũ = u·e^(λ(t−t0)), Eq. (32)), under a piecewise-constant
// disturbance f (such as (39)) and bounded measurement noise η (section 6: y̌ = y + η).
//
// The test signal is generated inside the model by undamped (or e^(λt)-growing) oscillators,
// so the sampled output is the exact continuous-time response at t_k = k·h — no zero-order
// hold on the sine. The disturbance switches at its own instants (the step is split there), so
// f is exact too. t0 = 0, plant at rest at t0 unless the disturbance started earlier.
#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "core/numeric/model/lti_model.h"

namespace idrig {

// f(t) = values[i] for start_times[i] <= t < start_times[i+1]; 0 before start_times[0].
// start_times may begin before 0: the disturbance then acts before t0 (see
// SimulateSineExperiment).
struct PiecewiseConstantSignal {
  std::vector<double> start_times;  // ascending [s]
  std::vector<double> values;
  double ValueAt(double t) const;
};

// How the phase of sign(sin ω_f t) in (39) is counted when ω_f is redrawn.
enum class SquareWavePhase {
  // Each period 2π/ω_f is one whole cycle of the square wave from phase 0: +a for π/ω_f, then
  // −a for π/ω_f (sin ω_f(t − t_c), t_c the start of the period; the phase is continuous, as a
  // generator whose frequency is changed once per period produces it). Every half-wave lasts
  // π/ω_f with ω_f ∈ [ω_min, ω_max]: the disturbance stays in its band. The default.
  kPeriodStart,
  // sin ω_f t with the experiment time t (not restarted): each segment is a full period at a
  // random phase, so the wave has pulses of any width at the redraws — low-frequency content
  // a²E[T⁴]/(48E[T])·ω² (T = 2π/ω_f), 16 times that of kPeriodStart for ω_f ∈ [3, 5].
  kExperimentTime,
};

// Disturbance (39) of [Aleksandrov]: f(t) = a·sign(sin ω_f t), with ω_f drawn uniformly from
// [omega_min, omega_max] (raw std::mt19937_64 output) and redrawn at the end of every period
// 2π/ω_f. Covers [start_time, duration]; start_time < 0 makes the disturbance act before the
// experiment starts (a plant in operation), so that no start-up kick enters the filter: with
// kPeriodStart and the plant at rest at t = 0 the first half-waves integrate to
// ∫f ≈ a·E[T²]/(4E[T]) ≈ 2.05 (a = 5, ω_f ∈ [3, 5]), an impulse-like kick that biases short
// filters by O(1/τ).
PiecewiseConstantSignal RandomSquareWaveDisturbance(
    double amplitude, double omega_min, double omega_max, double duration, uint64_t seed,
    SquareWavePhase phase = SquareWavePhase::kPeriodStart, double start_time = 0.0);

// One line of the test signal: amplitude·sin(omega·t + phase).
struct SineLine {
  double omega = 1.0;  // [rad/s]
  double amplitude = 1.0;
  double phase = 0.0;  // [rad]
};

struct SineExperimentSetup {
  TransferFunction plant;       // continuous w(s) = k(s)/d(s), proper
  std::vector<SineLine> lines;  // test signal (5)
  double lambda = 0.0;          // (+λ) block: the plant input is ũ = u·e^(λt), Eq. (32)
  PiecewiseConstantSignal disturbance;  // f, entering as in (1): y = w·u + f/d(s)
  double noise_bound = 0.0;     // η uniform in [−η*, η*], added to the measured output
  uint64_t noise_seed = 1;
};

struct SineExperimentRecord {
  double sample_time = 0.0;
  Eigen::VectorXd t;               // k·h
  Eigen::VectorXd u;               // plant input (ũ when λ > 0)
  Eigen::VectorXd y;               // measured output y̌ = y + η
  Eigen::VectorXd natural_output;  // ȳ + η: the output without the test signal (for (7))
};

// Samples k = 0..num_samples−1. When the disturbance starts before 0, the plant (at rest, u = 0)
// is first driven by f alone from its first start time up to t0 = 0. Throws std::invalid_argument on a non-proper or discrete plant,
// a non-positive step, or non-finite settings.
SineExperimentRecord SimulateSineExperiment(const SineExperimentSetup& setup, double sample_time,
                                            int64_t num_samples);

}  // namespace idrig
