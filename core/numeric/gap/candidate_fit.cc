// Candidate fitting of the gap diagnosis (see gap_diagnosis.h, gap_internal.h): one candidate's
// model (G0's coefficients as log multipliers, the effect's parameters φ), its output-error
// residuals, the Levenberg–Marquardt fit from the effect's starts, and the parameters' 1σ.
#include <unsupported/Eigen/NonLinearOptimization>
#include <unsupported/Eigen/NumericalDiff>

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>

#include "core/numeric/gap/gap_internal.h"

namespace idrig::gap_detail {

Candidate::Candidate(const TransferFunction& base, EffectKind kind, bool fit_plant,
                     const Scales& scales, int substeps, std::vector<double> fixed)
    : base_(base), kind_(kind), scales_(scales), substeps_(substeps), fixed_(std::move(fixed)) {
  if (fit_plant) {
    for (int i = 1; i < base.den.size(); ++i)
      if (base.den(i) != 0) free_den_.push_back(i);
    for (int i = 0; i < base.num.size(); ++i)
      if (base.num(i) != 0) free_num_.push_back(i);
  }
  effect_params_ = NumEffectParams(kind, fixed_);
}

int Candidate::NumEffectParams(EffectKind kind, const std::vector<double>& fixed) {
  switch (kind) {
    case EffectKind::kTimeDelay:
    case EffectKind::kActuatorLag:
    case EffectKind::kDeadZone:
    case EffectKind::kBacklash:
    case EffectKind::kCoulombFriction:
    case EffectKind::kCubicStiffness:
      return 1;
    case EffectKind::kUnmodelledResonance:
    case EffectKind::kInputSaturation:
    case EffectKind::kOutputSaturation:
      return 2;
    case EffectKind::kSensorNonlinearity:
      return fixed.empty() ? 2 : 0;  // polynomial a2, a3; or |y| (fixed = {1})
    case EffectKind::kOutputQuantization:
      return 1;  // q fixed by the samples' lattice; fitted: the noise before the rounding
    default:
      return 0;  // none, parameter_mismatch
  }
}

TransferFunction Candidate::Plant(const Eigen::VectorXd& x) const {
  TransferFunction g = base_;
  int j = 0;
  for (int i : free_den_) g.den(i) *= std::exp(std::clamp(x(j++), -20.0, 20.0));
  for (int i : free_num_) g.num(i) *= std::exp(std::clamp(x(j++), -20.0, 20.0));
  if (gain_only_) g.num *= std::exp(std::clamp(x(j++), -20.0, 20.0));
  return g;
}

Effect Candidate::EffectOf(const Eigen::VectorXd& x) const {
  const Eigen::VectorXd phi = x.tail(effect_params_);
  const Scales& s = scales_;
  auto pos = [](double v) { return std::exp(std::clamp(v, -30.0, 30.0)); };
  Effect e;
  e.kind = kind_;
  switch (kind_) {
    case EffectKind::kTimeDelay: e.params = {pos(phi(0)) * s.ts}; break;
    case EffectKind::kActuatorLag: e.params = {pos(phi(0)) * s.ts}; break;
    case EffectKind::kUnmodelledResonance:
      e.params = {pos(phi(0)) / s.ts, std::clamp(pos(phi(1)), 1e-4, 10.0)};
      break;
    case EffectKind::kInputSaturation:
    case EffectKind::kOutputSaturation: {
      const double scale = kind_ == EffectKind::kInputSaturation ? s.u_max : s.y_max;
      double lo = phi(0) * scale, hi = phi(1) * scale;
      if (hi - lo < 1e-9 * scale) hi = lo + 1e-9 * scale;
      e.params = {lo, hi};
      break;
    }
    case EffectKind::kDeadZone:
    case EffectKind::kBacklash:
    case EffectKind::kCoulombFriction:
      e.params = {pos(phi(0)) * s.u_max};
      break;
    case EffectKind::kCubicStiffness:
      e.params = {phi(0) * s.u_max / std::pow(s.y_max, 3)};
      break;
    case EffectKind::kSensorNonlinearity:
      if (fixed_.empty()) e.params = {1.0, phi(0) / s.y_max, phi(1) / (s.y_max * s.y_max), 0.0};
      else e.params = {1.0, 0.0, 0.0, 1.0};
      break;
    case EffectKind::kOutputQuantization: e.params = {fixed_.at(0)}; break;
    default: break;
  }
  return e;
}

Eigen::VectorXd Candidate::Phi(const std::vector<double>& p) const {
  const Scales& s = scales_;
  Eigen::VectorXd phi(effect_params_);
  switch (kind_) {
    case EffectKind::kTimeDelay:
    case EffectKind::kActuatorLag: phi(0) = std::log(p[0] / s.ts); break;
    case EffectKind::kUnmodelledResonance:
      phi(0) = std::log(p[0] * s.ts);
      phi(1) = std::log(p[1]);
      break;
    case EffectKind::kInputSaturation: phi << p[0] / s.u_max, p[1] / s.u_max; break;
    case EffectKind::kOutputSaturation: phi << p[0] / s.y_max, p[1] / s.y_max; break;
    case EffectKind::kDeadZone:
    case EffectKind::kBacklash:
    case EffectKind::kCoulombFriction: phi(0) = std::log(p[0] / s.u_max); break;
    case EffectKind::kCubicStiffness: phi(0) = p[0] * std::pow(s.y_max, 3) / s.u_max; break;
    case EffectKind::kSensorNonlinearity:
      if (effect_params_ == 2) phi << p[1] * s.y_max, p[2] * s.y_max * s.y_max;
      break;
    case EffectKind::kOutputQuantization: phi(0) = std::log(p[0]); break;  // s/q
    default: break;
  }
  return phi;
}

Eigen::VectorXd Candidate::Simulate(const Eigen::VectorXd& x, const GapRecord& record) const {
  EffectSimulationOptions options;
  options.substeps = substeps_;
  if (kind_ == EffectKind::kOutputQuantization) {
    // The best predictor of q·round((y + n)/q) when noise n ~ N(0, s²) enters before the
    // rounding is its conditional mean, a staircase smoothed by s (s → 0: the staircase).
    const double q = fixed_.at(0), s = q * std::exp(std::clamp(x(x.size() - 1), -12.0, 3.0));
    Eigen::VectorXd y = SimulateWithEffect(Plant(x), Effect{}, record.u, record.sample_time, options);
    const int reach = static_cast<int>(std::ceil(5 * s / q)) + 1;
    for (long k = 0; k < y.size(); ++k) {
      const double m = std::round(y(k) / q);
      double mean = 0;
      for (int j = -reach; j <= reach; ++j) {
        const double level = m + j;
        const double upper = 0.5 * std::erfc(-((level + 0.5) * q - y(k)) / (s * M_SQRT2));
        const double lower = 0.5 * std::erfc(-((level - 0.5) * q - y(k)) / (s * M_SQRT2));
        mean += level * (upper - lower);
      }
      // Levels beyond the reach carry < 1e-6 of the probability.
      y(k) = q * mean;
    }
    return y;
  }
  return SimulateWithEffect(Plant(x), EffectOf(x), record.u, record.sample_time, options);
}

void Residuals::operator()(const Eigen::VectorXd& x, Eigen::VectorXd& r) const {
  long offset = 0;
  for (const GapRecord& rec : *records) {
    const long n = rec.u.size() - rec.score_from;
    Eigen::VectorXd y_hat;
    bool ok = true;
    try {
      y_hat = candidate->Simulate(x, rec);
    } catch (const std::exception&) {
      ok = false;  // an invalid parameter set (e.g. a non-finite pole): a large residual
    }
    if (ok) r.segment(offset, n) = rec.y.tail(n) - y_hat.tail(n);
    for (long k = 0; k < n; ++k)
      if (!ok || !std::isfinite(r(offset + k))) r(offset + k) = 1e6 * (1 + std::abs(rec.y(k)));
    offset += n;
  }
}

double Mse(const Residuals& residuals, const Eigen::VectorXd& x) {
  Eigen::VectorXd r(residuals.count);
  residuals(x, r);
  return r.squaredNorm() / std::max<long>(1, residuals.count);
}

FitOutcome Minimise(const Residuals& residuals, Eigen::VectorXd x, int max_evaluations) {
  FitOutcome out;
  int calls = 0;
  if (x.size() > 0) {
    LmFunctor functor{residuals, static_cast<int>(x.size()), &calls};
    Eigen::NumericalDiff<LmFunctor> numeric(functor);
    Eigen::LevenbergMarquardt<Eigen::NumericalDiff<LmFunctor>> lm(numeric);
    lm.parameters.maxfev = max_evaluations;
    lm.parameters.xtol = 1e-7;
    lm.parameters.ftol = 1e-9;
    const auto status = lm.minimize(x);
    out.converged = status == Eigen::LevenbergMarquardtSpace::RelativeReductionTooSmall ||
                    status == Eigen::LevenbergMarquardtSpace::RelativeErrorTooSmall ||
                    status == Eigen::LevenbergMarquardtSpace::RelativeErrorAndReductionTooSmall ||
                    status == Eigen::LevenbergMarquardtSpace::CosinusTooSmall;
  } else {
    out.converged = true;
  }
  out.x = x;
  out.mse = Mse(residuals, x);
  out.evaluations = calls + 1;
  return out;
}

// Starting points (physical units) for each effect, from the data's scales.
std::vector<std::vector<double>> Starts(EffectKind kind, const Scales& s) {
  const double um = s.u_max, ts = s.ts, slow = s.slow;
  switch (kind) {
    case EffectKind::kTimeDelay:
      return {{1.0 * ts}, {3.0 * ts}, {std::max(ts, 0.1 * slow)}, {std::max(2 * ts, 0.4 * slow)},
              {std::max(ts, s.lag_of_best_match)}};
    case EffectKind::kActuatorLag:
      return {{std::max(ts, 0.05 * slow)}, {std::max(ts, 0.2 * slow)}, {std::max(ts, 0.8 * slow)}};
    case EffectKind::kUnmodelledResonance: {
      std::vector<std::vector<double>> starts;
      const double nyquist = M_PI / ts;
      for (double f : {0.01, 0.02, 0.04, 0.08, 0.15, 0.3, 0.5, 0.75})
        starts.push_back({f * nyquist, 0.1});
      return starts;
    }
    case EffectKind::kInputSaturation:
      return {{s.u_quantile[0], s.u_quantile[4]}, {s.u_quantile[1], s.u_quantile[3]},
              {0.5 * (s.u_quantile[1] + s.u_quantile[2]), 0.5 * (s.u_quantile[2] + s.u_quantile[3])}};
    case EffectKind::kDeadZone:
    case EffectKind::kBacklash:
    case EffectKind::kCoulombFriction:
      return {{0.03 * um}, {0.1 * um}, {0.3 * um}, {0.6 * um}};
    case EffectKind::kCubicStiffness: {
      const double unit = um / std::pow(s.y_max, 3);
      return {{0.05 * unit}, {0.3 * unit}, {1.0 * unit}, {-0.05 * unit}};
    }
    case EffectKind::kOutputSaturation:
      return {{s.y_quantile[0], s.y_quantile[3]}, {s.y_quantile[1], s.y_quantile[2]}};
    case EffectKind::kOutputQuantization:
      return {{0.05}, {0.3}};  // noise before the rounding, as a share of q
    case EffectKind::kSensorNonlinearity:
      return {{1.0, 0.0, 0.0, 0.0}, {1.0, 0.1 / s.y_max, 0.0, 0.0}, {1.0, 0.0, -0.1 / (s.y_max * s.y_max), 0.0}};
    default:
      return {{}};
  }
}

// Candidate quantisation steps: the mean resultant length R(q) = |mean exp(2πi y/q)| is near 1
// when the samples sit on multiples of q (and on multiples of q/2, q/3, …), near 1/√N when not.
// The largest q whose R is within half of the best is the step.
double QuantisationStep(const std::vector<GapRecord>& records, double* strength) {
  std::vector<double> y;
  for (const auto& r : records)
    for (long k = r.score_from; k < r.y.size(); ++k) y.push_back(r.y(k));
  double span = *std::max_element(y.begin(), y.end()) - *std::min_element(y.begin(), y.end());
  if (!(span > 0)) span = 1;
  auto resultant = [&y](double q) {
    std::complex<double> sum = 0;
    for (double v : y) sum += std::polar(1.0, 2 * M_PI * v / q);
    return std::abs(sum) / y.size();
  };
  // Coarse logarithmic grid span/3000 … span/3 (0.35 % apart: a lattice of up to ~300 steps
  // stays in phase), then a fine search around the chosen step.
  std::vector<std::pair<double, double>> table;
  const int grid = 2000;
  for (int i = 0; i < grid; ++i) {
    const double q = span * std::pow(10.0, -3.5 + 3.0 * i / (grid - 1));
    table.push_back({q, resultant(q)});
  }
  double best = 0;
  for (auto& [q, r] : table) best = std::max(best, r);
  // The largest-q local maximum that is within half of the best: q itself, not q/2, q/3, ….
  double step = table.front().first;
  for (size_t i = 1; i + 1 < table.size(); ++i)
    if (table[i].second >= 0.5 * best && table[i].second >= table[i - 1].second &&
        table[i].second >= table[i + 1].second)
      step = table[i].first;
  double refined = step, refined_r = resultant(step);
  for (int i = -100; i <= 100; ++i) {
    const double q = step * (1 + 0.005 * i / 100);
    const double r = resultant(q);
    if (r > refined_r) refined = q, refined_r = r;
  }
  *strength = refined_r;
  return refined;
}

void FitEffect(const FitContext& ctx, EffectKind kind, CandidateWork& w) {
  const TransferFunction& g0 = *ctx.g0;
  const std::vector<GapRecord>& estimation = *ctx.estimation;
  const std::vector<GapRecord>& validation = *ctx.validation;
  const GapOptions& options = *ctx.options;
  const Scales& scales = ctx.scales;
  const long n_est = ctx.n_est;
  const double q_step = ctx.q_step, q_strength = ctx.q_strength;
  const Eigen::VectorXd& refit_x = ctx.refit_fit.x;
  const Eigen::VectorXd zero_plant = Eigen::VectorXd::Zero(ctx.refit_size);
  CandidateFit& c = w.fit;
  // Sub-variants fixed before the fit: |y| for the sensor, the step for quantisation.
  std::vector<std::vector<double>> variants = {{}};
  if (kind == EffectKind::kSensorNonlinearity) variants = {{}, {1.0}};
  if (kind == EffectKind::kOutputQuantization) variants = {{q_step}};
  double best_criterion = std::numeric_limits<double>::infinity();
  for (const auto& fixed : variants) {
    Candidate cand(g0, kind, true, scales, options.substeps, fixed);
    Residuals residuals{&cand, &estimation, n_est};
    FitOutcome best;
    int evaluations = 0;
    // Starts: the plant as given (right when the effect is the whole gap) and as refitted
    // (which has already absorbed what a linear refit can), times the effect's starts.
    for (const Eigen::VectorXd* plant_start : {&refit_x, &zero_plant})
      for (const auto& start : Starts(kind, scales)) {
        Eigen::VectorXd x0(cand.Size());
        x0.head(cand.PlantParams()) = *plant_start;
        if (cand.EffectParams() > 0) x0.tail(cand.EffectParams()) = cand.Phi(start);
        FitOutcome f = Minimise(residuals, x0, options.evaluations_per_start * (cand.Size() + 1));
        evaluations += f.evaluations;
        if (!(f.mse >= best.mse)) best = f;  // also takes the first (best.mse is NaN)
      }
    FitOutcome polished =
        Minimise(residuals, best.x, options.evaluations_polish * (cand.Size() + 1));
    evaluations += polished.evaluations;
    if (polished.mse < best.mse) best = polished;
    const double criterion = n_est * std::log(best.mse) + cand.Size() * std::log(double(n_est));
    if (criterion < best_criterion) {
      best_criterion = criterion;
      c.effect = cand.EffectOf(best.x);
      c.plant = cand.Plant(best.x);
      c.parameters = cand.Size();
      c.estimation_mse = best.mse;
      w.y_val = Stack(validation, [&](const GapRecord& r) { return cand.Simulate(best.x, r); });
      // Linearised 1σ of the effect parameters: σ̂²(JᵀJ)⁻¹ in φ, mapped through dp/dφ.
      c.param_std.assign(EffectParameterNames(kind).size(), kNan);
      if (cand.EffectParams() > 0) {
        int calls = 0;
        LmFunctor functor{residuals, cand.Size(), &calls};
        Eigen::NumericalDiff<LmFunctor> numeric(functor);
        Eigen::MatrixXd jac(n_est, cand.Size());
        numeric.df(best.x, jac);
        evaluations += calls;
        const Eigen::MatrixXd info = jac.transpose() * jac;
        const Eigen::MatrixXd cov =
            best.mse * info.completeOrthogonalDecomposition().pseudoInverse();
        for (int j = 0; j < cand.EffectParams(); ++j) {
          const int col = cand.PlantParams() + j;
          Eigen::VectorXd bumped = best.x;
          const double h = 1e-6 * std::max(1.0, std::abs(bumped(col)));
          bumped(col) += h;
          const Effect lo = cand.EffectOf(best.x), hi = cand.EffectOf(bumped);
          const double sd = std::sqrt(std::max(0.0, cov(col, col)));
          for (size_t p = 0; p < lo.params.size(); ++p) {
            const double dp = (hi.params[p] - lo.params[p]) / h;
            if (dp != 0) c.param_std[p] = std::abs(dp) * sd;
          }
        }
      }
    }
    c.evaluations += evaluations;
  }
  if (kind == EffectKind::kOutputQuantization)
    c.note = "step from the samples' lattice, strength R = " + std::to_string(q_strength);
}

}  // namespace idrig::gap_detail
