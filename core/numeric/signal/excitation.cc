// Excitation signals: values, sample-by-sample generator and block generation.
// The SPEC grammar is in excitation_spec.cc, limits and condition (14) in excitation_limits.cc.
#include "core/numeric/signal/excitation.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace idrig {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

void Require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument("excitation: " + message);
}

std::string Num(double value) {
  std::ostringstream out;
  out.precision(10);
  out << value;
  return out.str();
}

// Uniform double in [0, 1) from the raw engine output (portable: no std distribution).
double UnitUniform(std::mt19937_64& engine) {
  return static_cast<double>(engine() >> 11) * 0x1.0p-53;
}

// Bit index of sample k for a bit clock fc: floor(k·fc/fs), guarded against k·fc/fs landing
// just below an integer by rounding.
int64_t BitIndex(int64_t k, double clock_hz, double sample_rate_hz) {
  const double bits = static_cast<double>(k) * clock_hz / sample_rate_hz;
  return static_cast<int64_t>(std::floor(bits + 1e-9));
}

double EffectiveClock(const ExcitationSpec& spec, double sample_rate_hz) {
  return spec.clock_hz > 0.0 ? spec.clock_hz : sample_rate_hz;
}

uint32_t LfsrMask(int bits) {
  uint32_t mask = 0;
  for (int exponent : PrbsPolynomialTaps(bits)) mask |= 1u << (bits - exponent);
  return mask | 1u;  // the x^bits term: the output bit itself
}

uint32_t LfsrInitialState(int bits) {
  return bits == 32 ? 0xFFFFFFFFu : ((1u << bits) - 1u);
}

// One Fibonacci LFSR step: returns the output bit, updates the state.
int LfsrStep(uint32_t& state, uint32_t mask, int bits) {
  const int out = static_cast<int>(state & 1u);
  const uint32_t feedback = static_cast<uint32_t>(__builtin_parity(state & mask));
  state = (state >> 1) | (feedback << (bits - 1));
  return out;
}

// Value of the analytic (stateless) signals at t_k = k/fs.
double AnalyticValue(const ExcitationSpec& spec, const std::vector<MultisineLine>& lines,
                     int64_t k, double sample_rate_hz) {
  const double t = static_cast<double>(k) / sample_rate_hz;
  switch (spec.kind) {
    case ExcitationKind::kStep:
      return spec.offset + (t >= spec.start_time ? spec.amplitude : 0.0);
    case ExcitationKind::kExponential:
      return spec.offset + (t >= spec.start_time
                                ? spec.amplitude *
                                      (1.0 - std::exp(-(t - spec.start_time) / spec.time_constant))
                                : 0.0);
    case ExcitationKind::kSine: {
      const double cycles = spec.frequency_hz * t;
      return spec.offset +
             spec.amplitude * std::sin(kTwoPi * (cycles - std::floor(cycles)) + spec.phase);
    }
    case ExcitationKind::kMultisine: {
      // Eq. (5) of [Aleksandrov]: u = Σ ρ_k sin(ω_k (t − t0) + φ_k), ω_k = n_k ω_b.
      double sum = spec.offset;
      for (const MultisineLine& line : lines) {
        const double cycles = line.harmonic * spec.base_frequency_hz * t;
        sum += line.amplitude * std::sin(kTwoPi * (cycles - std::floor(cycles)) + line.phase);
      }
      return sum;
    }
    case ExcitationKind::kChirp: {
      const double period = spec.sweep_time;
      const double tm = t - period * std::floor(t / period);
      const double f0 = spec.start_frequency_hz, f1 = spec.end_frequency_hz;
      double phase;
      if (spec.sweep == ChirpSweep::kLinear) {
        phase = kTwoPi * (f0 * tm + 0.5 * (f1 - f0) * tm * tm / period);
      } else {
        const double ratio = f1 / f0;
        phase = kTwoPi * f0 * period / std::log(ratio) * (std::pow(ratio, tm / period) - 1.0);
      }
      return spec.offset + spec.amplitude * std::sin(phase);
    }
    case ExcitationKind::kDiagnose: {
      const double period = spec.sweep_time;
      const double tm = t - period * std::floor(t / period);
      const double x = tm / period;  // position in the period, [0, 1)
      double value;
      if (x < 0.6) {
        static const double kLevels[3] = {0.06, 0.15, 0.3};
        const int block = std::min(2, static_cast<int>(x / 0.2));
        const double base = 1.0 / (0.2 * period);
        double sum = 0.0;
        for (const MultisineLine& line : lines) {
          const double cycles = line.harmonic * base * tm;
          sum += line.amplitude * std::sin(kTwoPi * (cycles - std::floor(cycles)) + line.phase);
        }
        value = kLevels[block] * sum;
      } else if (x < 0.8) {
        const double phase = (x - 0.6) / 0.1;  // two triangle periods
        const double f = phase - std::floor(phase);
        value = 0.6 * (f < 0.25 ? 4 * f : (f < 0.75 ? 2 - 4 * f : 4 * f - 4));
      } else {
        static const double kSteps[4] = {0.5, -0.5, 1.0, -1.0};
        value = kSteps[std::min(3, static_cast<int>((x - 0.8) / 0.05))];
      }
      return spec.offset + spec.amplitude * value;
    }
    default:
      return 0.0;  // binary signals are stateful
  }
}

std::vector<MultisineLine> DiagnoseLines(const ExcitationSpec& spec) {
  return MultisineLines(DiagnoseMultisine(spec));
}

}  // namespace

const char* ToString(ExcitationKind kind) {
  switch (kind) {
    case ExcitationKind::kStep: return "step";
    case ExcitationKind::kExponential: return "exp";
    case ExcitationKind::kSine: return "sine";
    case ExcitationKind::kMultisine: return "multisine";
    case ExcitationKind::kPrbs: return "prbs";
    case ExcitationKind::kRandomBinary: return "rbs";
    case ExcitationKind::kChirp: return "chirp";
    case ExcitationKind::kDiagnose: return "diagnose";
  }
  return "?";
}

std::vector<int> PrbsPolynomialTaps(int bits) {
  // Primitive polynomials x^bits + Σ x^e + 1 (maximum-length LFSR feedback), listed as the
  // exponents {bits, e…}; from the Wikipedia "Linear-feedback shift register" table (2..24)
  // and Xilinx XAPP 052 (25..32). Primitivity is verified in tests/unit/excitation.
  static const std::vector<std::vector<int>> kTaps = {
      {},           {},           {2, 1},       {3, 2},         {4, 3},        {5, 3},
      {6, 5},       {7, 6},       {8, 6, 5, 4}, {9, 5},         {10, 7},       {11, 9},
      {12, 11, 10, 4}, {13, 12, 11, 8}, {14, 13, 12, 2}, {15, 14}, {16, 15, 13, 4}, {17, 14},
      {18, 11},     {19, 18, 17, 14}, {20, 17}, {21, 19},       {22, 21},      {23, 18},
      {24, 23, 22, 17}, {25, 22}, {26, 6, 2, 1}, {27, 5, 2, 1}, {28, 25},     {29, 27},
      {30, 6, 4, 1}, {31, 28},    {32, 22, 2, 1}};
  Require(bits >= 2 && bits <= 32,
          "PRBS register length bits=" + std::to_string(bits) + " is outside 2..32");
  return kTaps[bits];
}

std::vector<MultisineLine> MultisineLines(const ExcitationSpec& spec) {
  std::vector<int> requested = spec.lines;
  if (requested.empty())
    for (int n = 1; n <= 10; ++n) requested.push_back(n);
  Require(spec.line_amplitudes.empty() || spec.line_amplitudes.size() == requested.size(),
          "multisine: amps has " + std::to_string(spec.line_amplitudes.size()) +
              " values but lines has " + std::to_string(requested.size()));
  Require(spec.line_phases.empty() || spec.line_phases.size() == requested.size(),
          "multisine: phases has " + std::to_string(spec.line_phases.size()) +
              " values but lines has " + std::to_string(requested.size()));
  std::vector<MultisineLine> lines;
  std::vector<double> explicit_phases;
  for (size_t i = 0; i < requested.size(); ++i) {
    const int n = requested[i];
    Require(n >= 1, "multisine: line " + std::to_string(n) + " is not a positive integer");
    const bool keep = spec.line_set == MultisineLineSet::kAll ||
                      (spec.line_set == MultisineLineSet::kOdd && n % 2 == 1) ||
                      (spec.line_set == MultisineLineSet::kOddOdd && n % 4 == 1);
    if (!keep) continue;
    MultisineLine line;
    line.harmonic = n;
    line.omega = kTwoPi * n * spec.base_frequency_hz;
    line.amplitude = spec.line_amplitudes.empty() ? 1.0 : spec.line_amplitudes[i];
    lines.push_back(line);
    if (!spec.line_phases.empty()) explicit_phases.push_back(spec.line_phases[i]);
  }
  Require(!lines.empty(), "multisine: the line set leaves no excited line; widen lines= or use set=all");
  std::vector<size_t> order(lines.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return lines[a].harmonic < lines[b].harmonic; });
  std::vector<MultisineLine> sorted;
  std::vector<double> sorted_phases;
  for (size_t i : order) {
    sorted.push_back(lines[i]);
    if (!explicit_phases.empty()) sorted_phases.push_back(explicit_phases[i]);
  }
  lines.swap(sorted);
  for (size_t i = 1; i < lines.size(); ++i)
    Require(lines[i].harmonic != lines[i - 1].harmonic,
            "multisine: line " + std::to_string(lines[i].harmonic) + " is listed twice");

  // Amplitudes: per line, or scaled to the requested RMS (lines are orthogonal harmonics:
  // RMS² = Σ ρ_k²/2).
  double power = 0.0;
  for (const auto& line : lines) power += 0.5 * line.amplitude * line.amplitude;
  Require(power > 0.0, "multisine: every line amplitude is zero");
  const double gain =
      spec.scale == MultisineScale::kRms ? spec.amplitude / std::sqrt(power) : spec.amplitude;
  for (auto& line : lines) line.amplitude *= gain;

  // Phases.
  if (!sorted_phases.empty()) {
    for (size_t i = 0; i < lines.size(); ++i) lines[i].phase = sorted_phases[i];
  } else if (spec.phase_rule == MultisinePhase::kSchroeder) {
    // Schroeder (1970): on u = Σ A_k cos(ω_k t + θ_k), θ_k = −2π Σ_{l<k} (k − l) p_l with
    // p_l = A_l²/Σ A² (k, l: positions among the excited lines). sin(x + θ + π/2) = cos(x + θ).
    double total = 0.0;
    for (const auto& line : lines) total += line.amplitude * line.amplitude;
    for (size_t k = 0; k < lines.size(); ++k) {
      double theta = 0.0;
      for (size_t l = 0; l < k; ++l)
        theta -= kTwoPi * static_cast<double>(k - l) * lines[l].amplitude * lines[l].amplitude /
                 total;
      lines[k].phase = std::remainder(theta + 0.25 * kTwoPi, kTwoPi);
    }
  } else if (spec.phase_rule == MultisinePhase::kRandom) {
    std::mt19937_64 engine(spec.seed);
    for (auto& line : lines) line.phase = kTwoPi * UnitUniform(engine);
  }
  return lines;
}

std::vector<int> MultisineDetectionLines(const ExcitationSpec& spec) {
  std::vector<int> free_lines;
  if (spec.line_set == MultisineLineSet::kAll) return free_lines;
  int max_line = 10;
  if (!spec.lines.empty()) max_line = *std::max_element(spec.lines.begin(), spec.lines.end());
  const auto excited = MultisineLines(spec);
  for (int n = 1; n <= max_line; ++n) {
    const bool is_excited = std::any_of(excited.begin(), excited.end(),
                                        [n](const MultisineLine& l) { return l.harmonic == n; });
    if (!is_excited) free_lines.push_back(n);
  }
  return free_lines;
}

void ValidateExcitation(const ExcitationSpec& spec, double sample_rate_hz) {
  Require(std::isfinite(sample_rate_hz) && sample_rate_hz > 0.0,
          "sample rate fs=" + Num(sample_rate_hz) + " Hz must be a positive number");
  const double nyquist = 0.5 * sample_rate_hz;
  Require(std::isfinite(spec.amplitude), "amp must be a finite number");
  Require(std::isfinite(spec.offset), "offset must be a finite number");
  switch (spec.kind) {
    case ExcitationKind::kStep:
      Require(std::isfinite(spec.start_time) && spec.start_time >= 0.0,
              "step: at=" + Num(spec.start_time) + " must be >= 0 s");
      break;
    case ExcitationKind::kExponential:
      Require(std::isfinite(spec.start_time) && spec.start_time >= 0.0,
              "exp: at=" + Num(spec.start_time) + " must be >= 0 s");
      Require(std::isfinite(spec.time_constant) && spec.time_constant > 0.0,
              "exp: T=" + Num(spec.time_constant) + " must be a positive time constant [s]");
      break;
    case ExcitationKind::kSine:
      Require(std::isfinite(spec.frequency_hz) && spec.frequency_hz > 0.0,
              "sine: f=" + Num(spec.frequency_hz) + " Hz must be positive");
      Require(spec.frequency_hz < nyquist, "sine: f=" + Num(spec.frequency_hz) +
                                               " Hz is not below the Nyquist frequency fs/2=" +
                                               Num(nyquist) + " Hz; raise fs or lower f");
      Require(std::isfinite(spec.phase), "sine: phase must be finite");
      break;
    case ExcitationKind::kMultisine: {
      Require(std::isfinite(spec.base_frequency_hz) && spec.base_frequency_hz > 0.0,
              "multisine: f0=" + Num(spec.base_frequency_hz) + " Hz must be positive");
      for (double a : spec.line_amplitudes)
        Require(std::isfinite(a) && a >= 0.0, "multisine: amps must be finite and >= 0");
      for (double p : spec.line_phases) Require(std::isfinite(p), "multisine: phases must be finite");
      const auto lines = MultisineLines(spec);
      const double top = lines.back().harmonic * spec.base_frequency_hz;
      Require(top < nyquist, "multisine: the highest line " +
                                 std::to_string(lines.back().harmonic) + "·f0 = " + Num(top) +
                                 " Hz is not below fs/2=" + Num(nyquist) +
                                 " Hz; raise fs or lower f0/lines");
      break;
    }
    case ExcitationKind::kPrbs:
    case ExcitationKind::kRandomBinary:
      if (spec.kind == ExcitationKind::kPrbs) PrbsPolynomialTaps(spec.register_bits);
      Require(std::isfinite(spec.clock_hz) && spec.clock_hz >= 0.0,
              "fc=" + Num(spec.clock_hz) + " Hz must be >= 0 (0: one bit per sample)");
      Require(spec.clock_hz <= sample_rate_hz,
              "bit clock fc=" + Num(spec.clock_hz) + " Hz exceeds the sample rate fs=" +
                  Num(sample_rate_hz) + " Hz; bits would be skipped");
      break;
    case ExcitationKind::kChirp:
      Require(std::isfinite(spec.start_frequency_hz) && spec.start_frequency_hz > 0.0 &&
                  std::isfinite(spec.end_frequency_hz) && spec.end_frequency_hz > 0.0,
              "chirp: f0 and f1 must be positive frequencies [Hz]");
      Require(std::max(spec.start_frequency_hz, spec.end_frequency_hz) < nyquist,
              "chirp: max(f0, f1)=" +
                  Num(std::max(spec.start_frequency_hz, spec.end_frequency_hz)) +
                  " Hz is not below fs/2=" + Num(nyquist) + " Hz");
      Require(std::isfinite(spec.sweep_time) && spec.sweep_time > 0.0,
              "chirp: T=" + Num(spec.sweep_time) + " s must be positive");
      Require(spec.sweep == ChirpSweep::kLinear ||
                  spec.start_frequency_hz != spec.end_frequency_hz,
              "chirp: a log sweep needs f0 != f1");
      break;
    case ExcitationKind::kDiagnose:
      Require(std::isfinite(spec.sweep_time) && spec.sweep_time > 0.0,
              "diagnose: T=" + Num(spec.sweep_time) + " s must be positive");
      Require(std::isfinite(spec.end_frequency_hz) && spec.end_frequency_hz >= 5.0 / spec.sweep_time,
              "diagnose: f1=" + Num(spec.end_frequency_hz) +
                  " Hz must be at least the multisine base 5/T=" + Num(5.0 / spec.sweep_time) + " Hz");
      Require(spec.end_frequency_hz < nyquist, "diagnose: f1=" + Num(spec.end_frequency_hz) +
                                                   " Hz is not below fs/2=" + Num(nyquist) + " Hz");
      break;
  }
}

double ExcitationPeriod(const ExcitationSpec& spec, double sample_rate_hz) {
  switch (spec.kind) {
    case ExcitationKind::kSine: return 1.0 / spec.frequency_hz;
    case ExcitationKind::kMultisine: return 1.0 / spec.base_frequency_hz;
    case ExcitationKind::kChirp:
    case ExcitationKind::kDiagnose: return spec.sweep_time;
    case ExcitationKind::kPrbs:
      return (std::ldexp(1.0, spec.register_bits) - 1.0) / EffectiveClock(spec, sample_rate_hz);
    default: return 0.0;
  }
}

ExcitationSpec DiagnoseMultisine(const ExcitationSpec& diagnose) {
  ExcitationSpec ms;
  ms.kind = ExcitationKind::kMultisine;
  ms.base_frequency_hz = 1.0 / (0.2 * diagnose.sweep_time);
  const int top = std::max(1, static_cast<int>(std::floor(diagnose.end_frequency_hz / ms.base_frequency_hz + 1e-9)));
  ms.lines.clear();
  for (int n = 1; n <= top; ++n) ms.lines.push_back(n);
  ms.line_set = MultisineLineSet::kOdd;
  ms.phase_rule = MultisinePhase::kRandom;
  ms.scale = MultisineScale::kRms;
  ms.amplitude = 1.0;
  ms.seed = diagnose.seed;
  return ms;
}

ExcitationGenerator::ExcitationGenerator(const ExcitationSpec& spec, double sample_rate_hz)
    : spec_(spec), sample_rate_hz_(sample_rate_hz) {
  ValidateExcitation(spec_, sample_rate_hz_);
  if (spec_.kind == ExcitationKind::kMultisine) lines_ = MultisineLines(spec_);
  if (spec_.kind == ExcitationKind::kDiagnose) lines_ = DiagnoseLines(spec_);
  if (spec_.kind == ExcitationKind::kPrbs) lfsr_mask_ = LfsrMask(spec_.register_bits);
  Reset();
}

void ExcitationGenerator::Reset() {
  index_ = 0;
  bit_index_ = -1;
  bit_value_ = 0.0;
  if (spec_.kind == ExcitationKind::kPrbs) lfsr_state_ = LfsrInitialState(spec_.register_bits);
  engine_.seed(spec_.seed);
}

double ExcitationGenerator::Next() {
  const int64_t k = index_++;
  if (spec_.kind != ExcitationKind::kPrbs && spec_.kind != ExcitationKind::kRandomBinary)
    return AnalyticValue(spec_, lines_, k, sample_rate_hz_);
  const int64_t bit = BitIndex(k, EffectiveClock(spec_, sample_rate_hz_), sample_rate_hz_);
  while (bit_index_ < bit) {
    int b;
    if (spec_.kind == ExcitationKind::kPrbs) {
      b = LfsrStep(lfsr_state_, lfsr_mask_, spec_.register_bits);
    } else {
      b = static_cast<int>(engine_() >> 63);
    }
    bit_value_ = b ? 1.0 : -1.0;
    ++bit_index_;
  }
  return spec_.offset + spec_.amplitude * bit_value_;
}

Eigen::VectorXd GenerateExcitation(const ExcitationSpec& spec, double sample_rate_hz,
                                   int64_t num_samples) {
  Require(num_samples >= 0, "negative number of samples");
  ValidateExcitation(spec, sample_rate_hz);
  Eigen::VectorXd u(num_samples);
  if (num_samples == 0) return u;
  if (spec.kind != ExcitationKind::kPrbs && spec.kind != ExcitationKind::kRandomBinary) {
    std::vector<MultisineLine> lines;
    if (spec.kind == ExcitationKind::kMultisine) lines = MultisineLines(spec);
    if (spec.kind == ExcitationKind::kDiagnose) lines = DiagnoseLines(spec);
    for (int64_t k = 0; k < num_samples; ++k) u[k] = AnalyticValue(spec, lines, k, sample_rate_hz);
    return u;
  }
  // Binary signals: the bit sequence first (one period of the m-sequence, or the random bits
  // the record needs), then each sample looks up its bit.
  const double clock = EffectiveClock(spec, sample_rate_hz);
  const int64_t bits_needed = BitIndex(num_samples - 1, clock, sample_rate_hz) + 1;
  std::vector<double> sequence;
  if (spec.kind == ExcitationKind::kPrbs) {
    const int64_t period = (int64_t{1} << spec.register_bits) - 1;
    const int64_t length = std::min(period, bits_needed);
    sequence.resize(length);
    uint32_t state = LfsrInitialState(spec.register_bits);
    const uint32_t mask = LfsrMask(spec.register_bits);
    for (int64_t i = 0; i < length; ++i)
      sequence[i] = LfsrStep(state, mask, spec.register_bits) ? 1.0 : -1.0;
  } else {
    std::mt19937_64 engine(spec.seed);
    sequence.resize(bits_needed);
    for (int64_t i = 0; i < bits_needed; ++i) sequence[i] = (engine() >> 63) ? 1.0 : -1.0;
  }
  const int64_t length = static_cast<int64_t>(sequence.size());
  for (int64_t k = 0; k < num_samples; ++k)
    u[k] = spec.offset +
           spec.amplitude * sequence[BitIndex(k, clock, sample_rate_hz) % length];
  return u;
}

}  // namespace idrig
