#include "core/numeric/gap/gap_bench.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/numeric/signal/excitation.h"

namespace idrig {
namespace {

double Uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * std::uniform_real_distribution<double>(0.0, 1.0)(rng);
}

double Gaussian(std::mt19937_64& rng) { return std::normal_distribution<double>(0.0, 1.0)(rng); }

// Random stable plant: first order, a mass–spring–damper, or the two in series. Position-like
// output (second order at least) for friction and cubic stiffness.
TransferFunction RandomPlant(EffectKind truth, std::mt19937_64& rng, double* bandwidth) {
  const double gain = Uniform(rng, 0.5, 2.0);
  const double omega = Uniform(rng, 2.0, 15.0);
  const double zeta = Uniform(rng, 0.15, 0.8);
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
      ExcitationSpec spec;
      spec.kind = ExcitationKind::kMultisine;
      spec.base_frequency_hz = fs / (segment - step);
      const int top = std::max(3, static_cast<int>(f_band / spec.base_frequency_hz));
      spec.lines.clear();
      for (int k = 1; k <= top; ++k) spec.lines.push_back(k);
      spec.line_set = MultisineLineSet::kOdd;
      spec.phase_rule = MultisinePhase::kRandom;
      spec.scale = MultisineScale::kRms;
      spec.amplitude = levels[s] * amplitude / 2;
      spec.seed = seed * 7 + s;
      const Eigen::VectorXd part = GenerateExcitation(spec, fs, segment - step);
      u.segment(s * segment, step).setConstant((s % 2 ? -0.6 : 0.6) * amplitude * levels[s]);
      u.segment(s * segment + step, segment - step) = part;
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

}  // namespace

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

GapCase MakeGapCase(EffectKind truth, std::mt19937_64& rng, const GapCaseOptions& options) {
  GapCase c;
  c.truth = truth;
  double bandwidth = 1;
  c.sim = RandomPlant(truth, rng, &bandwidth);
  c.real = c.sim;
  const char* kinds[3] = {"levels", "prbs", "rbs"};
  c.excitation = kinds[static_cast<int>(Uniform(rng, 0, 3)) % 3];
  if (!options.excitation.empty()) {
    if (options.excitation != "levels" && options.excitation != "prbs" && options.excitation != "rbs")
      throw std::invalid_argument("gap case: excitation '" + options.excitation +
                                  "' is not one of levels, prbs, rbs");
    c.excitation = options.excitation;
  }
  const double amplitude = Uniform(rng, 0.5, 2.0);
  const uint64_t seed = rng();
  const Eigen::VectorXd u_est = Excitation(c.excitation, bandwidth, amplitude, options, seed);
  const Eigen::VectorXd u_val = Excitation(c.excitation, bandwidth, amplitude, options, seed + 1);
  const Eigen::VectorXd y_lin = SimulateWithEffect(c.sim, Effect{}, u_est, options.sample_time);
  const double u_max = u_est.cwiseAbs().maxCoeff();
  const double y_max = y_lin.cwiseAbs().maxCoeff();
  const double y_hi = y_lin.maxCoeff(), y_lo = y_lin.minCoeff(), y_mean = y_lin.mean();
  const double sign = Uniform(rng, 0, 1) < 0.5 ? -1.0 : 1.0;
  Effect& e = c.effect;
  e.kind = truth;
  const double slow = 1.0 / bandwidth;
  switch (truth) {
    case EffectKind::kParameterMismatch:
      for (int i = 1; i < c.real.den.size(); ++i)
        c.real.den(i) *= 1 + (Uniform(rng, 0, 1) < 0.5 ? -1 : 1) * Uniform(rng, 0.1, 0.3);
      c.real.num *= 1 + (Uniform(rng, 0, 1) < 0.5 ? -1 : 1) * Uniform(rng, 0.1, 0.3);
      e.kind = EffectKind::kNone;
      break;
    case EffectKind::kTimeDelay:
      e.params = {std::max(2 * options.sample_time, Uniform(rng, 0.1, 0.4) * slow)};
      break;
    case EffectKind::kActuatorLag: e.params = {Uniform(rng, 0.15, 0.6) * slow}; break;
    case EffectKind::kUnmodelledResonance:
      e.params = {std::min(Uniform(rng, 3.0, 8.0) * bandwidth, 0.3 * M_PI / options.sample_time),
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
      e.params = {y_mean - Uniform(rng, 0.5, 0.8) * (y_mean - y_lo),
                  y_mean + Uniform(rng, 0.5, 0.8) * (y_hi - y_mean)};
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
      e.params = {Uniform(rng, 0.03, 0.1) * (y_hi - y_lo)};
      break;
    default:
      break;
  }
  // Noise from the SNR of the rig's own output on the estimation input.
  std::mt19937_64 quiet(0);
  const Eigen::VectorXd y_clean = SimulateRig(c.real, e, u_est, options.sample_time, 0.0, quiet);
  const double rms = std::sqrt((y_clean.array() - y_clean.mean()).square().mean());
  c.noise_sigma = rms * std::pow(10.0, -options.snr_db / 20);
  c.estimation.u = u_est;
  c.estimation.y = SimulateRig(c.real, e, u_est, options.sample_time, c.noise_sigma, rng);
  c.estimation.sample_time = options.sample_time;
  c.validation.u = u_val;
  c.validation.y = SimulateRig(c.real, e, u_val, options.sample_time, c.noise_sigma, rng);
  c.validation.sample_time = options.sample_time;
  return c;
}

}  // namespace idrig
