#pragma once
// Exact simulation of a continuous SISO plant in the finite-frequency experiments of
// [Aleksandrov]: plant (1) d(p) y = k(p) u + f, driven by the test signal (5) (or, for unstable
// plants, by the (+λ)-block output ũ = u·e^(λ(t−t0)), Eq. (32)), under a piecewise-constant
// disturbance f (such as (39)) and bounded measurement noise η (section 6: y̌ = y + η).
//
// The test signal is generated inside the model by undamped (or e^(λt)-growing) oscillators,
// so the sampled output is the exact continuous-time response at t_k = k·h — no zero-order
// hold on the sine. The disturbance switches at its own instants (the step is split there), so
// f is exact too. t0 = 0, plant at rest.
#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "core/numeric/lti_model.h"

namespace idrig {

// f(t) = values[i] for start_times[i] <= t < start_times[i+1]; 0 before start_times[0].
struct PiecewiseConstantSignal {
  std::vector<double> start_times;  // ascending [s]
  std::vector<double> values;
  double ValueAt(double t) const;
};

// Disturbance (39) of [Aleksandrov]: f(t) = a·sign(sin ω_f t), with ω_f drawn uniformly from
// [omega_min, omega_max] (raw std::mt19937_64 output) and redrawn at the end of every period
// 2π/ω_f. t is the experiment time, as (39) is written: sin is not restarted at each redraw, so
// each segment is one full square-wave period at a random phase. (Restarting every segment at
// phase 0 would make ∫f dt >= 0 throughout, an impulse-like start-up kick of area ≈ a·2π/(4ω_f)
// that biases short filters by O(1/τ).) Covers [0, duration].
PiecewiseConstantSignal RandomSquareWaveDisturbance(double amplitude, double omega_min,
                                                    double omega_max, double duration,
                                                    uint64_t seed);

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

// Samples k = 0..num_samples−1. Throws std::invalid_argument on a non-proper or discrete plant,
// a non-positive step, or non-finite settings.
SineExperimentRecord SimulateSineExperiment(const SineExperimentSetup& setup, double sample_time,
                                            int64_t num_samples);

}  // namespace idrig
