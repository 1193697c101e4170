// Finite-frequency identification, [Aleksandrov] (seed 003): Fourier filter (6), filterability
// (7)–(8), frequency equations (11)–(12), stopping rule (13), λ blocks (31)–(35).
// The natural-frequency range experiments (18)–(30) are in finite_frequency_range.cc.
#include "core/numeric/finite_frequency/finite_frequency.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/numeric/validation.h"

namespace idrig {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

[[noreturn]] void Fail(const std::string& message) {
  throw std::invalid_argument("finite-frequency: " + message);
}

std::string Num(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

// p(s + a) for ascending coefficients p_0..p_m: p'_j = Σ_{i>=j} C(i, j) a^(i−j) p_i.
Eigen::VectorXd ShiftPolynomial(const Eigen::VectorXd& ascending, double a) {
  const int m = static_cast<int>(ascending.size());
  Eigen::VectorXd out = Eigen::VectorXd::Zero(m);
  for (int i = 0; i < m; ++i) {
    double binomial = 1.0;  // C(i, j), j = i downwards
    double power = 1.0;     // a^(i − j)
    for (int j = i; j >= 0; --j) {
      out[j] += binomial * power * ascending[i];
      // next j − 1: C(i, j−1) = C(i, j)·j/(i − j + 1)
      binomial = binomial * j / (i - j + 1);
      power *= a;
    }
  }
  return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Test signal (5).

double FiniteFrequencySignal::BasePeriod() const { return kTwoPi / base_omega; }

Eigen::VectorXd FiniteFrequencySignal::Omegas() const {
  Eigen::VectorXd w(multiples.size());
  for (size_t i = 0; i < multiples.size(); ++i) w[i] = multiples[i] * base_omega;
  return w;
}

double FiniteFrequencySignal::ValueAt(double t) const {
  double u = 0.0;  // Eq. (5) of [Aleksandrov]
  for (size_t i = 0; i < multiples.size(); ++i)
    u += amplitudes[i] * std::sin(multiples[i] * base_omega * t);
  return u;
}

void ValidateSignal(const FiniteFrequencySignal& signal, double sample_time) {
  if (!(signal.base_omega > 0.0) || !std::isfinite(signal.base_omega))
    Fail("the base frequency ω_b = " + Num(signal.base_omega) + " rad/s must be positive");
  if (signal.multiples.empty()) Fail("the test signal has no frequencies");
  if (signal.amplitudes.size() != signal.multiples.size())
    Fail("the test signal has " + std::to_string(signal.multiples.size()) + " frequencies but " +
         std::to_string(signal.amplitudes.size()) + " amplitudes");
  for (size_t i = 0; i < signal.multiples.size(); ++i) {
    if (signal.multiples[i] < 1)
      Fail("test frequency multiple n_" + std::to_string(i + 1) + " = " +
           std::to_string(signal.multiples[i]) + " must be a positive integer (ω_k = n_k ω_b)");
    if (!(signal.amplitudes[i] > 0.0) || !std::isfinite(signal.amplitudes[i]))
      Fail("amplitude ρ_" + std::to_string(i + 1) + " = " + Num(signal.amplitudes[i]) +
           " must be positive and finite");
    for (size_t j = 0; j < i; ++j)
      if (signal.multiples[j] == signal.multiples[i])
        Fail("test frequency " + std::to_string(signal.multiples[i]) +
             "·ω_b is listed twice; the frequencies must be distinct");
    if (sample_time > 0.0 && signal.multiples[i] * signal.base_omega * sample_time >= kTwoPi / 2)
      Fail("test frequency " + Num(signal.multiples[i] * signal.base_omega) +
           " rad/s is not below the Nyquist frequency π/h = " + Num(kTwoPi / 2 / sample_time));
  }
}

FiniteFrequencySignal MakeFiniteFrequencySignal(double base_omega, const Eigen::VectorXd& omegas,
                                                const std::vector<double>& amplitudes,
                                                double tolerance) {
  if (!(base_omega > 0.0)) Fail("the base frequency ω_b must be positive");
  FiniteFrequencySignal signal;
  signal.base_omega = base_omega;
  signal.amplitudes = amplitudes;
  for (int i = 0; i < omegas.size(); ++i) {
    const double ratio = omegas[i] / base_omega;
    const double rounded = std::round(ratio);
    if (!(rounded >= 1.0) || std::abs(ratio - rounded) > tolerance * std::max(1.0, ratio))
      Fail("test frequency ω_" + std::to_string(i + 1) + " = " + Num(omegas[i]) +
           " rad/s is not an integer multiple of the base frequency ω_b = " + Num(base_omega) +
           " rad/s (ratio " + Num(ratio) + "); choose ω_k = n_k·ω_b");
    signal.multiples.push_back(static_cast<int>(rounded));
  }
  ValidateSignal(signal);
  return signal;
}

// ---------------------------------------------------------------------------------------------
// Fourier filter (6).

FourierFilter::FourierFilter(const FiniteFrequencySignal& signal, double sample_time,
                             double lambda, double block_time_offset)
    : signal_(signal),
      sample_time_(sample_time),
      lambda_(lambda),
      block_time_offset_(block_time_offset) {
  if (!(sample_time > 0.0) || !std::isfinite(sample_time))
    Fail("the sample time h = " + Num(sample_time) + " s must be positive");
  if (!(lambda >= 0.0) || !std::isfinite(lambda)) Fail("λ must be >= 0");
  ValidateSignal(signal, sample_time);
  omegas_ = signal.Omegas();
  rho_ = Eigen::Map<const Eigen::VectorXd>(signal.amplitudes.data(), signal.amplitudes.size());
  base_period_ = signal.BasePeriod();
  const auto lines = omegas_.size();
  sin_sum_ = cos_sum_ = last_sin_ = last_cos_ = Eigen::VectorXd::Zero(lines);
}

bool FourierFilter::Add(double y) {
  const long i = samples_++;
  const double t = static_cast<double>(i) * sample_time_;
  // (−λ) block, Eq. (31): ỹ = y·e^(−λ(t − t0)).
  const double value =
      lambda_ > 0.0 ? y * std::exp(-lambda_ * (t + block_time_offset_)) : y;
  const Eigen::VectorXd s = (omegas_ * t).array().sin(), c = (omegas_ * t).array().cos();
  bool completed = false;
  if (i > 0) {
    const double t_prev = t - sample_time_;
    // Base period boundaries τ_q = q·T_b inside (t_prev, t]: trapezoid up to τ_q with ỹ(τ_q)
    // interpolated linearly (exact boundary when τ_q is on a sample).
    for (;;) {
      const int q = completed_periods() + 1;
      const double tau = q * base_period_;
      if (tau > t + 1e-9 * sample_time_) break;
      const double part = std::min(tau - t_prev, sample_time_);
      const double fraction = part / sample_time_;
      const double y_tau = last_value_ + fraction * (value - last_value_);
      const Eigen::VectorXd s_tau = (omegas_ * tau).array().sin();
      const Eigen::VectorXd c_tau = (omegas_ * tau).array().cos();
      const Eigen::VectorXd sin_int = sin_sum_ + 0.5 * part * (last_value_ * last_sin_ + y_tau * s_tau);
      const Eigen::VectorXd cos_int = cos_sum_ + 0.5 * part * (last_value_ * last_cos_ + y_tau * c_tau);
      FrequencyParameters estimate;
      estimate.base_periods = q;
      estimate.tau = tau;
      // Eq. (6): α_k = 2/(ρ_k τ)∫ ỹ sin ω_k(t − t0) dt, β_k = 2/(ρ_k τ)∫ ỹ cos ω_k(t − t0) dt.
      estimate.alpha = (2.0 / tau) * sin_int.cwiseQuotient(rho_);
      estimate.beta = (2.0 / tau) * cos_int.cwiseQuotient(rho_);
      estimates_.push_back(std::move(estimate));
      completed = true;
    }
    sin_sum_ += 0.5 * sample_time_ * (last_value_ * last_sin_ + value * s);
    cos_sum_ += 0.5 * sample_time_ * (last_value_ * last_cos_ + value * c);
  }
  last_value_ = value;
  last_sin_ = s;
  last_cos_ = c;
  return completed;
}

std::vector<FrequencyParameters> FourierFilterPerBasePeriod(const Eigen::VectorXd& y,
                                                            double sample_time,
                                                            const FiniteFrequencySignal& signal,
                                                            double lambda, int max_base_periods) {
  FourierFilter filter(signal, sample_time, lambda);
  for (Eigen::Index i = 0; i < y.size(); ++i) {
    if (!std::isfinite(y[i])) Fail("output sample " + std::to_string(i) + " is not finite");
    filter.Add(y[i]);
    if (max_base_periods > 0 && filter.completed_periods() >= max_base_periods) break;
  }
  std::vector<FrequencyParameters> out = filter.estimates();
  if (max_base_periods > 0 && static_cast<int>(out.size()) > max_base_periods)
    out.resize(max_base_periods);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Filterability (7)–(8).

FilterabilityResult CheckFilterability(const Eigen::VectorXd& natural_output, double sample_time,
                                       const FiniteFrequencySignal& signal,
                                       const FilterabilityOptions& options) {
  if (!(options.epsilon_alpha > 0.0) || !(options.epsilon_beta > 0.0))
    Fail("filterability tolerances ε^α, ε^β of (8) must be positive");
  FilterabilityResult result;
  // Eq. (7): the Fourier filter (6) applied to the unexcited output ȳ.
  result.functions = FourierFilterPerBasePeriod(natural_output, sample_time, signal);
  result.iterations = static_cast<int>(result.functions.size());
  if (result.functions.empty()) {
    result.status = SolverStatus::kFailed;
    result.message = "the record is shorter than one base period T_b = " +
                     Num(signal.BasePeriod()) + " s";
    return result;
  }
  // Eq. (8): |ℓ^α_k(τ)| <= ε^α, |ℓ^β_k(τ)| <= ε^β from some τ on.
  int from = 0;
  for (const auto& f : result.functions) {
    const bool holds = f.alpha.cwiseAbs().maxCoeff() <= options.epsilon_alpha &&
                       f.beta.cwiseAbs().maxCoeff() <= options.epsilon_beta;
    if (!holds) from = 0;
    else if (from == 0) from = f.base_periods;
  }
  result.filterable_from = from;
  const auto& last = result.functions.back();
  result.final_cost = std::max(last.alpha.cwiseAbs().maxCoeff(), last.beta.cwiseAbs().maxCoeff());
  if (from > 0) {
    result.status = SolverStatus::kOk;
    result.message = "condition (8) holds from q = " + std::to_string(from) + " (τ = " +
                     Num(from * signal.BasePeriod()) + " s) to the end of the record";
  } else {
    result.status = SolverStatus::kNotConverged;
    result.message = "condition (8) does not hold at the end of the record: max |ℓ| = " +
                     Num(result.final_cost) + "; record longer or raise the amplitudes ρ_k";
  }
  return result;
}

// ---------------------------------------------------------------------------------------------
// Frequency equations (11)–(12).

FrequencyEquationsResult SolveFrequencyEquations(const Eigen::VectorXd& omegas,
                                                 const Eigen::VectorXd& alpha,
                                                 const Eigen::VectorXd& beta, int order,
                                                 int numerator_degree) {
  const int n = order, gamma = numerator_degree;
  const int lines = static_cast<int>(omegas.size());
  if (n < 1) Fail("the plant order n = " + std::to_string(n) + " must be >= 1");
  if (gamma < 0 || gamma >= n)
    Fail("the numerator degree γ = " + std::to_string(gamma) + " must satisfy 0 <= γ < n = " +
         std::to_string(n));
  if (alpha.size() != lines || beta.size() != lines)
    Fail("α and β need one value per test frequency");
  const int unknowns = n + gamma + 1;
  if (2 * lines < unknowns)
    Fail(std::to_string(lines) + " test frequencies give " + std::to_string(2 * lines) +
         " real equations but n + γ + 1 = " + std::to_string(unknowns) +
         " coefficients are unknown: use at least " + std::to_string((unknowns + 1) / 2) +
         " frequencies (the paper uses n)");
  for (int i = 0; i < lines; ++i) {
    if (!(omegas[i] > 0.0) || !std::isfinite(omegas[i]))
      Fail("test frequencies must be positive (ω_k != 0)");
    if (!std::isfinite(alpha[i]) || !std::isfinite(beta[i])) Fail("α, β must be finite");
    for (int j = 0; j < i; ++j)
      if (omegas[i] == omegas[j]) Fail("test frequencies must be distinct (ω_i != ω_j)");
  }
  // Unknowns x = (d_1..d_n, k_0..k_γ). Row pair per line, Eq. (12):
  //   Σ_j k_j (jω)^j − (α + jβ) Σ_i d_i (jω)^i = α + jβ.
  Eigen::MatrixXd a(2 * lines, unknowns);
  Eigen::VectorXd b(2 * lines);
  for (int l = 0; l < lines; ++l) {
    const std::complex<double> s(0.0, omegas[l]), g(alpha[l], beta[l]);
    std::complex<double> power = 1.0;
    for (int p = 0; p <= n; ++p) {
      if (p >= 1) {
        const std::complex<double> coef = -g * power;
        a(2 * l, p - 1) = coef.real();
        a(2 * l + 1, p - 1) = coef.imag();
      }
      if (p <= gamma) {
        a(2 * l, n + p) = power.real();
        a(2 * l + 1, n + p) = power.imag();
      }
      power *= s;
    }
    b[2 * l] = g.real();
    b[2 * l + 1] = g.imag();
  }
  // Column equilibration, then a rank-revealing solve.
  Eigen::VectorXd scale = a.colwise().norm().transpose();
  for (int c = 0; c < unknowns; ++c)
    if (!(scale[c] > 0.0)) scale[c] = 1.0;
  const Eigen::MatrixXd scaled = a * scale.cwiseInverse().asDiagonal();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(scaled, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = svd.singularValues();
  FrequencyEquationsResult result;
  result.iterations = 1;
  result.condition_number = sv[sv.size() - 1] > 0.0 ? sv[0] / sv[sv.size() - 1]
                                                    : std::numeric_limits<double>::infinity();
  const Eigen::VectorXd x =
      (Eigen::ColPivHouseholderQR<Eigen::MatrixXd>(scaled).solve(b)).cwiseQuotient(scale);
  result.d = x.head(n);
  result.k = x.tail(gamma + 1);
  result.final_cost = (a * x - b).norm();
  result.model.den.resize(n + 1);
  for (int i = 0; i < n; ++i) result.model.den[i] = result.d[n - 1 - i];
  result.model.den[n] = 1.0;
  result.model.num.resize(gamma + 1);
  for (int j = 0; j <= gamma; ++j) result.model.num[j] = result.k[gamma - j];
  if (!std::isfinite(result.condition_number) || result.condition_number > 1e12) {
    result.status = SolverStatus::kIllConditioned;
    result.message = "the frequency equations are ill-conditioned (condition number " +
                     Num(result.condition_number) +
                     "); choose test frequencies inside the natural-frequency range";
  } else {
    result.status = SolverStatus::kOk;
    result.message = "solved " + std::to_string(2 * lines) + " real equations for " +
                     std::to_string(unknowns) + " coefficients";
  }
  return result;
}

void UnshiftCoefficients(double lambda, Eigen::VectorXd* d, Eigen::VectorXd* k) {
  // Eq. (35): w̃(s) = w(s + λ) ⇒ d(s) ∝ d̃(s − λ), k(s) ∝ k̃(s − λ), normalised to d(0) = 1.
  const int n = static_cast<int>(d->size());
  Eigen::VectorXd den(n + 1);
  den[0] = 1.0;
  den.tail(n) = *d;
  const Eigen::VectorXd den_shifted = ShiftPolynomial(den, -lambda);
  const Eigen::VectorXd num_shifted = ShiftPolynomial(*k, -lambda);
  const double normaliser = den_shifted[0];  // d̃(−λ)
  if (normaliser == 0.0 || !std::isfinite(normaliser))
    Fail("cannot shift back by λ = " + Num(lambda) + ": d̃(−λ) = 0 (the plant has a pole at 0)");
  *d = den_shifted.tail(n) / normaliser;
  *k = num_shifted / normaliser;
}

// ---------------------------------------------------------------------------------------------
// Algorithm 2.1.

FiniteFrequencyResult IdentifyFiniteFrequency(const IoRecord& record,
                                              const FiniteFrequencyOptions& options) {
  ValidateIoRecord(record);
  if (record.NumInputs() != 1 || record.NumOutputs() != 1)
    Fail("the method is SISO: the record has " + std::to_string(record.NumInputs()) +
         " inputs and " + std::to_string(record.NumOutputs()) + " outputs");
  FiniteFrequencyResult result =
      IdentifyFiniteFrequency(record.y.col(0), record.sample_time, options, record.u.col(0));
  // Simulation fit of the model on the record (from rest, the input held between samples).
  // With λ > 0 the record's input is ũ = u·e^(λt) and w(s) may be unstable: no fit.
  result.fit_percent = std::numeric_limits<double>::quiet_NaN();
  if (options.lambda == 0.0 && result.status != SolverStatus::kFailed && result.model.den.allFinite() &&
      result.model.num.allFinite()) {
    const Eigen::MatrixXd sim = Simulate(LtiModel(result.model), record.u, record.sample_time);
    result.fit_percent = FitPercent(record.y, sim)(0);
  }
  return result;
}

FiniteFrequencyResult IdentifyFiniteFrequency(const Eigen::VectorXd& y, double sample_time,
                                              const FiniteFrequencyOptions& options,
                                              const Eigen::VectorXd& u) {
  const int n = options.order, gamma = options.numerator_degree;
  if (n < 1) Fail("set the plant order n (options.order >= 1)");
  if (gamma < 0 || gamma >= n) Fail("the numerator degree γ must satisfy 0 <= γ < n");
  ValidateSignal(options.signal, sample_time);
  const int lines = static_cast<int>(options.signal.multiples.size());
  if (2 * lines < n + gamma + 1)
    Fail(std::to_string(lines) + " test frequencies are fewer than the order needs: n + γ + 1 = " +
         std::to_string(n + gamma + 1) + " coefficients need at least " +
         std::to_string((n + gamma + 2) / 2) + " frequencies");
  if (!(options.epsilon_d > 0.0) || !(options.epsilon_k > 0.0))
    Fail("the stopping-rule tolerances ε^d, ε^k of (13) must be positive");
  if (options.consecutive < 1 || options.min_base_periods < 1 || options.skip_base_periods < 0 ||
      options.max_base_periods < 0)
    Fail("consecutive and min_base_periods must be >= 1, skip/max_base_periods >= 0");
  if (u.size() != 0 && u.size() != y.size())
    Fail("input and output records differ in length");
  if (!(options.input_bound >= 0.0) || !(options.output_bound >= 0.0))
    Fail("the bounds of note 6.1 must be >= 0 (0: unchecked)");
  const double base_period = options.signal.BasePeriod();
  if (options.lambda == 0.0 && options.input_bound > 0.0) {
    double peak = 0.0;
    for (double rho : options.signal.amplitudes) peak += rho;
    if (peak > options.input_bound)
      Fail("the test-signal amplitudes Σρ_k = " + Num(peak) + " exceed the input bound u* = " +
           Num(options.input_bound) + "; lower the amplitudes ρ_k");
  }
  int max_periods = options.max_base_periods;
  if (options.filter_time != 0.0) {
    const double q = options.filter_time / base_period;
    if (!(options.filter_time > 0.0) || std::round(q) < 1.0 ||
        std::abs(q - std::round(q)) > 1e-6 * std::max(1.0, q))
      Fail("the filter time τ = " + Num(options.filter_time) +
           " s is not a whole number of base periods T_b = " + Num(base_period) + " s (τ/T_b = " +
           Num(q) + "); use τ = q·T_b");
    max_periods = static_cast<int>(std::round(q));
  }

  // Note 6.1: the record ends at the first violation of |ũ| <= ũ*, |y| <= y*.
  Eigen::Index usable = y.size();
  bool bound_reached = false;
  for (Eigen::Index i = 0; i < y.size(); ++i) {
    if (!std::isfinite(y[i])) Fail("output sample " + std::to_string(i) + " is not finite");
    const bool over = (options.output_bound > 0.0 && std::abs(y[i]) > options.output_bound) ||
                      (options.input_bound > 0.0 && u.size() && std::abs(u[i]) > options.input_bound);
    if (over) {
      usable = i;
      bound_reached = true;
      break;
    }
  }

  // Skipped whole base periods (transient): t0 moves to skip·T_b, which must be on a sample.
  Eigen::Index start = 0;
  if (options.skip_base_periods > 0) {
    const double exact = options.skip_base_periods * base_period / sample_time;
    start = static_cast<Eigen::Index>(std::llround(exact));
    if (std::abs(exact - start) > 1e-6)
      Fail("skip_base_periods needs T_b = " + Num(base_period) +
           " s to be a whole number of samples h = " + Num(sample_time) + " s");
  }
  FourierFilter filter(options.signal, sample_time, options.lambda, start * sample_time);
  FiniteFrequencyResult result;
  result.bound_reached = bound_reached;
  result.record_used_s = usable > 0 ? (usable - 1) * sample_time : 0.0;
  const Eigen::VectorXd omegas = options.signal.Omegas();
  int consecutive = 0;
  bool stopped = false;
  for (Eigen::Index i = start; i < usable && !stopped; ++i) {
    if (!filter.Add(y[i])) continue;
    while (static_cast<int>(result.history.size()) < filter.completed_periods()) {
      const FrequencyParameters& p = filter.estimates()[result.history.size()];
      FiniteFrequencyEstimate e;
      e.base_periods = p.base_periods;
      e.tau = p.tau;
      e.alpha = p.alpha;
      e.beta = p.beta;
      if (options.zoh_correction) {
        for (int l = 0; l < lines; ++l) {
          // Z(s) = (1 − e^(−sh))/(sh) at s = λ + jω_l: the hold's response (half-sample delay).
          const std::complex<double> s(options.lambda, omegas[l]), sh = s * sample_time;
          const std::complex<double> z = std::abs(sh) < 1e-8 ? 1.0 - 0.5 * sh : (1.0 - std::exp(-sh)) / sh;
          const std::complex<double> g = std::complex<double>(p.alpha[l], p.beta[l]) / z;
          e.alpha[l] = g.real();
          e.beta[l] = g.imag();
        }
      }
      // Operation (в): frequency equations (12) at τ = q·T_b.
      const FrequencyEquationsResult solved = SolveFrequencyEquations(omegas, e.alpha, e.beta, n, gamma);
      e.d = solved.d;
      e.k = solved.k;
      e.condition_number = solved.condition_number;
      if (options.lambda > 0.0) UnshiftCoefficients(options.lambda, &e.d, &e.k);  // Eq. (35)
      // Stopping rule (13) against the previous base period.
      if (!result.history.empty() && e.base_periods >= options.min_base_periods) {
        const auto& prev = result.history.back();
        e.rule_met = ((e.d - prev.d).cwiseAbs().array() <=
                      options.epsilon_d * e.d.cwiseAbs().array()).all() &&
                     ((e.k - prev.k).cwiseAbs().array() <=
                      options.epsilon_k * e.k.cwiseAbs().array()).all();
      }
      consecutive = e.rule_met ? consecutive + 1 : 0;
      result.history.push_back(e);
      if (consecutive >= options.consecutive && options.filter_time == 0.0) {
        stopped = true;
        break;
      }
      if (max_periods > 0 && static_cast<int>(result.history.size()) >= max_periods) {
        stopped = true;
        break;
      }
    }
  }
  if (result.history.empty()) {
    result.status = SolverStatus::kFailed;
    result.message = "the usable record (" + Num(result.record_used_s) +
                     " s) is shorter than one base period T_b = " + Num(base_period) + " s" +
                     (bound_reached ? " because a bound of note 6.1 was reached" : "");
    return result;
  }
  const FiniteFrequencyEstimate& last = result.history.back();
  result.d = last.d;
  result.k = last.k;
  result.base_periods = last.base_periods;
  result.tau = last.tau;
  result.iterations = last.base_periods;
  result.stopping_rule_met = consecutive >= options.consecutive;
  result.model.den.resize(n + 1);
  for (int i = 0; i < n; ++i) result.model.den[i] = result.d[n - 1 - i];
  result.model.den[n] = 1.0;
  result.model.num.resize(gamma + 1);
  for (int j = 0; j <= gamma; ++j) result.model.num[j] = result.k[gamma - j];
  // Cost: residual of the frequency equations of the final model, relative.
  double residual = 0.0, scale = 0.0;
  for (int l = 0; l < lines; ++l) {
    const std::complex<double> g(last.alpha[l], last.beta[l]);
    std::complex<double> model = FrequencyResponse(result.model, omegas[l]);
    if (options.lambda > 0.0) {
      model = PolyVal(result.model.num, std::complex<double>(options.lambda, omegas[l])) /
              PolyVal(result.model.den, std::complex<double>(options.lambda, omegas[l]));
    }
    residual += std::norm(g - model);
    scale += std::norm(g);
  }
  result.final_cost = scale > 0.0 ? std::sqrt(residual / scale) : 0.0;
  if (options.filter_time > 0.0) {
    const bool reached = result.base_periods == max_periods;
    result.status = reached ? SolverStatus::kOk : SolverStatus::kNotConverged;
    result.message = reached ? "fixed filter time τ = " + Num(result.tau) + " s (" +
                                   std::to_string(result.base_periods) + " base periods)"
                             : "the record ends after " + std::to_string(result.base_periods) +
                                   " base periods, before the requested τ = " +
                                   Num(options.filter_time) + " s";
  } else if (result.stopping_rule_met) {
    result.status = last.condition_number > 1e12 ? SolverStatus::kIllConditioned
                                                  : SolverStatus::kOk;
    result.message = "stopping rule (13) met at q = " + std::to_string(result.base_periods) +
                     " base periods (τ = " + Num(result.tau) + " s)";
    if (result.status == SolverStatus::kIllConditioned)
      result.message += "; the frequency equations are ill-conditioned (condition number " +
                        Num(last.condition_number) + ")";
  } else {
    result.status = SolverStatus::kNotConverged;
    result.message = "stopping rule (13) not met within " + std::to_string(result.base_periods) +
                     " base periods (τ = " + Num(result.tau) + " s)" +
                     (bound_reached ? ": a bound of note 6.1 ended the experiment"
                                    : ": record longer, raise ρ_k or loosen ε^d, ε^k");
  }
  return result;
}

}  // namespace idrig
