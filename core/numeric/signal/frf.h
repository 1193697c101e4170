#pragma once
// Frequency-response functions (FRFs) measured on a grid of lines, and their estimation from
// sampled time records (section 1 of [Balda]: "the transition from the time domain to the
// frequency domain uses the discrete Fourier transform, usually as an FFT").
//
// Units: frequencies are ANGULAR, ω [rad/s], everywhere in this header (p = iω). Readers of
// files in Hz convert once (core/io/frf_csv.h).
#include <Eigen/Dense>
#include <complex>
#include <vector>

#include "core/numeric/io_record.h"

namespace idrig {

struct Frf {
  Eigen::VectorXd omega;             // L lines, ω [rad/s], strictly increasing
  std::vector<Eigen::MatrixXcd> h;   // L matrices ny×nu: H(iω_k) (output per unit input)
  // Optional (empty when unknown): noise variance of each element of H, L×(ny·nu) with
  // column index out + ny·in; coherence, L×ny (multiple coherence of each output).
  Eigen::MatrixXd variance;
  Eigen::MatrixXd coherence;
  int averages = 0;                  // segments (Welch) or periods averaged; 0: not estimated

  int NumLines() const { return static_cast<int>(omega.size()); }
  int NumOutputs() const { return h.empty() ? 0 : static_cast<int>(h[0].rows()); }
  int NumInputs() const { return h.empty() ? 0 : static_cast<int>(h[0].cols()); }
  // The (out, in) element on every line.
  Eigen::VectorXcd Element(int out = 0, int in = 0) const;
};

// A SISO FRF from a vector of values.
Frf MakeSisoFrf(const Eigen::VectorXd& omega, const Eigen::VectorXcd& h);

// Throws std::invalid_argument naming the problem: no lines, sizes that differ between
// omega/h/variance/coherence, NaN/Inf (with line), frequencies not strictly increasing, and
// — unless allow_zero_frequency — a line at ω <= 0.
void ValidateFrf(const Frf& frf, bool allow_zero_frequency = false);

struct WelchOptions {
  int segment_length = 0;   // samples per segment (FFT length); 0: N/8 rounded down to even
  double overlap = 0.5;     // fraction of a segment shared with the next, in [0, 1)
  bool hann_window = true;  // Hann window (false: rectangular)
  bool keep_dc = false;     // keep the ω = 0 line
};

// H1 estimator with Welch averaging: on every line, H1 = S_yu S_uu⁻¹ with cross-spectra
// averaged over windowed, overlapping segments; coherence γ²_i = S_yiu S_uu⁻¹ S_uyi / S_yiyi.
// Variance of each H element from the coherence, var ≈ (1 − γ²)|H|²/(n_avg γ²) (Bendat &
// Piersol, for one input). Lines k = 1 … nfft/2 at ω_k = 2πk/(nfft·Ts).
// Throws std::invalid_argument for an invalid record, a segment longer than the record or
// shorter than 8 samples, fewer segments than inputs (S_uu singular), overlap outside [0, 1).
Frf EstimateFrfWelch(const IoRecord& record, const WelchOptions& options = {});

struct PeriodicOptions {
  int period_samples = 0;       // samples per excitation period (required, > 0)
  int skip_periods = 0;         // transient periods dropped at the start
  double excited_threshold = 1e-6;  // keep lines with |Ū| > threshold·max|Ū| (0: keep all)
  bool keep_dc = false;
};

// Periodic excitation, one input: the DFT of each period, averaged over P periods
// (Ū, Ȳ); H = Ȳ/Ū on the excited lines, and the noise variance of H per line from the
// scatter between periods: var H ≈ (σ²_Y + |H|²σ²_U − 2 Re(H̄ σ_YU))/(P |Ū|²), σ² the sample
// (co)variances over periods. coherence is left empty. Throws std::invalid_argument for
// more than one input, fewer than 2 full periods, or no excited line.
Frf EstimateFrfPeriodic(const IoRecord& record, const PeriodicOptions& options);

}  // namespace idrig
