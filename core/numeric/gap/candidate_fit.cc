// Attribution part of the gap diagnosis (see gap_diagnosis.h); localisation is gap_where.cc.
#include "core/numeric/gap/gap_diagnosis.h"

#include <unsupported/Eigen/MatrixFunctions>
#include <unsupported/Eigen/NonLinearOptimization>
#include <unsupported/Eigen/NumericalDiff>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <thread>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "core/numeric/validation.h"

namespace idrig {
namespace {

[[noreturn]] void Fail(const std::string& message) {
  throw std::invalid_argument("gap diagnosis: " + message);
}

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------------------------------------
// Input checks and the continuous sim model.

void CheckRecords(const std::vector<GapRecord>& records, const std::string& what, double ts,
                  int min_samples) {
  for (size_t r = 0; r < records.size(); ++r) {
    const GapRecord& rec = records[r];
    const std::string name = what + " record " + std::to_string(r + 1);
    if (rec.u.size() != rec.y.size())
      Fail(name + ": u has " + std::to_string(rec.u.size()) + " samples but y has " +
           std::to_string(rec.y.size()));
    for (long k = 0; k < rec.u.size(); ++k)
      if (!std::isfinite(rec.u(k)) || !std::isfinite(rec.y(k)))
        Fail(name + ": sample " + std::to_string(k + 1) + " is NaN or Inf");
    if (rec.u.size() - rec.score_from < min_samples)
      Fail(name + ": " + std::to_string(rec.u.size() - rec.score_from) +
           " samples are too few for the sim model (need at least " + std::to_string(min_samples) +
           ")");
    if (std::abs(rec.sample_time - ts) > 1e-9 * ts)
      Fail(name + ": sample time " + std::to_string(rec.sample_time) + " s differs from " +
           std::to_string(ts) + " s of the first record");
    if (rec.u.maxCoeff() - rec.u.minCoeff() <= 1e-12 * std::max(1.0, rec.u.cwiseAbs().maxCoeff()))
      Fail(name + ": the input is constant, so it carries no information about the gap");
  }
}

TransferFunction ContinuousSimModel(const TransferFunction& sim, double ts) {
  Validate(sim);
  if (sim.num.size() > sim.den.size()) Fail("the sim model is improper (num order > den order)");
  if (!sim.IsDiscrete()) return Normalized(sim);
  if (std::abs(sim.sample_time - ts) > 1e-9 * ts)
    Fail("the sim model is discrete with Ts = " + std::to_string(sim.sample_time) +
         " s but the data's sample time is " + std::to_string(ts) +
         " s; give a continuous model or one sampled at the data's rate");
  TransferFunction undelayed = sim;
  undelayed.delay_s = 0;
  const StateSpace d = ToStateSpace(undelayed);
  const int n = d.Order();
  const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(n, n);
  const Eigen::VectorXcd poles = d.A.eigenvalues();
  for (int i = 0; i < poles.size(); ++i)
    if (std::abs(poles(i).imag()) < 1e-9 * std::max(1.0, std::abs(poles(i))) && poles(i).real() <= 1e-9)
      Fail("the discrete sim model has a pole at z = " + std::to_string(poles(i).real()) +
           " on the non-positive real axis, so it has no continuous equivalent; give a continuous "
           "model (or identify one of lower order)");
  if (std::abs((d.A - identity).determinant()) < 1e-12)
    Fail("the discrete sim model has a pole at z = 1; give a continuous model");
  StateSpace c = d;
  c.A = d.A.log() / ts;
  c.B = (d.A - identity).partialPivLu().solve(c.A * d.B);
  c.sample_time = 0;
  TransferFunction tf = Normalized(ToTransferFunction(c));
  tf.delay_s = sim.delay_s;
  return tf;
}

// Slowest time constant of the plant [s] (from its poles), for scaling lags and delays.
double SlowTimeConstant(const TransferFunction& plant, double ts, double duration) {
  double slow = 0;
  const Eigen::VectorXcd p = Poles(plant);
  for (int i = 0; i < p.size(); ++i)
    if (std::abs(p(i)) > 1e-9) slow = std::max(slow, 1.0 / std::abs(p(i)));
  if (slow == 0) slow = duration / 10;
  return std::clamp(slow, 2 * ts, duration);
}

// ---------------------------------------------------------------------------------------------
// One candidate: the plant's free coefficients θ (log multipliers) and the effect's φ.

struct Scales {
  double ts = 1, slow = 1, u_max = 1, y_max = 1;
  double lag_of_best_match = 0;  // [s] shift of G0's output that best matches y (cross-correlation)
  double u_quantile[5] = {0, 0, 0, 0, 0};  // 2, 15, 50, 85, 98 %
  double y_quantile[4] = {0, 0, 0, 0};     // 0.5, 2, 98, 99.5 %
};

double Quantile(std::vector<double> v, double p) {
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(p * (v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

class Candidate {
 public:
  Candidate(const TransferFunction& base, EffectKind kind, bool fit_plant, const Scales& scales,
            int substeps, std::vector<double> fixed = {})
      : base_(base), kind_(kind), scales_(scales), substeps_(substeps), fixed_(std::move(fixed)) {
    if (fit_plant) {
      for (int i = 1; i < base.den.size(); ++i)
        if (base.den(i) != 0) free_den_.push_back(i);
      for (int i = 0; i < base.num.size(); ++i)
        if (base.num(i) != 0) free_num_.push_back(i);
    }
    effect_params_ = NumEffectParams(kind, fixed_);
  }

  static int NumEffectParams(EffectKind kind, const std::vector<double>& fixed) {
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

  int PlantParams() const {
    return static_cast<int>(free_den_.size() + free_num_.size()) + (gain_only_ ? 1 : 0);
  }
  // Only the plant's gain moves (one multiplier on num): a gap that is a pure gain change.
  void SetGainOnly() {
    free_den_.clear();
    free_num_.clear();
    gain_only_ = true;
  }
  int EffectParams() const { return effect_params_; }
  int Size() const { return PlantParams() + EffectParams(); }

  TransferFunction Plant(const Eigen::VectorXd& x) const {
    TransferFunction g = base_;
    int j = 0;
    for (int i : free_den_) g.den(i) *= std::exp(std::clamp(x(j++), -20.0, 20.0));
    for (int i : free_num_) g.num(i) *= std::exp(std::clamp(x(j++), -20.0, 20.0));
    if (gain_only_) g.num *= std::exp(std::clamp(x(j++), -20.0, 20.0));
    return g;
  }

  // φ → physical parameters, in EffectParameterNames order.
  Effect EffectOf(const Eigen::VectorXd& x) const {
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

  // Inverse of EffectOf for the effect part, for starting points given in physical units.
  Eigen::VectorXd Phi(const std::vector<double>& p) const {
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

  Eigen::VectorXd Simulate(const Eigen::VectorXd& x, const GapRecord& record) const {
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

  EffectKind kind() const { return kind_; }

 private:
  TransferFunction base_;
  EffectKind kind_;
  Scales scales_;
  int substeps_;
  std::vector<double> fixed_;
  std::vector<int> free_den_, free_num_;
  bool gain_only_ = false;
  int effect_params_ = 0;
};

// Residuals y − ŷ over the scored samples of every record, as one vector.
struct Residuals {
  const Candidate* candidate;
  const std::vector<GapRecord>* records;
  long count = 0;

  void operator()(const Eigen::VectorXd& x, Eigen::VectorXd& r) const {
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
};

struct LmFunctor {
  using Scalar = double;
  enum { InputsAtCompileTime = Eigen::Dynamic, ValuesAtCompileTime = Eigen::Dynamic };
  using InputType = Eigen::VectorXd;
  using ValueType = Eigen::VectorXd;
  using JacobianType = Eigen::MatrixXd;
  Residuals residuals;
  int n_inputs = 0;
  int* calls = nullptr;
  int inputs() const { return n_inputs; }
  int values() const { return static_cast<int>(residuals.count); }
  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& f) const {
    ++*calls;
    residuals(x, f);
    return 0;
  }
};

double Mse(const Residuals& residuals, const Eigen::VectorXd& x) {
  Eigen::VectorXd r(residuals.count);
  residuals(x, r);
  return r.squaredNorm() / std::max<long>(1, residuals.count);
}

struct FitOutcome {
  Eigen::VectorXd x;
  double mse = kNan;
  int evaluations = 0;
  bool converged = false;
};

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

// Every sample within 2 % of the range from the minimum or the maximum.
bool BinaryInput(const std::vector<GapRecord>& records) {
  for (const auto& r : records) {
    const double lo = r.u.minCoeff(), hi = r.u.maxCoeff(), tol = 0.02 * (hi - lo);
    for (long k = r.score_from; k < r.u.size(); ++k)
      if (std::abs(r.u(k) - lo) > tol && std::abs(r.u(k) - hi) > tol) return false;
  }
  return true;
}

double Correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::VectorXd ac = a.array() - a.mean(), bc = b.array() - b.mean();
  const double d = ac.norm() * bc.norm();
  return d > 0 ? ac.dot(bc) / d : 0.0;
}

// Simulation over the scored samples of every record, concatenated.
Eigen::VectorXd Stack(const std::vector<GapRecord>& records,
                      const std::function<Eigen::VectorXd(const GapRecord&)>& f) {
  long total = 0;
  for (const auto& r : records) total += r.u.size() - r.score_from;
  Eigen::VectorXd out(total);
  long offset = 0;
  for (const auto& r : records) {
    const long n = r.u.size() - r.score_from;
    out.segment(offset, n) = f(r).tail(n);
    offset += n;
  }
  return out;
}

}  // namespace

TransferFunction SimModelTransferFunction(const LtiModel& model) {
  if (const auto* tf = std::get_if<TransferFunction>(&model)) return *tf;
  const StateSpace& ss = std::get<StateSpace>(model);
  if (ss.NumInputs() != 1 || ss.NumOutputs() != 1)
    Fail("the sim model must be SISO; it has " + std::to_string(ss.NumInputs()) + " inputs and " +
         std::to_string(ss.NumOutputs()) + " outputs");
  TransferFunction tf = ToTransferFunction(ss);
  tf.delay_s = ss.delay_s;
  return tf;
}

GapRecord ToGapRecord(const IoRecord& record) {
  if (record.NumInputs() != 1 || record.NumOutputs() != 1)
    Fail("the records must be SISO (t,u,y); this one has " + std::to_string(record.NumInputs()) +
         " inputs and " + std::to_string(record.NumOutputs()) + " outputs");
  GapRecord r;
  r.u = record.u.col(0);
  r.y = record.y.col(0);
  r.sample_time = record.sample_time;
  return r;
}

void SplitRecord(const GapRecord& record, std::vector<GapRecord>& estimation,
                 std::vector<GapRecord>& validation) {
  const long n = record.u.size();
  const long half = n / 2;
  GapRecord est = record;
  est.u = record.u.head(half);
  est.y = record.y.head(half);
  est.score_from = 0;
  GapRecord val = record;
  val.score_from = static_cast<int>(half);
  estimation.push_back(est);
  validation.push_back(val);
}

GapReport DiagnoseGap(const TransferFunction& sim_model, const std::vector<GapRecord>& estimation_in,
                      const std::vector<GapRecord>& validation_in, const GapOptions& options) {
  if (estimation_in.empty()) Fail("no estimation records");
  const double ts = estimation_in.front().sample_time;
  if (!(ts > 0)) Fail("the records' sample time must be positive");
  const TransferFunction g0 = ContinuousSimModel(sim_model, ts);
  const int order = g0.Order();
  const int min_samples = std::max(20, 10 * (order + 4));

  GapReport report;
  std::vector<GapRecord> estimation, validation;
  if (validation_in.empty()) {
    if (estimation_in.size() == 1) {
      if (estimation_in.front().u.size() < 2 * min_samples)
        Fail("the record has " + std::to_string(estimation_in.front().u.size()) +
             " samples: too short to split into estimation and validation halves (need " +
             std::to_string(2 * min_samples) + ")");
      SplitRecord(estimation_in.front(), estimation, validation);
      report.notes.push_back(
          "one record and no validation record: estimation on the first half, validation on the "
          "second half (simulated through the first half to carry the state)");
    } else {
      estimation.assign(estimation_in.begin(), estimation_in.end() - 1);
      validation.push_back(estimation_in.back());
      report.notes.push_back("no validation record: the last estimation record is held out");
    }
  } else {
    estimation = estimation_in;
    validation = validation_in;
  }
  CheckRecords(estimation, "estimation", ts, min_samples);
  CheckRecords(validation, "validation", ts, min_samples);

  Scales scales;
  scales.ts = ts;
  std::vector<double> all_u, all_y;
  double duration = 0;
  for (const auto& r : estimation) {
    all_u.insert(all_u.end(), r.u.data(), r.u.data() + r.u.size());
    all_y.insert(all_y.end(), r.y.data(), r.y.data() + r.y.size());
    duration = std::max(duration, r.u.size() * ts);
  }
  scales.slow = SlowTimeConstant(g0, ts, duration);
  scales.u_max = std::max(1e-12, std::max(std::abs(*std::max_element(all_u.begin(), all_u.end())),
                                          std::abs(*std::min_element(all_u.begin(), all_u.end()))));
  scales.y_max = std::max(1e-12, std::max(std::abs(*std::max_element(all_y.begin(), all_y.end())),
                                          std::abs(*std::min_element(all_y.begin(), all_y.end()))));
  const double uq[5] = {0.02, 0.15, 0.5, 0.85, 0.98};
  for (int i = 0; i < 5; ++i) scales.u_quantile[i] = Quantile(all_u, uq[i]);
  const double yq[4] = {0.005, 0.02, 0.98, 0.995};
  for (int i = 0; i < 4; ++i) scales.y_quantile[i] = Quantile(all_y, yq[i]);

  long n_est = 0, n_val = 0;
  for (const auto& r : estimation) n_est += r.u.size() - r.score_from;
  for (const auto& r : validation) n_val += r.u.size() - r.score_from;
  report.estimation_samples = static_cast<int>(n_est);
  report.validation_samples = static_cast<int>(n_val);

  const std::vector<EffectKind> kinds = options.candidates.empty() ? AllEffects() : options.candidates;
  const Eigen::VectorXd y_val = Stack(validation, [](const GapRecord& r) { return r.y; });

  // G0 as given, and G0 refitted (parameter_mismatch): the references for every effect.
  Candidate as_is(g0, EffectKind::kNone, false, scales, options.substeps);
  const Eigen::VectorXd no_params(0);
  const Eigen::VectorXd y0_val =
      Stack(validation, [&](const GapRecord& r) { return as_is.Simulate(no_params, r); });

  const double as_is_mse = Mse(Residuals{&as_is, &estimation, n_est}, no_params);
  Candidate refit(g0, EffectKind::kParameterMismatch, true, scales, options.substeps);
  Residuals refit_residuals{&refit, &estimation, n_est};
  const FitOutcome refit_fit = Minimise(refit_residuals, Eigen::VectorXd::Zero(refit.Size()),
                                        options.evaluations_polish * (refit.Size() + 1));
  const Eigen::VectorXd y_refit_val =
      Stack(validation, [&](const GapRecord& r) { return refit.Simulate(refit_fit.x, r); });

  const Eigen::VectorXd zero_plant = Eigen::VectorXd::Zero(refit.Size());
  {
    // Lag that best aligns G0's output with the measured one (a delay's natural start).
    const GapRecord& first = estimation.front();
    const Eigen::VectorXd y0 = as_is.Simulate(no_params, first);
    const long n = first.y.size();
    const long max_lag = std::min<long>(n / 4, static_cast<long>(10 * scales.slow / ts) + 1);
    double best = -INFINITY;
    for (long lag = 0; lag <= max_lag; ++lag) {
      const double c = first.y.tail(n - lag).dot(y0.head(n - lag)) / std::sqrt(double(n - lag));
      if (c > best) best = c, scales.lag_of_best_match = lag * ts;
    }
  }
  double q_strength = 0;
  const double q_step = QuantisationStep(estimation, &q_strength);

  struct Work {
    CandidateFit fit;
    Eigen::VectorXd y_val;
  };
  const int k_effects = std::max<int>(1, static_cast<int>(kinds.size()) - 2);
  auto fit_one = [&](EffectKind kind) {
    Work w;
    CandidateFit& c = w.fit;
    if (kind == EffectKind::kNone) {
      c.effect.kind = kind;
      c.plant = g0;
      c.estimation_mse = as_is_mse;
      w.y_val = y0_val;
      c.significant = true;
    } else if (kind == EffectKind::kParameterMismatch) {
      c.effect = refit.EffectOf(refit_fit.x);
      c.plant = refit.Plant(refit_fit.x);
      c.parameters = refit.Size();
      c.estimation_mse = refit_fit.mse;
      c.evaluations = refit_fit.evaluations;
      w.y_val = y_refit_val;
    } else {
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
        for (const Eigen::VectorXd* plant_start : {&refit_fit.x, &zero_plant})
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
    // Likelihood ratio on the estimation records (Wilks): the effect against the refitted G0,
    // the refitted G0 against G0, each at the Bonferroni-corrected level.
    if (kind != EffectKind::kNone) {
      const double reference = kind == EffectKind::kParameterMismatch ? as_is_mse : refit_fit.mse;
      const int dof = kind == EffectKind::kParameterMismatch
                          ? std::max(1, c.parameters)
                          : std::max(1, c.parameters - refit.Size());
      const double level = kind == EffectKind::kParameterMismatch ? options.significance
                                                                  : options.significance / k_effects;
      c.likelihood_ratio = n_est * std::log(reference / std::max(c.estimation_mse, 1e-300));
      c.lr_threshold = ChiSquareQuantile(1 - level, dof);
      c.significant = c.likelihood_ratio > c.lr_threshold;
    }
    c.validation_mse = (y_val - w.y_val).squaredNorm() / n_val;
    c.nrmse_after = Nrmse(y_val, w.y_val)(0);
    c.bic = n_val * std::log(std::max(c.validation_mse, 1e-300)) + c.parameters * std::log(double(n_est));
    if (kind == EffectKind::kNone) {
      c.signature = 1;
    } else if (kind == EffectKind::kParameterMismatch) {
      c.signature = Correlation(w.y_val - y0_val, y_val - y0_val);
    } else {
      c.signature = Correlation(w.y_val - y_refit_val, y_val - y_refit_val);
    }
    return w;
  };
  // The candidates are independent: fit them on `threads` threads (results do not depend on
  // the schedule; each candidate is fitted deterministically).
  std::vector<Work> work(kinds.size());
  {
    const int threads = std::max(1, std::min<int>(static_cast<int>(kinds.size()),
                                                  options.threads > 0 ? options.threads
                                                                      : static_cast<int>(std::thread::hardware_concurrency())));
    std::atomic<size_t> next{0};
    std::vector<std::string> errors(kinds.size());
    auto run = [&] {
      for (size_t i = next++; i < kinds.size(); i = next++) {
        try {
          work[i] = fit_one(kinds[i]);
        } catch (const std::exception& e) {
          errors[i] = e.what();
        }
      }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(run);
    run();
    for (auto& t : pool) t.join();
    for (size_t i = 0; i < kinds.size(); ++i)
      if (!errors[i].empty())
        throw std::invalid_argument(std::string("gap diagnosis: fitting ") + EffectName(kinds[i]) +
                                    " failed: " + errors[i]);
  }

  // Eligibility: an effect must beat the refitted G0 significantly and reproduce the gap's
  // signature; parameter_mismatch must beat G0; none is always eligible.
  for (auto& w : work) {
    CandidateFit& c = w.fit;
    if (c.effect.kind == EffectKind::kNone) c.eligible = true;
    else if (c.effect.kind == EffectKind::kParameterMismatch) c.eligible = c.significant;
    else c.eligible = c.significant && c.signature >= options.min_signature;
  }
  std::sort(work.begin(), work.end(), [](const Work& a, const Work& b) {
    if (a.fit.eligible != b.fit.eligible) return a.fit.eligible;
    return a.fit.bic < b.fit.bic;
  });
  const double best_bic = work.front().fit.bic;
  double total = 0;
  for (auto& w : work)
    if (w.fit.eligible) total += std::exp(-0.5 * (w.fit.bic - best_bic));
  for (auto& w : work) {
    w.fit.score = w.fit.eligible ? std::exp(-0.5 * (w.fit.bic - best_bic)) / total : 0.0;
    report.ranking.push_back(w.fit);
  }

  // Noise floor: the smallest estimation residual among the candidates.
  double noise_mse = std::numeric_limits<double>::infinity();
  for (const auto& c : report.ranking) noise_mse = std::min(noise_mse, c.estimation_mse);
  const double y_val_spread = (y_val.array() - y_val.mean()).matrix().norm() / std::sqrt(double(n_val));

  const CandidateFit& top = report.ranking.front();
  GapVerdict& v = report.verdict;
  v.effect = EffectName(top.effect.kind);
  v.confidence = top.score;
  v.params = top.effect;
  v.param_std = top.param_std;
  v.plant = top.plant;
  v.nrmse_before = Nrmse(y_val, y0_val)(0);
  v.nrmse_after = top.nrmse_after;
  const double noise_nrmse = std::sqrt(noise_mse) / std::max(y_val_spread, 1e-300);
  const double explainable = v.nrmse_before - noise_nrmse;
  v.shrink = explainable > 0 ? (v.nrmse_before - v.nrmse_after) / explainable : 0.0;
  if (report.ranking.size() > 1 && report.ranking[1].eligible &&
      report.ranking[1].bic - top.bic < options.ambiguity_bic) {
    v.effect = "ambiguous";
    v.tied = {EffectName(top.effect.kind), EffectName(report.ranking[1].effect.kind)};
  }
  // A two-valued input (PRBS, random binary) passes a dead zone, backlash or a symmetric
  // saturation as a mere gain: when the gap is a pure gain change, those cannot be told from a
  // parameter mismatch with this data.
  if (v.effect == "parameter_mismatch" && BinaryInput(estimation) && BinaryInput(validation)) {
    Candidate gain(g0, EffectKind::kParameterMismatch, true, scales, options.substeps);
    gain.SetGainOnly();
    Residuals gain_residuals{&gain, &estimation, n_est};
    const FitOutcome gain_fit = Minimise(gain_residuals, Eigen::VectorXd::Zero(1), 200);
    const double lr = n_est * std::log(gain_fit.mse / refit_fit.mse);
    const int dof = std::max(1, refit.Size() - 1);
    if (lr < ChiSquareQuantile(1 - options.significance, dof)) {
      v.effect = "ambiguous";
      v.tied = {"parameter_mismatch", "dead_zone", "backlash", "input_saturation"};
      v.confidence = 1.0 / v.tied.size();  // nothing in the data prefers one of them
      report.notes.push_back(
          "the input takes two values only, and the gap is a pure gain change (gain-only refit "
          "not worse: LR " + std::to_string(lr) + "): input dead zone, backlash and symmetric "
          "saturation act as a gain on such a signal and cannot be told from a parameter "
          "mismatch; excite at several amplitudes to separate them");
    }
  }
  if (v.effect == "none")
    v.explanation = "no candidate explains the gap better than noise: G0 fits within the noise";
  else if (v.effect == "ambiguous")
    v.explanation = "the top candidates (" + v.tied[0] + ", " + v.tied[1] +
                    (v.tied.size() > 2 ? ", …" : "") +
                    ") fit the validation data equally well; more informative data would separate them";
  else
    v.explanation = v.effect + " closes " + std::to_string(int(std::round(100 * v.shrink))) +
                    " % of the explainable gap on the validation records";

  report.where = LocateGap(g0, validation, std::sqrt(noise_mse));
  report.where.noise_nrmse = noise_nrmse;
  return report;
}

}  // namespace idrig
