#pragma once
// Defaults of finite-frequency identification for a user's record (issue 15): the test signal
// (5) found in the record's input when the user does not give it, and the numerator degree γ
// chosen when not given. [Aleksandrov] designs the test signal, so the paper needs neither.
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "core/numeric/finite_frequency/finite_frequency.h"

namespace idrig {

struct TestSignalSearchOptions {
  double peak_threshold = 0.05;    // spectral peaks above this fraction of the largest count
  int max_lines = 32;              // at most this many test lines
  int max_base_divisor = 64;       // ω_b = ω_(lowest line)/m for m = 1..this
  double min_explained = 0.99;     // the multisine must explain this fraction of u's variance
};

struct FoundTestSignal {
  FiniteFrequencySignal signal;    // ω_b, n_k, ρ_k (ρ_k by least squares on the input)
  std::vector<double> phases;      // φ_k of u ≈ Σ ρ_k sin(ω_k t + φ_k), t from the first sample
  double explained = 0.0;          // 1 − ‖u − û‖²/‖u − ū‖²
};

// The multisine in the input samples u(i·h): peaks of the Hann-windowed spectrum, the base
// frequency as the largest ω_b of which every peak is a multiple (within two FFT bins), then ω_b
// refined by least squares of u on Σ (a_k sin + b_k cos)(n_k ω_b t) + c over ω_b (golden
// section within half a bin of the highest line): exact for a noise-free multisine.
// Throws std::invalid_argument when u has no peaks, the peaks share no base frequency, or the
// multisine explains less than min_explained of u (not a multisine: give the frequencies).
FoundTestSignal FindTestSignal(const Eigen::VectorXd& u, double sample_time,
                               const TestSignalSearchOptions& options = {});

struct NumeratorDegreeRow {
  int numerator_degree = 0;        // γ
  double residual = 0.0;           // relative residual of the frequency equations (12)
  std::string status;
};

struct NumeratorDegreeChoice {
  int numerator_degree = 0;
  std::vector<NumeratorDegreeRow> table;
};

// γ from 0 to min(n − 1, 2·lines − n − 1): each identified with `options` (γ replaced); the
// smallest γ whose relative residual is at most max(2·(smallest residual), tolerance). A γ
// that makes (12) exactly determined always fits, so only a smaller γ that fits as well wins.
NumeratorDegreeChoice ChooseNumeratorDegree(const IoRecord& record, const FiniteFrequencyOptions& options,
                                            double tolerance = 1e-3);

}  // namespace idrig
