// Natural-frequency range of [Aleksandrov], sections 4–5: experiments 4.1 (lower bound, (18)–
// (24)) and 5.1 (upper bound, (25)–(30)), and the choice of test frequencies inside the range.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/numeric/finite_frequency/finite_frequency.h"

namespace idrig {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

[[noreturn]] void Fail(const std::string& message) {
  throw std::invalid_argument("finite-frequency range: " + message);
}

std::string Num(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

void CheckOptions(const RangeExperimentOptions& options) {
  if (!(options.initial_omega > 0.0) || !std::isfinite(options.initial_omega))
    Fail("the first test frequency ω_1 must be positive");
  if (!(options.amplitude > 0.0) || !std::isfinite(options.amplitude))
    Fail("the amplitude ρ_1 must be positive");
  if (!(options.filter_time > 0.0)) Fail("the filter time τ* must be positive");
  if (!(options.delta_t > 0.0)) Fail("δ_T of (24) must be positive");
  if (options.max_experiments < 2) Fail("at least two experiments are needed for check (24)");
  if (options.samples_per_period < 8) Fail("use at least 8 samples per period");
  if (options.relative_degree < 1) Fail("n − γ must be >= 1");
  if (options.skip_periods < 0) Fail("skip_periods must be >= 0");
}

FrequencyBoundResult Search(const SineExperimentRunner& run, const RangeExperimentOptions& options,
                            bool upper) {
  CheckOptions(options);
  FrequencyBoundResult result;
  double omega = options.initial_omega;
  result.steps.push_back(RunRangeExperiment(run, omega, options, upper));
  for (int e = 1; e < options.max_experiments; ++e) {
    omega = upper ? 2.0 * omega : 0.5 * omega;  // ω^[i+1] = 2ω^[i] (5.1) or ω^[i]/2 (4.1)
    result.steps.push_back(RunRangeExperiment(run, omega, options, upper));
    const double previous = result.steps[result.steps.size() - 2].time_constant;
    const double current = result.steps.back().time_constant;
    // Eq. (24): |T(ω^[i]) − T(ω^[i+1])| <= δ_T |T(ω^[i+1])|.
    if (std::abs(previous - current) <= options.delta_t * std::abs(current)) {
      result.status = SolverStatus::kOk;
      break;
    }
  }
  const RangeExperimentStep& last = result.steps.back();
  result.iterations = static_cast<int>(result.steps.size());
  result.time_constant = last.time_constant;
  result.omega_bound = 1.0 / last.time_constant;  // Eq. (23) / (30)
  const std::string which = upper ? "upper" : "lower";
  if (result.status == SolverStatus::kOk) {
    result.message = which + " bound ω̂ = " + Num(result.omega_bound) + " rad/s (T = " +
                     Num(last.time_constant) + " s) after " +
                     std::to_string(result.iterations) + " experiments; check (24) met at ω_1 = " +
                     Num(last.omega);
  } else {
    result.status = SolverStatus::kNotConverged;
    result.message = "check (24) not met after " + std::to_string(result.iterations) +
                     " experiments (last ω_1 = " + Num(last.omega) + ", T = " +
                     Num(last.time_constant) + "); lengthen τ* or loosen δ_T";
  }
  if (!(last.time_constant > 0.0) && result.status == SolverStatus::kOk) {
    result.status = SolverStatus::kFailed;
    result.message += "; but T <= 0: the plant is not of the assumed structure (n − γ?)";
  }
  return result;
}

}  // namespace

double LowerTimeConstant(double alpha, double beta, double omega) {
  return -beta / (omega * alpha);  // Eq. (19)
}

double UpperTimeConstant(double alpha, double beta, double omega, int relative_degree) {
  if (relative_degree % 2 == 0) return alpha / (omega * beta);  // Eq. (25)
  return -beta / (omega * alpha);  // Eq. (26) (corrected misprint, see header)
}

RangeExperimentStep RunRangeExperiment(const SineExperimentRunner& run, double omega,
                                       const RangeExperimentOptions& options, bool upper) {
  CheckOptions(options);
  if (!(omega > 0.0)) Fail("ω_1 must be positive");
  const double period = kTwoPi / omega;
  int per_period = options.samples_per_period;
  if (options.max_sample_time > 0.0)
    per_period = std::max(per_period, static_cast<int>(std::ceil(period / options.max_sample_time)));
  const double h = period / per_period;
  const int periods = std::max(1, static_cast<int>(std::lround(options.filter_time / period)));
  const long samples = static_cast<long>(periods + options.skip_periods) * per_period + 1;
  const Eigen::VectorXd y = run(options.amplitude, omega, h, samples);
  if (y.size() != samples)
    Fail("the experiment returned " + std::to_string(y.size()) + " samples, expected " +
         std::to_string(samples));
  // Experiment 4.1/5.1: the test signal (18) through the Fourier filter (6) with n = 1.
  FiniteFrequencySignal signal;
  signal.base_omega = omega;
  signal.multiples = {1};
  signal.amplitudes = {options.amplitude};
  const Eigen::VectorXd measured = y.tail(samples - options.skip_periods * per_period);
  const auto estimates = FourierFilterPerBasePeriod(measured, h, signal, 0.0, periods);
  if (estimates.empty()) Fail("the experiment is shorter than one period");
  RangeExperimentStep step;
  step.omega = omega;
  step.tau = estimates.back().tau;
  step.sample_time = h;
  step.alpha = estimates.back().alpha[0];
  step.beta = estimates.back().beta[0];
  step.time_constant = upper ? UpperTimeConstant(step.alpha, step.beta, omega, options.relative_degree)
                             : LowerTimeConstant(step.alpha, step.beta, omega);
  return step;
}

FrequencyBoundResult EstimateLowerFrequencyBound(const SineExperimentRunner& run,
                                                 const RangeExperimentOptions& options) {
  return Search(run, options, /*upper=*/false);
}

FrequencyBoundResult EstimateUpperFrequencyBound(const SineExperimentRunner& run,
                                                 const RangeExperimentOptions& options) {
  return Search(run, options, /*upper=*/true);
}

FiniteFrequencySignal ChooseTestFrequencies(double omega_lower, double omega_upper, int count,
                                            double amplitude, int base_divisor) {
  if (!(omega_lower > 0.0) || !(omega_upper > omega_lower))
    Fail("the range needs 0 < ω_lower < ω_upper, got [" + Num(omega_lower) + ", " +
         Num(omega_upper) + "]");
  if (count < 1) Fail("at least one test frequency");
  if (base_divisor < 1) Fail("base_divisor must be >= 1");
  if (!(amplitude > 0.0)) Fail("the amplitude must be positive");
  FiniteFrequencySignal signal;
  signal.base_omega = omega_lower / base_divisor;
  for (int i = 0; i < count; ++i) {
    const double fraction = count == 1 ? 0.5 : static_cast<double>(i) / (count - 1);
    const double target = omega_lower * std::pow(omega_upper / omega_lower, fraction);
    int multiple = std::max(1, static_cast<int>(std::lround(target / signal.base_omega)));
    if (!signal.multiples.empty()) multiple = std::max(multiple, signal.multiples.back() + 1);
    signal.multiples.push_back(multiple);
    signal.amplitudes.push_back(amplitude);
  }
  return signal;
}

}  // namespace idrig
