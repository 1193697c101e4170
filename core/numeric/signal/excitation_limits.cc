// Amplitude and rate bounds, and the small-excitation condition (14) of [Aleksandrov].
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/numeric/signal/excitation.h"

namespace idrig {

namespace {

std::string Num(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

constexpr int64_t kMaxCheckedSamples = 20'000'000;

}  // namespace

AcceptedExcitation AcceptExcitation(const ExcitationSpec& spec, double sample_rate_hz,
                                    const ExcitationLimits& limits) {
  ValidateExcitation(spec, sample_rate_hz);
  if (!(limits.max_abs >= 0.0) || !(limits.max_rate >= 0.0) || !(limits.horizon_s >= 0.0))
    throw std::invalid_argument("excitation limits: max_abs, max_rate and horizon_s must be >= 0");
  double horizon = limits.horizon_s;
  if (horizon == 0.0) {
    horizon = ExcitationPeriod(spec, sample_rate_hz);
    if (horizon == 0.0) horizon = 10.0;
    if (spec.kind == ExcitationKind::kStep || spec.kind == ExcitationKind::kExponential)
      horizon = std::max(horizon, spec.start_time + 10.0 * spec.time_constant);
  }
  const int64_t samples =
      std::min<int64_t>(kMaxCheckedSamples, static_cast<int64_t>(std::ceil(horizon * sample_rate_hz)) + 1);

  AcceptedExcitation accepted;
  accepted.spec = spec;
  Eigen::VectorXd u = GenerateExcitation(spec, sample_rate_hz, samples);

  // Condition (14) of [Aleksandrov]: |y(t) − ȳ(t)| ≤ ε_y. For a linear plant y − ȳ is the
  // response to u alone from rest: simulate it on the prior model.
  const SmallExcitation& small = limits.small_excitation;
  if (small.enabled) {
    if (!(small.epsilon_y > 0.0))
      throw std::invalid_argument("small-excitation condition (14): epsilon_y must be > 0");
    Validate(small.prior_model);
    const StateSpace model = ToStateSpace(small.prior_model);
    if (model.IsDiscrete() && std::abs(model.sample_time * sample_rate_hz - 1.0) > 1e-9)
      throw std::invalid_argument(
          "small-excitation condition (14): the discrete prior model's sample time " +
          Num(model.sample_time) + " s differs from 1/fs = " + Num(1.0 / sample_rate_hz) + " s");
    const Eigen::MatrixXd y = Simulate(model, u, 1.0 / sample_rate_hz);
    const double peak = y.cwiseAbs().maxCoeff();
    if (!(peak > 0.0))
      throw std::invalid_argument(
          "small-excitation condition (14): the prior model does not respond to this signal");
    if (small.scale_to_fit) {
      accepted.amplitude_scale = small.epsilon_y / peak;
      accepted.spec.amplitude *= accepted.amplitude_scale;
      accepted.spec.offset *= accepted.amplitude_scale;
      u *= accepted.amplitude_scale;
      accepted.peak_forced_response = small.epsilon_y;
    } else if (peak > small.epsilon_y) {
      throw std::invalid_argument(
          "small-excitation condition (14) violated: max|y − ȳ| = " + Num(peak) +
          " on the prior model exceeds epsilon_y = " + Num(small.epsilon_y) +
          "; lower amp to at most " + Num(spec.amplitude * small.epsilon_y / peak));
    } else {
      accepted.peak_forced_response = peak;
    }
  }

  accepted.peak_abs = u.cwiseAbs().maxCoeff();
  double rate = std::abs(u[0]) * sample_rate_hz;  // from rest, u_{−1} = 0
  for (int64_t k = 1; k < u.size(); ++k)
    rate = std::max(rate, std::abs(u[k] - u[k - 1]) * sample_rate_hz);
  accepted.peak_rate = rate;
  const double amp = accepted.spec.amplitude;
  if (limits.max_abs > 0.0 && accepted.peak_abs > limits.max_abs)
    throw std::invalid_argument("excitation '" + FormatExcitationSpec(accepted.spec) +
                                "' reaches |u| = " + Num(accepted.peak_abs) +
                                " above the amplitude bound " + Num(limits.max_abs) +
                                "; lower amp (and offset) by the factor " +
                                Num(limits.max_abs / accepted.peak_abs) + " (amp <= " +
                                Num(amp * limits.max_abs / accepted.peak_abs) + ")");
  if (limits.max_rate > 0.0 && accepted.peak_rate > limits.max_rate)
    throw std::invalid_argument("excitation '" + FormatExcitationSpec(accepted.spec) +
                                "' changes at |du/dt| = " + Num(accepted.peak_rate) +
                                "/s above the rate bound " + Num(limits.max_rate) +
                                "/s; lower amp, the frequencies or the bit clock fc (amp <= " +
                                Num(amp * limits.max_rate / accepted.peak_rate) +
                                " at these frequencies)");
  return accepted;
}

}  // namespace idrig
