#include "core/numeric/gap/effects.h"

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

double Sign(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0); }

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

EffectSimulator::EffectSimulator(const TransferFunction& plant, const Effect& effect,
                                 double sample_time, const EffectSimulationOptions& options)
    : EffectSimulator(plant, std::vector<Effect>{effect}, sample_time, options) {}

EffectSimulator::EffectSimulator(const TransferFunction& plant, const std::vector<Effect>& effects,
                                 double sample_time, const EffectSimulationOptions& options)
    : effects_(effects) {
  Validate(plant);
  if (effects_.empty()) effects_.push_back(Effect{});
  for (const Effect& e : effects_) ValidateEffect(e);
  if (plant.IsDiscrete()) Fail("effect simulation needs a continuous plant");
  if (!(sample_time > 0.0)) Fail("effect simulation: sample time must be positive");
  if (options.substeps < 1) Fail("effect simulation: substeps must be >= 1");
  // The linear effects fold into the plant, in series (their order does not matter).
  TransferFunction linear = plant;
  for (const Effect& e : effects_) {
    if (IsLinearEffect(e.kind)) linear = ApplyLinearEffect(linear, e);
    if (IsFeedbackEffect(e.kind)) feedback_ = true;
  }
  if (feedback_) {
    // Friction and cubic stiffness act in feedback: u_eff depends on the plant's own state.
    TransferFunction undelayed = Normalized(linear);
    undelayed.delay_s = 0.0;
    const StateSpace c = ToStateSpace(undelayed);
    substeps_ = options.substeps;
    const SampledPlant p = Sample(undelayed, sample_time / substeps_);
    A_ = p.A;
    B_ = p.B;
    C_ = p.C;
    D_ = p.D;
    velocity_row_ = c.C.row(0) * c.A;
    velocity_input_ = (c.C.row(0) * c.B.col(0))(0, 0);
    // The stick rule needs the force to reach dy/dt within a sub-step: relative degree 1 or 2
    // (C B ≠ 0 or C A B ≠ 0). Behind a further lag (degree ≥ 3) no input can stop the motion in
    // one sub-step, and friction stays F_c·sign(dy/dt).
    const double cab = velocity_row_.dot(c.B.col(0));
    stick_ = velocity_input_ != 0.0 || std::abs(cab) > 1e-9 * velocity_row_.norm() * c.B.col(0).norm();
    delay_ = std::lround(linear.delay_s / sample_time);
  } else {
    const SampledPlant p = Sample(linear, sample_time);
    A_ = p.A;
    B_ = p.B;
    C_ = p.C;
    D_ = p.D;
    delay_ = p.delay;
  }
  Reset();
}

void EffectSimulator::Reset() {
  x_ = Eigen::VectorXd::Zero(A_.rows());
  next_ = Eigen::VectorXd::Zero(A_.rows());
  delay_line_.assign(delay_, 0.0);
  delay_head_ = 0;
  backlash_.assign(effects_.size(), 0.0);
}

// Coulomb friction as a set-valued force (Filippov; Karnopp's discrete stick rule): the force
// f that brings dy/dt to zero at the end of this sub-step, f_stop = u − u_stop with
// u_stop = −(v_row A x)/(v_row B + v_in), is applied when |f_stop| ≤ F_c (the axis stops or stays
// stuck: static = kinetic friction); otherwise F_c·sign(f_stop), which opposes the motion the
// sub-step would give. Unlike F_c·sign(dy/dt) this does not chatter at reversals, so the result
// does not depend on the sub-step (a mass below its breakaway force does not creep). Only where
// the input reaches dy/dt within a sub-step (relative degree ≤ 2, `stick_`).
double EffectSimulator::FrictionForce(double u, double limit) const {
  const double gain = velocity_row_.dot(B_) + velocity_input_;  // ∂(dy/dt)_next / ∂u
  const double free = velocity_row_.dot(A_ * x_);                // (dy/dt)_next at u = 0
  if (!stick_ || !(std::abs(gain) > 1e-300)) return limit * Sign(velocity_row_.dot(x_) + velocity_input_ * u);
  const double stop = u + free / gain;  // u − u_stop
  return std::clamp(stop, -limit, limit);
}

double EffectSimulator::Step(double u) {
  // Input side: static maps and the play operator, in the order given.
  for (size_t i = 0; i < effects_.size(); ++i) {
    const auto& p = effects_[i].params;
    switch (effects_[i].kind) {
      case EffectKind::kInputSaturation: u = std::clamp(u, p[0], p[1]); break;
      case EffectKind::kDeadZone: u = DeadZone(u, p[0]); break;
      case EffectKind::kBacklash:
        backlash_[i] = std::max(u - p[0], std::min(u + p[0], backlash_[i]));
        u = backlash_[i];
        break;
      default: break;
    }
  }
  // Whole-sample delay (a fractional part is in the sampled plant).
  if (delay_ > 0) {
    const double delayed = delay_line_[delay_head_];
    delay_line_[delay_head_] = u;
    delay_head_ = (delay_head_ + 1) % delay_;
    u = delayed;
  }
  double y;
  if (feedback_) {
    y = 0.0;
    for (int j = 0; j < substeps_; ++j) {
      double u_eff = u;
      for (const Effect& e : effects_)
        if (e.kind == EffectKind::kCubicStiffness) {
          const double position = C_.dot(x_) + D_ * u;
          u_eff -= e.params[0] * position * position * position;
        }
      for (const Effect& e : effects_)
        if (e.kind == EffectKind::kCoulombFriction) u_eff -= FrictionForce(u_eff, e.params[0]);
      if (j == 0) y = C_.dot(x_) + D_ * u_eff;
      next_.noalias() = A_ * x_;
      next_ += B_ * u_eff;
      x_.swap(next_);
    }
  } else {
    y = C_.dot(x_) + D_ * u;
    next_.noalias() = A_ * x_;
    next_ += B_ * u;
    x_.swap(next_);
  }
  // Output side, in the order given.
  for (const Effect& e : effects_) {
    const auto& p = e.params;
    switch (e.kind) {
      case EffectKind::kOutputSaturation: y = std::clamp(y, p[0], p[1]); break;
      case EffectKind::kSensorNonlinearity: y = SensorMap(y, p); break;
      case EffectKind::kOutputQuantization: y = p[0] * std::round(y / p[0]); break;
      default: break;
    }
  }
  return y;
}

Eigen::VectorXd SimulateWithEffect(const TransferFunction& plant, const Effect& effect,
                                   const Eigen::VectorXd& u, double sample_time,
                                   const EffectSimulationOptions& options) {
  return SimulateWithEffects(plant, std::vector<Effect>{effect}, u, sample_time, options);
}

Eigen::VectorXd SimulateWithEffects(const TransferFunction& plant, const std::vector<Effect>& effects,
                                    const Eigen::VectorXd& u, double sample_time,
                                    const EffectSimulationOptions& options) {
  if (!u.allFinite()) Fail("effect simulation: input contains NaN or Inf");
  EffectSimulator simulator(plant, effects, sample_time, options);
  Eigen::VectorXd y(u.size());
  for (long k = 0; k < u.size(); ++k) {
    y(k) = simulator.Step(u(k));
    if (!std::isfinite(y(k))) {  // a diverging loop (e.g. softening stiffness): hold, stop
      y.tail(u.size() - k).setConstant(y(k));
      break;
    }
  }
  return y;
}

}  // namespace idrig
