#pragma once
// Excitation signals for identification experiments: scaled step, exponential 1 − e^(−t/T)
// (Fig. 7 of [Ivanovsky]), multisine of integer multiples of a base frequency (Eq. (5) of
// [Aleksandrov]), maximum-length PRBS, random binary, chirp (linear/log) and single sine.
//
// Every signal is a deterministic function of its spec (and its seed: std::mt19937_64 only,
// raw engine output, no implementation-defined distributions) sampled at t_k = k/fs, k = 0, 1, …
// (t0 = 0). It is produced either sample by sample by ExcitationGenerator (real time) or as a
// block by GenerateExcitation (offline); both give bit-identical values.
//
// Units: time [s], frequencies in Hz unless the key says rad/s (w, w0), phases [rad],
// amplitudes in the actuator's units. The SPEC string grammar is in docs/excitation.md:
//   kind:key=value,key=value,…      e.g. prbs:bits=10,amp=1
// No I/O here: only parsing of a spec string.
#include <Eigen/Dense>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "core/numeric/model/lti_model.h"

namespace idrig {

enum class ExcitationKind {
  kStep,          // offset + amp·1(t − at)
  kExponential,   // offset + amp·(1 − e^(−(t − at)/T))·1(t − at)
  kSine,          // offset + amp·sin(2π f t + phase)
  kMultisine,     // offset + Σ ρ_k sin(n_k ω_b t + φ_k), Eq. (5) of [Aleksandrov]
  kPrbs,          // offset ± amp, maximum-length LFSR sequence, period (2^bits − 1)/clock
  kRandomBinary,  // offset ± amp, one fair random bit per clock period
  kChirp,         // offset + amp·sin(φ(t mod T)), frequency swept f0 → f1 over T
  kDiagnose,      // offset + the gap-diagnosis sequence over period T (see DiagnoseSegments)
};

// Which harmonics of the base frequency a multisine excites, among lines[].
//   kAll:    every requested line.
//   kOdd:    odd lines only; the even lines stay free to detect even-order distortion.
//   kOddOdd: lines 1, 5, 9, … (4m+1); lines 3, 7, 11, … and the even lines stay free to
//            detect odd- and even-order distortion.
enum class MultisineLineSet { kAll, kOdd, kOddOdd };
enum class MultisinePhase { kZero, kSchroeder, kRandom };
// What `amplitude` means for a multisine: the amplitude of every line (ρ_k = amp, or
// amp·amps[k] with per-line factors), or the RMS of the whole signal.
enum class MultisineScale { kLine, kRms };
enum class ChirpSweep { kLinear, kLogarithmic };

// The most lines a multisine SPEC may list (each costs a sine per sample; a SPEC of a few ranges
// listing 3.5 M lines took 15 s to parse: found by tests/fuzz/fuzz_excitation_spec).
inline constexpr long long kMaxMultisineLines = 10000;

struct ExcitationSpec {
  ExcitationKind kind = ExcitationKind::kSine;
  double amplitude = 1.0;   // amp
  double offset = 0.0;      // offset, added to every signal
  uint64_t seed = 0;        // seed of std::mt19937_64 (random phases, random binary)

  // step, exp
  double start_time = 0.0;  // at [s]
  double time_constant = 1.0;  // T of exp [s]

  // sine
  double frequency_hz = 1.0;  // f (or w/(2π))
  double phase = 0.0;         // [rad]

  // multisine: ω_k = lines[k]·2π·base_frequency_hz, after the line-set filter
  double base_frequency_hz = 0.1;  // f0 (or w0/(2π)); base period T_b = 1/f0
  std::vector<int> lines;          // requested harmonic numbers n_k >= 1 (default 1..10), at most
                                   // kMaxMultisineLines of them
  MultisineLineSet line_set = MultisineLineSet::kAll;
  MultisinePhase phase_rule = MultisinePhase::kZero;
  MultisineScale scale = MultisineScale::kLine;
  std::vector<double> line_amplitudes;  // amps: per requested line factors (same length)
  std::vector<double> line_phases;      // phases: explicit per requested line [rad]

  // prbs, random binary
  int register_bits = 10;  // bits, 2..32
  double clock_hz = 0.0;   // fc, bit rate; 0: one bit per sample (fc = fs)

  // chirp
  double start_frequency_hz = 0.1;  // f0
  double end_frequency_hz = 1.0;    // f1
  double sweep_time = 10.0;         // T [s]: the sweep repeats with this period
  ChirpSweep sweep = ChirpSweep::kLinear;

  // diagnose: period T = sweep_time [s], highest multisine line ≤ f1 = end_frequency_hz, seed
};

// The `diagnose` sequence, designed to separate the effects of the gap diagnosis (amplitude
// dependence, detection lines, reversals, steps). Over each period T:
//   [0, 0.6T)   three blocks of 0.2T: a random-phase odd multisine (base 1/(0.2T), odd lines up
//               to f1; the even lines stay free), RMS 0.06, 0.15, 0.3 × amp (peaks ≈ amp);
//   [0.6T, 0.8T) slow reversals: two triangle periods of peak 0.6 amp;
//   [0.8T, T)   steps: +0.5, −0.5, +1, −1 × amp, 0.05T each.
// The multisine of one block (unit RMS), for analysis of the detection lines.
ExcitationSpec DiagnoseMultisine(const ExcitationSpec& diagnose);

// Parses a SPEC string (grammar in docs/excitation.md). Throws std::invalid_argument naming the
// bad kind, key or value and listing what is allowed.
ExcitationSpec ParseExcitationSpec(const std::string& text);
// The canonical SPEC string of a spec (parses back to the same signal).
std::string FormatExcitationSpec(const ExcitationSpec& spec);
const char* ToString(ExcitationKind kind);

// Checks the spec on its own and against the sample rate fs [Hz]: finite values, positive
// frequencies/time constants, every frequency below Nyquist (fs/2), register length, lines.
// Throws std::invalid_argument with an actionable message.
void ValidateExcitation(const ExcitationSpec& spec, double sample_rate_hz);

// One spectral line of a multisine after the line-set filter and phase rule: the signal is
// Σ amplitude·sin(harmonic·ω_b·t + phase).
struct MultisineLine {
  int harmonic = 0;
  double omega = 0.0;  // harmonic·2π·f0 [rad/s]
  double amplitude = 0.0;
  double phase = 0.0;  // [rad]
};
// The excited lines (ascending harmonic). Schroeder phases are the classic low-crest-factor
// rule φ_k = −2π Σ_{l<k} (k − l) p_l on the cosine form (p_l: power fraction of line l),
// converted to the sine form of Eq. (5).
std::vector<MultisineLine> MultisineLines(const ExcitationSpec& spec);
// The free (unexcited) lines of 1..max(lines) that detect distortion: even lines for kOdd,
// lines 3, 7, 11, … and the even lines for kOddOdd, none for kAll.
std::vector<int> MultisineDetectionLines(const ExcitationSpec& spec);

// Exact period of the signal [s] (0 for aperiodic signals: step, exp, random binary).
//   sine 1/f; multisine 1/f0; prbs (2^bits − 1)/fc; chirp T.
double ExcitationPeriod(const ExcitationSpec& spec, double sample_rate_hz);

// Feedback taps of the Fibonacci LFSR of length `bits` (2..32): exponents e of the primitive
// polynomial x^bits + Σ x^e + 1 (the table of Xilinx XAPP 052 / Wikipedia "LFSR").
std::vector<int> PrbsPolynomialTaps(int bits);

// Sample-by-sample generator (real time). Next() returns u(t_k) and advances k.
class ExcitationGenerator {
 public:
  // Validates (throws std::invalid_argument).
  ExcitationGenerator(const ExcitationSpec& spec, double sample_rate_hz);
  double Next();
  void Reset();
  int64_t sample_index() const { return index_; }
  double time() const { return static_cast<double>(index_) / sample_rate_hz_; }
  const ExcitationSpec& spec() const { return spec_; }

 private:
  ExcitationSpec spec_;
  double sample_rate_hz_;
  int64_t index_ = 0;
  std::vector<MultisineLine> lines_;
  // binary signals: current bit, the bit clock, LFSR state / random engine
  int64_t bit_index_ = -1;
  double bit_value_ = 0.0;
  uint32_t lfsr_state_ = 0;
  uint32_t lfsr_mask_ = 0;
  std::mt19937_64 engine_;
};

// u(t_k), k = 0..num_samples−1, as a block (offline). Same values as ExcitationGenerator.
Eigen::VectorXd GenerateExcitation(const ExcitationSpec& spec, double sample_rate_hz,
                                   int64_t num_samples);

// ---------------------------------------------------------------------------------------------
// Limits and the small-excitation condition (14) of [Aleksandrov].

// Condition (14): |y(t) − ȳ(t)| ≤ ε_y, i.e. the plant's forced response to the excitation
// alone (linear plant: y − ȳ is the response to u from rest) stays within ε_y. Checked on a
// prior model of the plant by exact ZOH simulation at fs over the checked horizon.
struct SmallExcitation {
  bool enabled = false;
  TransferFunction prior_model;  // continuous or discrete prior model of the plant
  double epsilon_y = 0.0;        // ε_y of (14), in output units
  // true: scale the whole signal (amp and offset) so that max|y − ȳ| = ε_y; false: reject a
  // signal that violates (14).
  bool scale_to_fit = true;
};

struct ExcitationLimits {
  double max_abs = 0.0;          // |u_k| ≤ max_abs; 0: unchecked
  double max_rate = 0.0;         // |u_k − u_{k−1}|·fs ≤ max_rate [units/s], u_{−1} = 0; 0: unchecked
  double horizon_s = 0.0;        // checked span; 0: one period (or 10 s for aperiodic signals)
  SmallExcitation small_excitation;
};

struct AcceptedExcitation {
  ExcitationSpec spec;            // possibly with amplitude scaled by condition (14)
  double amplitude_scale = 1.0;   // factor applied to amplitude and offset by condition (14)
  double peak_abs = 0.0;          // max |u_k| over the horizon
  double peak_rate = 0.0;         // max |u_k − u_{k−1}|·fs
  double peak_forced_response = 0.0;  // max |y − ȳ| on the prior model (0 when not checked)
};

// Checks a signal before it is used. Throws std::invalid_argument naming the violated bound,
// the value found and the largest amplitude that would pass.
AcceptedExcitation AcceptExcitation(const ExcitationSpec& spec, double sample_rate_hz,
                                    const ExcitationLimits& limits);

}  // namespace idrig
