#include "core/numeric/gap/gap_bench.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>

#include "core/numeric/gap/gap_internal.h"
#include "core/numeric/model/lti_model.h"
#include "core/numeric/signal/excitation.h"
#include "core/numeric/validation.h"

namespace idrig {
namespace {

double Uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * std::uniform_real_distribution<double>(0.0, 1.0)(rng);
}

double Gaussian(std::mt19937_64& rng) { return std::normal_distribution<double>(0.0, 1.0)(rng); }

// Random stable plant: first order, a mass–spring–damper, or the two in series. Position-like
// output (second order at least) for friction and cubic stiffness.
TransferFunction RandomPlant(EffectKind truth, std::mt19937_64& rng, double* bandwidth,
                             const GapCaseOptions& options) {
  if (options.integrating) {
    // Position from force (a damped mass, K/(s(s + c))) or a level from a flow through a pump
    // lag: both K/(s(Ts + 1)) with one integrator; "bandwidth" is the lag's corner.
    const double corner = Uniform(rng, 2.0, 10.0);
    const double gain = Uniform(rng, 0.5, 2.0);
    TransferFunction tf;
    tf.num = Eigen::VectorXd::Constant(1, gain * corner);
    tf.den = Eigen::Vector3d(1.0, corner, 0.0);
    *bandwidth = corner;
    return tf;
  }
  const double gain = Uniform(rng, 0.5, 2.0);
  const double omega = Uniform(rng, 2.0, 15.0);
  const double zeta = Uniform(rng, options.zeta_min, options.zeta_max);
  if (options.plants == "zeros") {
    // ω²·p·(1 ± s/z) / ((s² + 2ζωs + ω²)(s + p)): relative degree 2, so that friction and a
    // cubic spring still act on a position-like output. A third of them non-minimum phase.
    const double pole = Uniform(rng, 1.5, 4.0) * omega;
    const double zero = Uniform(rng, 0.5, 3.0) * omega;
    const double lead = Uniform(rng, 0, 1) < 1.0 / 3 ? -1.0 : 1.0;
    TransferFunction tf;
    tf.num = Eigen::Vector2d(lead / zero, 1.0) * (gain * omega * omega * pole);
    tf.den = Eigen::Vector4d(1.0, 2 * zeta * omega + pole, omega * omega + 2 * zeta * omega * pole,
                             omega * omega * pole);
    *bandwidth = omega;
    return tf;
  }
  if (options.plants == "two-mass") {
    // Force on mass 1, position of mass 2: K·ω1²ω2² / ((s² + 2ζ1ω1s + ω1²)(s² + 2ζ2ω2s + ω2²)),
    // the second mode 2–5 times the first; half of them collocated-like, with an antiresonance
    // (s² + 2ζzωzs + ωz²)·ω2²/ωz² between the two modes (relative degree 2).
    const double omega2 = Uniform(rng, 2.0, 5.0) * omega;
    const double zeta2 = Uniform(rng, options.zeta_min, options.zeta_max);
    const bool antiresonance = Uniform(rng, 0, 1) < 0.5;
    const double omega_z = Uniform(rng, 1.3, 0.8 * omega2 / omega) * omega;
    const Eigen::Vector3d m1(1.0, 2 * zeta * omega, omega * omega);
    const Eigen::Vector3d m2(1.0, 2 * zeta2 * omega2, omega2 * omega2);
    TransferFunction tf;
    tf.den = PolynomialProduct(m1, m2);
    const double k = gain * omega * omega * omega2 * omega2;
    if (antiresonance)
      tf.num = Eigen::Vector3d(1.0, 2 * 0.5 * zeta * omega_z, omega_z * omega_z) * (k / (omega_z * omega_z));
    else
      tf.num = Eigen::VectorXd::Constant(1, k);
    *bandwidth = omega;
    return tf;
  }
  int shape = static_cast<int>(Uniform(rng, 0, 3));
  if (IsFeedbackEffect(truth) && shape == 0) shape = 1;
  TransferFunction tf;
  if (shape == 0) {
    tf.num = Eigen::VectorXd::Constant(1, gain * omega / 3);
    tf.den = Eigen::Vector2d(1.0, omega / 3);
    *bandwidth = omega / 3;
  } else {
    tf.num = Eigen::VectorXd::Constant(1, gain * omega * omega);
    tf.den = Eigen::Vector3d(1.0, 2 * zeta * omega, omega * omega);
    *bandwidth = omega;
    if (shape == 2) {
      const double pole = Uniform(rng, 1.5, 4.0) * omega;
      tf.num *= pole;
      tf.den = Eigen::Vector4d(1.0, 2 * zeta * omega + pole, omega * omega + 2 * zeta * omega * pole,
                               omega * omega * pole);
    }
  }
  return tf;
}

// One period of `samples` of a random-phase odd multisine: every odd line up to f_band (three
// at least), RMS `rms`.
Eigen::VectorXd OddMultisine(double fs, int samples, double f_band, double rms, uint64_t seed) {
  ExcitationSpec spec;
  spec.kind = ExcitationKind::kMultisine;
  spec.base_frequency_hz = fs / samples;
  const int top = std::max(3, static_cast<int>(f_band / spec.base_frequency_hz));
  spec.lines.clear();
  for (int k = 1; k <= top; ++k) spec.lines.push_back(k);
  spec.line_set = MultisineLineSet::kOdd;
  spec.phase_rule = MultisinePhase::kRandom;
  spec.scale = MultisineScale::kRms;
  spec.amplitude = rms;
  spec.seed = seed;
  return GenerateExcitation(spec, fs, samples);
}

Eigen::VectorXd Excitation(const std::string& kind, double bandwidth, double amplitude,
                           const GapCaseOptions& options, uint64_t seed) {
  const double fs = 1.0 / options.sample_time;
  const int n = options.samples;
  const double f_band = std::min(0.4 * fs, 3.0 * bandwidth / (2 * M_PI));  // excite ~3× bandwidth
  if (kind == "levels") {
    // Three segments of a random-phase odd multisine (RMS 0.25, 0.55, 1 × amplitude) with a step
    // up and back between them.
    Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
    const int segment = n / 3;
    const double levels[3] = {0.25, 0.55, 1.0};
    const int step = std::max(10, segment / 6);
    for (int s = 0; s < 3; ++s) {
      const Eigen::VectorXd part = OddMultisine(fs, segment - step, f_band, levels[s] * amplitude / 2, seed * 7 + s);
      u.segment(s * segment, step).setConstant((s % 2 ? -0.6 : 0.6) * amplitude * levels[s]);
      u.segment(s * segment + step, segment - step) = part;
    }
    return u;
  }
  if (kind == "multisine") {
    // One random-phase odd multisine (every odd line up to f_band, RMS amplitude/2) repeated over
    // five periods: the periodic test of a frequency-domain lab. The noise floor comes from the
    // spread across periods and the detection lines are available.
    const int periods = 5;
    const int period = n / periods;
    const Eigen::VectorXd one = OddMultisine(fs, period, f_band, amplitude / 2, seed);
    Eigen::VectorXd u(n);
    for (int k = 0; k < n; ++k) u(k) = one(k % period);
    return u;
  }
  if (kind == "noise") {
    // Band-limited Gaussian noise: white noise through two first-order low-passes at f_band,
    // scaled so that the peak is about `amplitude` (standard deviation amplitude/3). Not periodic:
    // the noise floor comes from the ARX predictor, no detection lines.
    std::mt19937_64 g(seed);
    const double a = 1 - std::exp(-2 * M_PI * f_band * options.sample_time);
    Eigen::VectorXd u(n);
    double s1 = 0, s2 = 0;
    for (long k = -200; k < n; ++k) {  // run in so the record does not start from zero
      s1 += a * (Gaussian(g) - s1);
      s2 += a * (s1 - s2);
      if (k >= 0) u(k) = s2;
    }
    const double sd = std::sqrt((u.array() - u.mean()).square().mean());
    return (u.array() - u.mean()) * (amplitude / 3 / std::max(sd, 1e-12));
  }
  if (kind == "steps") {
    // A random staircase: levels uniform in ±amplitude held for 0.5–3 of the plant's slow time
    // constants each (what a rig engineer's manual test looks like).
    std::mt19937_64 g(seed);
    Eigen::VectorXd u(n);
    long k = 0;
    while (k < n) {
      const double level = Uniform(g, -amplitude, amplitude);
      const long hold = std::max<long>(5, std::lround(Uniform(g, 0.5, 3.0) / bandwidth / options.sample_time));
      for (long j = 0; j < hold && k < n; ++j, ++k) u(k) = level;
    }
    return u;
  }
  if (kind == "chirp") {
    // One logarithmic sweep over the record from f_band/30 to f_band at a constant amplitude,
    // its start and direction drawn from the seed.
    std::mt19937_64 g(seed);
    const double f0 = f_band / 30, f1 = f_band, T = n * options.sample_time;
    const double phase0 = Uniform(g, 0, 2 * M_PI);
    const bool up = Uniform(g, 0, 1) < 0.5;
    Eigen::VectorXd u(n);
    const double r = std::log(f1 / f0);
    for (long k = 0; k < n; ++k) {
      const double t = (up ? k : n - 1 - k) * options.sample_time;
      u(k) = amplitude * std::sin(phase0 + 2 * M_PI * f0 * T / r * (std::exp(r * t / T) - 1));
    }
    return u;
  }
  ExcitationSpec spec;
  spec.kind = kind == "prbs" ? ExcitationKind::kPrbs : ExcitationKind::kRandomBinary;
  spec.amplitude = amplitude;
  spec.register_bits = 10;
  spec.clock_hz = fs / std::max(1, static_cast<int>(std::round(fs / (2.5 * f_band))));
  spec.seed = seed;
  Eigen::VectorXd u = GenerateExcitation(spec, fs, n);
  if (kind == "prbs") {  // start somewhere else in the sequence for each realisation
    const long shift = static_cast<long>(seed % 997) * 3;
    Eigen::VectorXd longer = GenerateExcitation(spec, fs, n + shift);
    u = longer.tail(n);
  }
  return u;
}

// What an effect's parameters are drawn against: the physical input and the linear output.
struct SignalStats {
  double u_max = 1, y_max = 1, y_hi = 1, y_lo = -1, y_mean = 0, bandwidth = 1, ts = 0.01;
};

// Random parameters of `kind`, scaled to the signals (parameter_mismatch moves `real`).
Effect DrawEffect(EffectKind kind, std::mt19937_64& rng, const SignalStats& st,
                  TransferFunction& real) {
  const double sign = Uniform(rng, 0, 1) < 0.5 ? -1.0 : 1.0;
  Effect e;
  e.kind = kind;
  const double slow = 1.0 / st.bandwidth;
  const double u_max = st.u_max, y_max = st.y_max;
  switch (kind) {
    case EffectKind::kParameterMismatch: {
      // Every coefficient 10–30 % off, drawn again while the rig would be unstable (a third-order
      // plant's Hurwitz margin a1·a2 − a3 can go negative, most easily when lightly damped): a
      // rig that diverges is not a model mismatch. An integrator (a zero last coefficient) stays.
      const TransferFunction sim = real;
      auto unstable = [](const TransferFunction& tf) {
        const Eigen::VectorXcd poles = Poles(tf);
        for (long i = 0; i < poles.size(); ++i)
          if (poles(i).real() > 1e-9 * std::max(1.0, std::abs(poles(i)))) return true;
        return false;
      };
      do {
        real = sim;
        for (int i = 1; i < real.den.size(); ++i)
          real.den(i) *= 1 + (Uniform(rng, 0, 1) < 0.5 ? -1 : 1) * Uniform(rng, 0.1, 0.3);
        real.num *= 1 + (Uniform(rng, 0, 1) < 0.5 ? -1 : 1) * Uniform(rng, 0.1, 0.3);
      } while (unstable(real));
      e.kind = EffectKind::kNone;
      break;
    }
    case EffectKind::kTimeDelay:
      e.params = {std::max(2 * st.ts, Uniform(rng, 0.1, 0.4) * slow)};
      break;
    case EffectKind::kActuatorLag: e.params = {Uniform(rng, 0.15, 0.6) * slow}; break;
    case EffectKind::kUnmodelledResonance:
      e.params = {std::min(Uniform(rng, 3.0, 8.0) * st.bandwidth, 0.3 * M_PI / st.ts),
                  Uniform(rng, 0.05, 0.2)};
      break;
    case EffectKind::kInputSaturation:
      e.params = {-Uniform(rng, 0.4, 0.8) * u_max, Uniform(rng, 0.4, 0.8) * u_max};
      break;
    case EffectKind::kDeadZone: e.params = {Uniform(rng, 0.1, 0.3) * u_max}; break;
    case EffectKind::kBacklash: e.params = {Uniform(rng, 0.05, 0.2) * u_max}; break;
    case EffectKind::kCoulombFriction: e.params = {Uniform(rng, 0.1, 0.3) * u_max}; break;
    case EffectKind::kCubicStiffness:
      e.params = {Uniform(rng, 0.2, 0.5) * u_max / std::pow(y_max, 3)};
      break;
    case EffectKind::kOutputSaturation:
      e.params = {st.y_mean - Uniform(rng, 0.5, 0.8) * (st.y_mean - st.y_lo),
                  st.y_mean + Uniform(rng, 0.5, 0.8) * (st.y_hi - st.y_mean)};
      break;
    case EffectKind::kSensorNonlinearity:
      if (Uniform(rng, 0, 1) < 0.5) {
        e.params = {1.0, 0.0, 0.0, 1.0};
      } else {
        e.params = {1.0, Uniform(rng, -0.2, 0.2) / y_max,
                    sign * Uniform(rng, 0.1, 0.3) / (y_max * y_max), 0.0};
      }
      break;
    case EffectKind::kOutputQuantization:
      e.params = {Uniform(rng, 0.03, 0.1) * (st.y_hi - st.y_lo)};
      break;
    default:
      break;
  }
  return e;
}

int Stage(EffectKind kind) {  // order in which effects act on the signal path
  switch (kind) {
    case EffectKind::kInputSaturation: return 0;
    case EffectKind::kDeadZone: return 1;
    case EffectKind::kBacklash: return 2;
    case EffectKind::kOutputSaturation: return 5;
    case EffectKind::kSensorNonlinearity: return 6;
    case EffectKind::kOutputQuantization: return 7;
    default: return 3;  // linear (folded into the plant) and feedback
  }
}

// What the diagnosis's own fit absorbs of a record's output (GapCase::visibility_refit), as
// columns over the record: with `plant_refit`, the output's sensitivity to each coefficient of the
// linear part (the numerator's, and the denominator's but its leading 1 and its zeros, so that an
// integrator stays one), by a forward difference; the sensitivities to the parameters of the
// `others` effects and to an actuator offset; and with `segment` > 0 (multiple shooting) an
// offset and the free response of every state per segment. `record(g, effects, u)` draws the
// record, noise-free, from the rig with linear part g, those effects and input u.
Eigen::MatrixXd RefitColumns(
    const TransferFunction& plant, bool plant_refit, const std::vector<Effect>& others, const Eigen::VectorXd& u,
    long segment, double ts,
    const std::function<Eigen::VectorXd(const TransferFunction&, const std::vector<Effect>&, const Eigen::VectorXd&)>&
        record) {
  const Eigen::VectorXd base = record(plant, others, u);
  std::vector<Eigen::VectorXd> cols;
  const auto difference = [&](const TransferFunction& g, const std::vector<Effect>& effects,
                              const Eigen::VectorXd& input, double h) {
    cols.push_back((record(g, effects, input) - base) / h);
  };
  const auto step = [](double value) { return 1e-6 * std::max(std::abs(value), 1e-3); };
  if (plant_refit) {
    for (long i = 0; i < plant.num.size(); ++i) {
      TransferFunction g = plant;
      const double h = step(g.num[i]);
      g.num[i] += h;
      difference(g, others, u, h);
    }
    for (long i = 1; i < plant.den.size(); ++i) {
      if (plant.den[i] == 0) continue;
      TransferFunction g = plant;
      const double h = step(g.den[i]);
      g.den[i] += h;
      difference(g, others, u, h);
    }
  }
  // The other effect's parameters, refitted beside this one (a flag, such as the |y| sensor's,
  // gives a zero column).
  for (size_t j = 0; j < others.size(); ++j)
    for (size_t i = 0; i < others[j].params.size(); ++i) {
      std::vector<Effect> moved = others;
      const double h = step(moved[j].params[i]);
      moved[j].params[i] += h;
      difference(plant, moved, u, h);
    }
  const double du = step(u.cwiseAbs().maxCoeff());
  difference(plant, others, Eigen::VectorXd(u.array() + du), du);
  if (segment > 0) {
    GapRecord shape;
    shape.y = Eigen::VectorXd::Zero(u.size());
    const auto segments = gap_detail::Segments(shape, segment);
    long longest = 0;
    for (const auto& s : segments) longest = std::max(longest, s.second);
    const Eigen::MatrixXd free = gap_detail::FreeResponse(gap_detail::SampledUndelayed(plant, ts), longest);
    for (const auto& [start, length] : segments) {
      Eigen::VectorXd level = Eigen::VectorXd::Zero(u.size());
      level.segment(start, length).setOnes();
      cols.push_back(level);
      for (long j = 0; j < free.cols(); ++j) {
        Eigen::VectorXd state = Eigen::VectorXd::Zero(u.size());
        const long rows = std::min(length, static_cast<long>(free.rows()));
        state.segment(start, rows) = free.col(j).head(rows);
        cols.push_back(state);
      }
    }
  }
  Eigen::MatrixXd out(u.size(), static_cast<long>(cols.size()));
  for (size_t j = 0; j < cols.size(); ++j) out.col(static_cast<long>(j)) = cols[j];
  return out;
}

}  // namespace

const std::vector<std::pair<EffectKind, EffectKind>>& CoOccurringEffectPairs() {
  static const std::vector<std::pair<EffectKind, EffectKind>> pairs = {
      {EffectKind::kCoulombFriction, EffectKind::kInputSaturation},
      {EffectKind::kDeadZone, EffectKind::kCubicStiffness},
      {EffectKind::kBacklash, EffectKind::kOutputQuantization},
      {EffectKind::kTimeDelay, EffectKind::kSensorNonlinearity},
      {EffectKind::kActuatorLag, EffectKind::kInputSaturation},
      {EffectKind::kCoulombFriction, EffectKind::kBacklash},
      {EffectKind::kDeadZone, EffectKind::kActuatorLag},
  };
  return pairs;
}

Eigen::VectorXd SimulateRig(const TransferFunction& plant, const Effect& effect,
                            const Eigen::VectorXd& u, double sample_time, double noise_sigma,
                            std::mt19937_64& rng) {
  EffectSimulationOptions fine;
  fine.substeps = 16;
  if (effect.kind == EffectKind::kOutputQuantization) {
    Eigen::VectorXd y = SimulateWithEffect(plant, Effect{}, u, sample_time, fine);
    for (long k = 0; k < y.size(); ++k) {
      const double noisy = y(k) + noise_sigma * Gaussian(rng);
      y(k) = effect.params[0] * std::round(noisy / effect.params[0]);
    }
    return y;
  }
  Eigen::VectorXd y = SimulateWithEffect(plant, effect, u, sample_time, fine);
  for (long k = 0; k < y.size(); ++k) y(k) += noise_sigma * Gaussian(rng);
  return y;
}

Eigen::VectorXd SimulateRig(const TransferFunction& plant, const std::vector<Effect>& effects_in,
                            const Eigen::VectorXd& u, double sample_time, double noise_sigma,
                            std::mt19937_64& rng, double input_offset, double output_offset,
                            double noise_pole, const Eigen::VectorXd& sensor_drift,
                            const Eigen::VectorXd& load) {
  if (effects_in.size() <= 1 && input_offset == 0 && output_offset == 0 && noise_pole == 0 &&
      sensor_drift.size() == 0 && load.size() == 0)
    return SimulateRig(plant, effects_in.empty() ? Effect{} : effects_in.front(), u, sample_time,
                       noise_sigma, rng);
  std::vector<Effect> effects = effects_in;
  std::stable_sort(effects.begin(), effects.end(),
                   [](const Effect& a, const Effect& b) { return Stage(a.kind) < Stage(b.kind); });
  Eigen::VectorXd w = u.array() + input_offset;
  TransferFunction g = plant;
  Effect feedback;
  const Effect* quantizer = nullptr;
  std::vector<const Effect*> output_maps;
  for (const Effect& e : effects) {
    ValidateEffect(e);
    switch (e.kind) {
      case EffectKind::kInputSaturation:
        w = w.cwiseMax(e.params[0]).cwiseMin(e.params[1]);
        break;
      case EffectKind::kDeadZone:
        for (long k = 0; k < w.size(); ++k) w(k) = DeadZone(w(k), e.params[0]);
        break;
      case EffectKind::kBacklash: w = Backlash(w, e.params[0]); break;
      case EffectKind::kCoulombFriction:
      case EffectKind::kCubicStiffness:
        if (feedback.kind != EffectKind::kNone)
          throw std::invalid_argument("rig simulation: at most one feedback effect (friction or "
                                      "cubic stiffness) at a time");
        feedback = e;
        break;
      case EffectKind::kOutputSaturation:
      case EffectKind::kSensorNonlinearity: output_maps.push_back(&e); break;
      case EffectKind::kOutputQuantization: quantizer = &e; break;
      case EffectKind::kNone: break;
      default: g = ApplyLinearEffect(g, e); break;
    }
  }
  if (load.size() != 0) {
    if (load.size() != w.size()) throw std::invalid_argument("rig simulation: the load disturbance and the input differ in length");
    w += load;
  }
  EffectSimulationOptions fine;
  fine.substeps = 16;
  Eigen::VectorXd y = SimulateWithEffect(g, feedback, w, sample_time, fine);
  for (const Effect* e : output_maps)
    for (long k = 0; k < y.size(); ++k) y(k) = OutputMap(*e, y(k));
  const double innovation = std::sqrt(1 - noise_pole * noise_pole);
  double e = 0;
  for (long k = 0; k < y.size(); ++k) {
    e = k == 0 ? Gaussian(rng) : noise_pole * e + innovation * Gaussian(rng);
    y(k) += noise_sigma * e;
    if (k < sensor_drift.size()) y(k) += sensor_drift(k);
    if (quantizer) y(k) = quantizer->params[0] * std::round(y(k) / quantizer->params[0]);
    y(k) += output_offset;
  }
  return y;
}

void AddGlitches(Eigen::VectorXd& y, int count, std::mt19937_64& rng) {
  if (count <= 0 || y.size() < 40) return;
  const double lo = y.minCoeff(), hi = y.maxCoeff(), span = std::max(hi - lo, 1e-12);
  for (int g = 0; g < count; ++g) {
    const long length = 1 + static_cast<long>(Uniform(rng, 0, 3));  // 1–3 samples
    const long at = static_cast<long>(Uniform(rng, 10, static_cast<double>(y.size() - 10 - length)));
    const double kind = Uniform(rng, 0, 1);
    // A spike 2–20 output spans off (either sign), a dropout to zero (a sensor offset makes it a
    // jump), or a reading stuck at a rail one span beyond the range.
    const double value = kind < 0.4   ? y(at) + (Uniform(rng, 0, 1) < 0.5 ? -1 : 1) * Uniform(rng, 2, 20) * span
                         : kind < 0.7 ? 0.0
                                      : hi + span;
    for (long k = at; k < at + length; ++k) y(k) = value;
  }
}

GapCase MakeGapCase(EffectKind truth, std::mt19937_64& rng, const GapCaseOptions& options) {
  return MakeGapCase(std::vector<EffectKind>{truth}, rng, options);
}

void ValidateGapCaseOptions(const GapCaseOptions& o) {
  if (!(o.zeta_min > 0 && o.zeta_min <= o.zeta_max))
    throw std::invalid_argument("gap case: damping range LO,HI = " + std::to_string(o.zeta_min) + "," +
                                std::to_string(o.zeta_max) + " needs 0 < LO <= HI");
  if (!(o.noise_pole >= 0 && o.noise_pole < 1))
    throw std::invalid_argument("gap case: noise pole " + std::to_string(o.noise_pole) + " is not in [0, 1)");
  if (!o.plants.empty() && o.plants != "zeros" && o.plants != "two-mass")
    throw std::invalid_argument("gap case: plant family '" + o.plants + "' is not one of zeros, two-mass");
  if (o.glitches < 0) throw std::invalid_argument("gap case: a negative number of glitches");
  if (!(o.process_noise >= 0 && o.process_noise < 1))
    throw std::invalid_argument("gap case: process-noise share " + std::to_string(o.process_noise) +
                                " is not in [0, 1)");
  if (!o.plants.empty() && o.integrating)
    throw std::invalid_argument("gap case: a plant family and --integrating are two plant choices; give one");
}

GapCase MakeGapCase(const std::vector<EffectKind>& truths, std::mt19937_64& rng,
                    const GapCaseOptions& options) {
  ValidateGapCaseOptions(options);
  if (truths.empty() || truths.size() > 2)
    throw std::invalid_argument("gap case: give one or two effects, not " +
                                std::to_string(truths.size()));
  if (truths.size() == 2) {
    if (truths[0] == truths[1] || truths[0] == EffectKind::kNone || truths[1] == EffectKind::kNone ||
        truths[0] == EffectKind::kParameterMismatch || truths[1] == EffectKind::kParameterMismatch)
      throw std::invalid_argument(std::string("gap case: the pair ") + EffectName(truths[0]) + " + " +
                                  EffectName(truths[1]) + " is not two distinct effects of the library");
    if (IsFeedbackEffect(truths[0]) && IsFeedbackEffect(truths[1]))
      throw std::invalid_argument("gap case: at most one feedback effect in a pair");
  }
  GapCase c;
  c.truth = truths.front();
  c.truths = truths;
  const EffectKind shape_of = truths.size() == 2 && IsFeedbackEffect(truths[1]) ? truths[1] : truths[0];
  double bandwidth = 1;
  c.sim = RandomPlant(shape_of, rng, &bandwidth, options);
  c.real = c.sim;
  const char* kinds[3] = {"levels", "prbs", "rbs"};
  c.excitation = kinds[static_cast<int>(Uniform(rng, 0, 3)) % 3];
  if (!options.excitation.empty()) {
    const auto& known = BenchExcitations();
    if (std::find(known.begin(), known.end(), options.excitation) == known.end()) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      throw std::invalid_argument("gap case: excitation '" + options.excitation + "' is not one of " + list);
    }
    c.excitation = options.excitation;
  }
  const double amplitude = Uniform(rng, 0.5, 2.0);
  const uint64_t seed = rng();
  const Eigen::VectorXd u_est = Excitation(c.excitation, bandwidth, amplitude, options, seed);
  const Eigen::VectorXd u_val = Excitation(c.excitation, bandwidth, amplitude, options, seed + 1);
  if (options.offsets) {
    const double side = Uniform(rng, 0, 1) < 0.5 ? -1.0 : 1.0;
    c.input_offset = side * Uniform(rng, 0.0, 0.3) * u_est.cwiseAbs().maxCoeff();
  }
  // Effects are sized against the physical input (command + actuator offset).
  const Eigen::VectorXd u_phys = u_est.array() + c.input_offset;
  const Eigen::VectorXd y_lin = SimulateWithEffect(c.sim, Effect{}, u_phys, options.sample_time);
  SignalStats st;
  st.u_max = u_phys.cwiseAbs().maxCoeff();
  st.y_max = y_lin.cwiseAbs().maxCoeff();
  st.y_hi = y_lin.maxCoeff();
  st.y_lo = y_lin.minCoeff();
  st.y_mean = y_lin.mean();
  st.bandwidth = bandwidth;
  st.ts = options.sample_time;
  for (EffectKind kind : truths) c.effects.push_back(DrawEffect(kind, rng, st, c.real));
  c.effect = c.effects.front();
  if (options.offsets) {
    const double side = Uniform(rng, 0, 1) < 0.5 ? -1.0 : 1.0;
    c.output_offset = side * Uniform(rng, 0.1, 1.0) * (st.y_hi - st.y_lo);
  }
  // Warm-up at zero command (the rig settles at its operating point), dropped from the records.
  long warm = 0;
  if (options.offsets) {
    double slow = 1.0 / bandwidth;
    for (const Effect& e : c.effects)
      if (e.kind == EffectKind::kActuatorLag) slow += e.params[0];
    warm = std::clamp<long>(static_cast<long>(10 * slow / options.sample_time), 100, 3000);
  }
  // Process noise (GapCaseOptions::process_noise): the output RMS of the rig's linear part for a
  // unit white load over a record (after the warm-up, mean removed) scales the load.
  const double share = options.process_noise;
  double load_gain = 0;
  if (share > 0) {
    std::mt19937_64 unit(1);
    Eigen::VectorXd d(warm + options.samples);
    for (long k = 0; k < d.size(); ++k) d(k) = Gaussian(unit);
    const Eigen::VectorXd yd = SimulateWithEffect(c.real, Effect{}, d, options.sample_time);
    const Eigen::VectorXd tail = yd.tail(options.samples);
    const double rms = std::sqrt((tail.array() - tail.mean()).square().mean());
    if (rms > 0) load_gain = std::sqrt(share) / rms;
  }
  // drift: the sensor's rise over the record, in noise sigmas (GapCaseOptions::drift).
  // The rig with `effects` on `plant` (the case's own unless told otherwise: GapCase::visibility).
  auto record_of = [&](const TransferFunction& plant, const std::vector<Effect>& effects, const Eigen::VectorXd& u,
                       double sigma, std::mt19937_64& g, double drift) {
    Eigen::VectorXd padded = Eigen::VectorXd::Zero(warm + u.size());
    padded.tail(u.size()) = u;
    Eigen::VectorXd ramp;
    if (drift != 0) {
      ramp = Eigen::VectorXd::Zero(padded.size());
      for (long k = 0; k < u.size(); ++k) ramp(warm + k) = drift * sigma * k / std::max<long>(1, u.size() - 1);
    }
    Eigen::VectorXd load;
    if (share > 0 && sigma > 0) {
      load.resize(padded.size());
      for (long k = 0; k < load.size(); ++k) load(k) = load_gain * sigma * Gaussian(g);
    }
    const double output_sigma = sigma * std::sqrt(1 - share);
    const Eigen::VectorXd y = SimulateRig(plant, effects, padded, options.sample_time, output_sigma, g,
                                          c.input_offset, c.output_offset, options.noise_pole, ramp, load);
    return Eigen::VectorXd(y.tail(u.size()));
  };
  auto record = [&](const Eigen::VectorXd& u, double sigma, std::mt19937_64& g, double drift = 0) {
    return record_of(c.real, c.effects, u, sigma, g, drift);
  };
  // Noise from the SNR of the rig's own output on the estimation input.
  std::mt19937_64 quiet(0);
  const Eigen::VectorXd y_clean = record(u_est, 0.0, quiet);
  const double rms = std::sqrt((y_clean.array() - y_clean.mean()).square().mean());
  c.noise_sigma = rms * std::pow(10.0, -options.snr_db / 20);
  c.estimation.u = u_est;
  const std::mt19937_64 estimation_draws = rng;  // to replay the same load and noise without an effect
  c.estimation.y = record(u_est, c.noise_sigma, rng, options.drift);
  c.estimation.sample_time = options.sample_time;
  c.validation.u = u_val;
  const std::mt19937_64 validation_draws = rng;  // to replay the same load and noise without an effect
  c.validation.y = record(u_val, c.noise_sigma, rng, -options.drift);
  c.validation.sample_time = options.sample_time;
  const std::vector<Eigen::VectorXd> unglitched = {c.estimation.y, c.validation.y};
  // Sensor or acquisition glitches, drawn last so that the rest of the case does not move.
  for (GapRecord* r : {&c.estimation, &c.validation}) AddGlitches(r->y, options.glitches, rng);
  // GapCase::visibility: each record drawn again with the same load, noise and drift but
  // without each withheld effect in turn; the difference, less its least-squares fit on
  // [1, y without] ([1] for parameter_mismatch), over σ²; the larger of the two records.
  // GapCase::visibility_refit: the same difference less its fit on those columns and on what the
  // diagnosis's refit absorbs (RefitColumns).
  const long segment = ShootingSegment(c.sim, options.samples, options.sample_time);
  for (size_t i = 0; i < c.truths.size(); ++i) {
    const EffectKind k = c.truths[i];
    if (k == EffectKind::kNone || !(c.noise_sigma > 0)) {
      c.visibility.push_back(std::numeric_limits<double>::infinity());
      c.visibility_refit.push_back(std::numeric_limits<double>::infinity());
      continue;
    }
    std::vector<Effect> others;
    for (size_t j = 0; j < c.effects.size(); ++j)
      if (j != i) others.push_back(c.effects[j]);
    const bool mismatch = k == EffectKind::kParameterMismatch;
    const TransferFunction& plant = mismatch ? c.sim : c.real;
    // The refit's columns from noise-free records (a quantiser's rounding left out: its steps are
    // not a sensitivity).
    std::vector<Effect> smooth;
    double q = 0;  // the other effect's quantiser step, if it is one
    for (const Effect& e : others)
      if (e.kind != EffectKind::kOutputQuantization) smooth.push_back(e);
      else q = e.params[0];
    const auto noise_free = [&](const TransferFunction& g, const std::vector<Effect>& effects,
                                const Eigen::VectorXd& input) {
      std::mt19937_64 none(0);
      return record_of(g, effects, input, 0.0, none, 0.0);
    };
    // Beside a quantiser, Δy of the same noise is the rounding flips the effect causes, each a
    // whole step, which a test that did not know the noise cannot place: the noise dithers the
    // quantiser, which then passes the effect's own Δy (from the records without the quantiser,
    // `with` and `smooth`) in noise of variance σ² + q²/12.
    std::vector<Effect> with = smooth;
    with.push_back(c.effects[i]);
    const double variance = c.noise_sigma * c.noise_sigma + q * q / 12;
    double most = 0, most_refit = 0;
    for (int r = 0; r < 2; ++r) {
      std::mt19937_64 replay = r == 0 ? estimation_draws : validation_draws;
      const Eigen::VectorXd& u = r == 0 ? u_est : u_val;
      const Eigen::VectorXd without =
          record_of(plant, others, u, c.noise_sigma, replay, r == 0 ? options.drift : -options.drift);
      Eigen::MatrixXd basis(without.size(), mismatch ? 1 : 2);
      basis.col(0).setOnes();
      if (!mismatch) basis.col(1) = without;
      const Eigen::VectorXd d = unglitched[r] - without;
      const Eigen::VectorXd left = d - basis * basis.colPivHouseholderQr().solve(d);
      most = std::max(most, left.squaredNorm() / (c.noise_sigma * c.noise_sigma));
      const Eigen::VectorXd d_refit =
          q > 0 ? Eigen::VectorXd(noise_free(c.real, with, u) - noise_free(plant, smooth, u)) : d;
      const Eigen::MatrixXd taken = RefitColumns(plant, !mismatch, smooth, u, segment, options.sample_time, noise_free);
      Eigen::MatrixXd refit(basis.rows(), basis.cols() + taken.cols());
      refit << basis, taken;
      const Eigen::VectorXd left_refit = d_refit - refit * refit.colPivHouseholderQr().solve(d_refit);
      most_refit = std::max(most_refit, left_refit.squaredNorm() / variance);
    }
    c.visibility.push_back(most);
    c.visibility_refit.push_back(most_refit);
  }
  return c;
}

double BenchVisibilityThreshold() { return ChiSquareQuantile(1 - 0.01 / (AllEffects().size() - 2), 1); }

const std::vector<std::string>& BenchExcitations() {
  static const std::vector<std::string> kinds = {"levels", "prbs", "rbs", "noise", "steps", "chirp", "multisine"};
  return kinds;
}

const std::vector<std::pair<EffectKind, EffectKind>>& AnyEffectPairs() {
  static const std::vector<std::pair<EffectKind, EffectKind>> pairs = [] {
    std::vector<EffectKind> effects;
    for (EffectKind k : AllEffects())
      if (k != EffectKind::kNone && k != EffectKind::kParameterMismatch) effects.push_back(k);
    std::vector<std::pair<EffectKind, EffectKind>> all;
    for (size_t i = 0; i < effects.size(); ++i)
      for (size_t j = i + 1; j < effects.size(); ++j)
        if (!(IsFeedbackEffect(effects[i]) && IsFeedbackEffect(effects[j]))) all.emplace_back(effects[i], effects[j]);
    return all;
  }();
  return pairs;
}

std::vector<EffectKind> BenchCaseTruth(int index, double combo_share, bool any_pairs) {
  if (index < 0) throw std::invalid_argument("gap bench: negative case index");
  if (!(combo_share >= 0 && combo_share <= 1))
    throw std::invalid_argument("gap bench: the share of two-effect cases must be in [0, 1]");
  const auto combos_before = [&](long i) { return static_cast<long>(std::floor(i * combo_share + 1e-9)); };
  const long before = combos_before(index);
  if (combos_before(index + 1) > before) {
    const auto& pairs = any_pairs ? AnyEffectPairs() : CoOccurringEffectPairs();
    const auto& p = pairs[before % pairs.size()];
    return {p.first, p.second};
  }
  const auto& kinds = AllEffects();
  return {kinds[(index - before) % kinds.size()]};
}

namespace {
std::string Label(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : "+") + n;
  return s.empty() ? "none" : s;
}
}  // namespace

GapBenchScore ScoreGapBench(const std::vector<GapBenchOutcome>& outcomes) {
  GapBenchScore s;
  std::vector<double> shrinks;
  double seconds = 0;
  for (const auto& o : outcomes) {
    if (o.truth.empty()) throw std::invalid_argument("gap bench: an outcome without a truth");
    ++s.cases;
    seconds += o.seconds;
    std::vector<std::string> truth;
    for (EffectKind k : o.truth) truth.push_back(EffectName(k));
    const std::vector<std::string> named = o.effects.empty() ? std::vector<std::string>{o.verdict} : o.effects;
    ++s.confusion[Label(truth)][Label(named)];
    auto has = [&](const std::string& n) { return std::find(named.begin(), named.end(), n) != named.end(); };
    const bool two_valued = o.excitation == "prbs" || o.excitation == "rbs";
    bool decidable = true;
    for (EffectKind k : o.truth)
      if (two_valued && IsInputMap(k)) decidable = false;
    // A subset's counts: single cases and right top-1, pair cases and both named.
    auto count = [&](bool in, int& singles, int& right, int& pairs, int& both) {
      if (!in) return;
      if (truth.size() == 1) ++singles, right += o.verdict == truth[0];
      else ++pairs, both += has(truth[0]) && has(truth[1]);
    };
    count(decidable, s.decidable_single_cases, s.decidable_single_correct, s.decidable_combo_cases,
          s.decidable_combo_both);
    const auto visible = [](const std::vector<double>& v) {
      return std::all_of(v.begin(), v.end(), [](double x) { return x >= BenchVisibilityThreshold(); });
    };
    const bool detectable = decidable && visible(o.visibility);
    count(detectable, s.detectable_single_cases, s.detectable_single_correct, s.detectable_combo_cases,
          s.detectable_combo_both);
    count(detectable && visible(o.visibility_refit), s.refit_single_cases, s.refit_single_correct,
          s.refit_combo_cases, s.refit_combo_both);
    if (truth.size() == 1) {
      ++s.single_cases;
      ++s.by_excitation[o.excitation].second;
      if (o.verdict == truth[0]) {
        ++s.single_correct;
        ++s.by_excitation[o.excitation].first;
        if (named.size() > 1) ++s.single_extra;
        if (o.truth[0] != EffectKind::kNone) shrinks.push_back(o.shrink);
      }
      if (o.truth[0] == EffectKind::kNone) {
        ++s.none_cases;
        if (o.verdict != "none") ++s.false_alarms;
      }
    } else {
      ++s.combo_cases;
      const std::string pair = Label(truth);
      ++s.by_pair[pair].second;
      if (has(truth[0]) && has(truth[1])) {
        ++s.combo_both;
        ++s.by_pair[pair].first;
      }
      if (o.verdict == truth[0] || o.verdict == truth[1]) ++s.combo_either;
    }
  }
  std::sort(shrinks.begin(), shrinks.end());
  s.median_shrink_correct = shrinks.empty() ? std::numeric_limits<double>::quiet_NaN() : shrinks[shrinks.size() / 2];
  s.top1_accuracy = s.single_cases ? double(s.single_correct) / s.single_cases : 0.0;
  s.false_alarm_rate = s.none_cases ? double(s.false_alarms) / s.none_cases : 0.0;
  s.combo_both_rate = s.combo_cases ? double(s.combo_both) / s.combo_cases : 0.0;
  s.combo_top1_rate = s.combo_cases ? double(s.combo_either) / s.combo_cases : 0.0;
  s.mean_seconds = s.cases ? seconds / s.cases : 0.0;
  s.top1_decidable = s.decidable_single_cases ? double(s.decidable_single_correct) / s.decidable_single_cases : 0.0;
  s.combo_both_decidable = s.decidable_combo_cases ? double(s.decidable_combo_both) / s.decidable_combo_cases : 0.0;
  s.top1_detectable = s.detectable_single_cases ? double(s.detectable_single_correct) / s.detectable_single_cases : 0.0;
  s.combo_both_detectable = s.detectable_combo_cases ? double(s.detectable_combo_both) / s.detectable_combo_cases : 0.0;
  s.top1_refit = s.refit_single_cases ? double(s.refit_single_correct) / s.refit_single_cases : 0.0;
  s.combo_both_refit = s.refit_combo_cases ? double(s.refit_combo_both) / s.refit_combo_cases : 0.0;
  return s;
}

}  // namespace idrig
