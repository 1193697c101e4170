#include "core/numeric/effects.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace idrig {
namespace {

[[noreturn]] void Fail(const std::string& message) { throw std::invalid_argument(message); }

struct EffectEntry {
  EffectKind kind;
  const char* name;
  std::vector<std::string> params;
};

const std::vector<EffectEntry>& Entries() {
  static const std::vector<EffectEntry> entries = {
      {EffectKind::kNone, "none", {}},
      {EffectKind::kParameterMismatch, "parameter_mismatch", {}},
      {EffectKind::kTimeDelay, "time_delay", {"tau_s"}},
      {EffectKind::kActuatorLag, "actuator_lag", {"T_s"}},
      {EffectKind::kUnmodelledResonance, "unmodelled_resonance", {"omega_rad_s", "zeta"}},
      {EffectKind::kInputSaturation, "input_saturation", {"u_lo", "u_hi"}},
      {EffectKind::kDeadZone, "dead_zone", {"d"}},
      {EffectKind::kBacklash, "backlash", {"r"}},
      {EffectKind::kCoulombFriction, "coulomb_friction", {"F_c"}},
      {EffectKind::kCubicStiffness, "cubic_stiffness", {"k3"}},
      {EffectKind::kOutputSaturation, "output_saturation", {"y_lo", "y_hi"}},
      {EffectKind::kSensorNonlinearity, "sensor_nonlinearity", {"a1", "a2", "a3", "absolute"}},
      {EffectKind::kOutputQuantization, "output_quantization", {"q"}},
  };
  return entries;
}

const EffectEntry& Entry(EffectKind kind) {
  for (const auto& e : Entries())
    if (e.kind == kind) return e;
  Fail("unknown effect kind");
}

// A SISO plant sampled under ZOH at step h: x+ = A x + B u, y = C x + D u, whole-sample delay.
struct SampledPlant {
  Eigen::MatrixXd A;
  Eigen::VectorXd B;
  Eigen::RowVectorXd C;
  double D = 0.0;
  long delay = 0;
};

SampledPlant Sample(const TransferFunction& plant, double step) {
  const StateSpace d = DiscretizeZoh(ToStateSpace(plant), step);
  SampledPlant s;
  s.A = d.A;
  s.B = d.B.col(0);
  s.C = d.C.row(0);
  s.D = d.D(0, 0);
  s.delay = std::lround(d.delay_s / step);
  return s;
}

Eigen::VectorXd SimulateLinear(const SampledPlant& p, const Eigen::VectorXd& u) {
  const long n = u.size();
  Eigen::VectorXd y(n);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(p.A.rows()), next(p.A.rows());
  for (long k = 0; k < n; ++k) {
    const double uk = k - p.delay >= 0 ? u(k - p.delay) : 0.0;
    y(k) = p.C.dot(x) + p.D * uk;
    next.noalias() = p.A * x;
    next += p.B * uk;
    x.swap(next);
  }
  return y;
}

double Sign(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0); }

// Friction and cubic stiffness act in feedback: u_eff depends on the plant's own state.
Eigen::VectorXd SimulateFeedback(const TransferFunction& plant, const Effect& effect,
                                 const Eigen::VectorXd& u, double sample_time, int substeps) {
  TransferFunction undelayed = plant;
  undelayed.delay_s = 0.0;
  const StateSpace c = ToStateSpace(undelayed);
  const double h = sample_time / substeps;
  const SampledPlant p = Sample(undelayed, h);
  const long delay = std::lround(plant.delay_s / sample_time);
  const Eigen::RowVectorXd ca = c.C.row(0) * c.A;
  const double cb = (c.C.row(0) * c.B.col(0))(0, 0);
  const double gain = effect.params[0];
  const bool friction = effect.kind == EffectKind::kCoulombFriction;
  const long n = u.size();
  Eigen::VectorXd y(n);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(p.A.rows()), next(p.A.rows());
  for (long k = 0; k < n; ++k) {
    const double uk = k - delay >= 0 ? u(k - delay) : 0.0;
    for (int j = 0; j < substeps; ++j) {
      double u_eff;
      if (friction) {
        const double velocity = ca.dot(x) + cb * uk;  // dy/dt from the continuous state
        u_eff = uk - gain * Sign(velocity);
      } else {
        const double position = p.C.dot(x) + p.D * uk;
        u_eff = uk - gain * position * position * position;
      }
      if (j == 0) y(k) = p.C.dot(x) + p.D * u_eff;
      next.noalias() = p.A * x;
      next += p.B * u_eff;
      x.swap(next);
    }
    if (!std::isfinite(y(k))) {  // a diverging (e.g. softening) loop: stop, report as is
      y.tail(n - k).setConstant(y(k));
      break;
    }
  }
  return y;
}

}  // namespace

const std::vector<EffectKind>& AllEffects() {
  static const std::vector<EffectKind> all = [] {
    std::vector<EffectKind> kinds;
    for (const auto& e : Entries()) kinds.push_back(e.kind);
    return kinds;
  }();
  return all;
}

const char* EffectName(EffectKind kind) { return Entry(kind).name; }

EffectKind EffectFromName(const std::string& name) {
  std::string known;
  for (const auto& e : Entries()) {
    if (name == e.name) return e.kind;
    known += (known.empty() ? "" : ", ") + std::string(e.name);
  }
  Fail("unknown effect '" + name + "'; known effects: " + known);
}

const std::vector<std::string>& EffectParameterNames(EffectKind kind) { return Entry(kind).params; }

bool IsLinearEffect(EffectKind kind) {
  return kind == EffectKind::kTimeDelay || kind == EffectKind::kActuatorLag ||
         kind == EffectKind::kUnmodelledResonance;
}

bool IsFeedbackEffect(EffectKind kind) {
  return kind == EffectKind::kCoulombFriction || kind == EffectKind::kCubicStiffness;
}

void ValidateEffect(const Effect& effect) {
  const auto& names = EffectParameterNames(effect.kind);
  const std::string what = std::string("effect ") + EffectName(effect.kind);
  if (effect.params.size() != names.size())
    Fail(what + " takes " + std::to_string(names.size()) + " parameters, got " +
         std::to_string(effect.params.size()));
  for (size_t i = 0; i < names.size(); ++i)
    if (!std::isfinite(effect.params[i])) Fail(what + ": parameter " + names[i] + " is not finite");
  const auto& p = effect.params;
  switch (effect.kind) {
    case EffectKind::kTimeDelay:
      if (p[0] < 0) Fail(what + ": tau_s must be >= 0");
      break;
    case EffectKind::kActuatorLag:
      if (p[0] < 0) Fail(what + ": T_s must be >= 0");
      break;
    case EffectKind::kUnmodelledResonance:
      if (p[0] <= 0 || p[1] <= 0) Fail(what + ": omega_rad_s and zeta must be > 0");
      break;
    case EffectKind::kInputSaturation:
    case EffectKind::kOutputSaturation:
      if (!(p[0] < p[1])) Fail(what + ": the lower limit must be below the upper limit");
      break;
    case EffectKind::kDeadZone:
    case EffectKind::kBacklash:
    case EffectKind::kCoulombFriction:
      if (p[0] < 0) Fail(what + ": " + names[0] + " must be >= 0");
      break;
    case EffectKind::kOutputQuantization:
      if (p[0] <= 0) Fail(what + ": q must be > 0");
      break;
    default:
      break;
  }
}

TransferFunction ApplyLinearEffect(const TransferFunction& plant, const Effect& effect) {
  TransferFunction g = plant;
  const auto& p = effect.params;
  auto multiply_den = [&g](const Eigen::VectorXd& factor) {
    Eigen::VectorXd den = Eigen::VectorXd::Zero(g.den.size() + factor.size() - 1);
    for (int i = 0; i < g.den.size(); ++i)
      for (int j = 0; j < factor.size(); ++j) den(i + j) += g.den(i) * factor(j);
    g.den = den;
  };
  switch (effect.kind) {
    case EffectKind::kTimeDelay:
      g.delay_s += p[0];
      break;
    case EffectKind::kActuatorLag:
      if (p[0] > 0) multiply_den(Eigen::Vector2d(p[0], 1.0));  // 1/(T s + 1)
      break;
    case EffectKind::kUnmodelledResonance: {
      const double w = p[0], z = p[1];
      multiply_den(Eigen::Vector3d(1.0, 2.0 * z * w, w * w));  // ω²/(s² + 2ζωs + ω²)
      g.num *= w * w;
      break;
    }
    default:
      break;
  }
  return g;
}

double DeadZone(double u, double width) { return Sign(u) * std::max(std::abs(u) - width, 0.0); }

Eigen::VectorXd Backlash(const Eigen::VectorXd& u, double half_width) {
  Eigen::VectorXd w(u.size());
  double previous = 0.0;
  for (long k = 0; k < u.size(); ++k) {
    previous = std::max(u(k) - half_width, std::min(u(k) + half_width, previous));
    w(k) = previous;
  }
  return w;
}

double SensorMap(double y, const std::vector<double>& p) {
  if (p[3] != 0.0) return p[0] * std::abs(y);
  return y * (p[0] + y * (p[1] + y * p[2]));
}

Eigen::VectorXd SimulateWithEffect(const TransferFunction& plant, const Effect& effect,
                                   const Eigen::VectorXd& u, double sample_time,
                                   const EffectSimulationOptions& options) {
  Validate(plant);
  ValidateEffect(effect);
  if (plant.IsDiscrete()) Fail("effect simulation needs a continuous plant");
  if (!(sample_time > 0.0)) Fail("effect simulation: sample time must be positive");
  if (!u.allFinite()) Fail("effect simulation: input contains NaN or Inf");
  if (options.substeps < 1) Fail("effect simulation: substeps must be >= 1");
  const auto& p = effect.params;
  if (IsFeedbackEffect(effect.kind))
    return SimulateFeedback(Normalized(plant), effect, u, sample_time, options.substeps);

  const SampledPlant sampled = Sample(ApplyLinearEffect(plant, effect), sample_time);
  Eigen::VectorXd input = u;
  switch (effect.kind) {
    case EffectKind::kInputSaturation:
      input = u.cwiseMax(p[0]).cwiseMin(p[1]);
      break;
    case EffectKind::kDeadZone:
      input = u.unaryExpr([&](double v) { return DeadZone(v, p[0]); });
      break;
    case EffectKind::kBacklash:
      input = Backlash(u, p[0]);
      break;
    default:
      break;
  }
  Eigen::VectorXd y = SimulateLinear(sampled, input);
  switch (effect.kind) {
    case EffectKind::kOutputSaturation:
      y = y.cwiseMax(p[0]).cwiseMin(p[1]);
      break;
    case EffectKind::kSensorNonlinearity:
      y = y.unaryExpr([&](double v) { return SensorMap(v, p); });
      break;
    case EffectKind::kOutputQuantization:
      y = y.unaryExpr([&](double v) { return p[0] * std::round(v / p[0]); });
      break;
    default:
      break;
  }
  return y;
}

}  // namespace idrig
