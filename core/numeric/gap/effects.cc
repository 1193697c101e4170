#include "core/numeric/gap/effects.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/numeric/model/lti_model.h"

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

// x+ = A x + B u + F w, and a row times x, as plain loops: for the few states of a plant
// Eigen's general matrix–vector kernel costs more in dispatch than in arithmetic (a third of
// a diagnosis's time went there). N > 0: a loop of fixed length N, which the compiler unrolls
// (EffectSimulator::Step chooses N once per sample for up to 6 states); N = 0: x.size(). The
// same operations in the same order either way, so the same result to the bit.
template <int N>
[[gnu::always_inline]] inline void Advance(const Eigen::MatrixXd& a, const Eigen::VectorXd& x,
                                           const Eigen::VectorXd& b, double u, const Eigen::VectorXd& f,
                                           double w, Eigen::VectorXd& next) {
  const long n = N > 0 ? N : x.size();
  const double* pa = a.data();
  const double *px = x.data(), *pb = b.data(), *pf = f.data();
  double* pn = next.data();
  for (long i = 0; i < n; ++i) pn[i] = pb[i] * u + pf[i] * w;
  for (long j = 0; j < n; ++j) {
    const double xj = px[j];
    const double* col = pa + j * n;
    for (long i = 0; i < n; ++i) pn[i] += col[i] * xj;
  }
}

template <int N>
[[gnu::always_inline]] inline double Dot(const Eigen::RowVectorXd& r, const Eigen::VectorXd& x) {
  const long n = N > 0 ? N : x.size();
  const double *pr = r.data(), *px = x.data();
  double s = 0.0;
  for (long i = 0; i < n; ++i) s += pr[i] * px[i];
  return s;
}

}  // namespace

ForcePath SplitAtForce(const TransferFunction& plant) {
  const TransferFunction g = Normalized(plant);
  ForcePath out;
  out.drive.num = Eigen::VectorXd::Ones(1);
  out.drive.den = Eigen::VectorXd::Ones(1);
  out.drive.delay_s = g.delay_s;
  out.mechanics = g;
  out.mechanics.delay_s = 0.0;
  if (g.IsDiscrete()) return out;
  const double scale = g.num.cwiseAbs().maxCoeff();
  long lead = 0;
  while (lead + 1 < g.num.size() && std::abs(g.num(lead)) <= 1e-12 * scale) ++lead;
  const Eigen::VectorXd num = g.num.tail(g.num.size() - lead);
  if (!(scale > 0.0) || g.Order() - (num.size() - 1) <= 2) return out;
  // The mechanics: the slowest complex pair or the two slowest real poles, whichever is slower
  // (geometric mean of |p|); integrators are the slowest real poles.
  const Eigen::VectorXcd poles = PolynomialRoots(g.den);
  const double size = poles.cwiseAbs().maxCoeff();
  std::vector<long> real, pair;
  for (long i = 0; i < poles.size(); ++i) {
    if (std::abs(poles(i).imag()) <= 1e-9 * std::max(size, 1e-300))
      real.push_back(i);
    else if (poles(i).imag() > 0 && (pair.empty() || std::abs(poles(i)) < std::abs(poles(pair[0]))))
      pair = {i};
  }
  std::sort(real.begin(), real.end(), [&](long a, long b) { return std::abs(poles(a)) < std::abs(poles(b)); });
  double pair_speed = INFINITY, real_speed = INFINITY;
  if (!pair.empty()) pair_speed = std::abs(poles(pair[0]));
  if (real.size() >= 2) real_speed = std::sqrt(std::abs(poles(real[0])) * std::abs(poles(real[1])));
  if (!std::isfinite(std::min(pair_speed, real_speed))) return out;
  Eigen::VectorXcd mech(2), rest(poles.size() - 2);
  std::vector<bool> used(poles.size(), false);
  if (pair_speed <= real_speed) {
    mech << poles(pair[0]), std::conj(poles(pair[0]));
    used[pair[0]] = true;
    // Its conjugate: the nearest pole to conj(p) not yet used.
    long best = -1;
    for (long i = 0; i < poles.size(); ++i)
      if (!used[i] && (best < 0 || std::abs(poles(i) - mech(1)) < std::abs(poles(best) - mech(1)))) best = i;
    used[best] = true;
  } else {
    mech << poles(real[0]), poles(real[1]);
    used[real[0]] = used[real[1]] = true;
  }
  for (long i = 0, j = 0; i < poles.size(); ++i)
    if (!used[i]) rest(j++) = poles(i);
  // No split through a zero at s = 0 or an integrator left in the drive: drive(0) = 1 needs both.
  for (long i = 0; i < rest.size(); ++i)
    if (std::abs(rest(i)) <= 1e-9 * size) return out;
  const Eigen::VectorXd rest_den = PolynomialFromRoots(rest), mech_den = PolynomialFromRoots(mech);
  const double num0 = num(num.size() - 1), rest0 = rest_den(rest_den.size() - 1);
  if (!(std::abs(num0) > 1e-9 * scale) || !(std::abs(rest0) > 0.0)) return out;
  out.drive.num = num * (rest0 / num0);
  out.drive.den = rest_den;
  out.mechanics.num = Eigen::VectorXd::Constant(1, num0 / rest0);
  out.mechanics.den = mech_den;
  out.split = true;
  return out;
}

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

bool IsAbsoluteSensor(const Effect& e) {
  return e.kind == EffectKind::kSensorNonlinearity && e.params.size() > 3 && e.params[3] != 0.0;
}

bool IsLinearEffect(EffectKind kind) {
  return kind == EffectKind::kTimeDelay || kind == EffectKind::kActuatorLag ||
         kind == EffectKind::kUnmodelledResonance;
}

bool IsFeedbackEffect(EffectKind kind) {
  return kind == EffectKind::kCoulombFriction || kind == EffectKind::kCubicStiffness;
}

bool IsInputMap(EffectKind kind) {
  return kind == EffectKind::kInputSaturation || kind == EffectKind::kDeadZone || kind == EffectKind::kBacklash;
}

std::vector<Effect> InRigOrder(std::vector<Effect> effects) {
  const auto rank = [](const Effect& e) {
    switch (e.kind) {
      case EffectKind::kInputSaturation: return 0;
      case EffectKind::kDeadZone: return 1;
      case EffectKind::kBacklash: return 2;
      default: return 3;
    }
  };
  std::stable_sort(effects.begin(), effects.end(), [&](const Effect& a, const Effect& b) { return rank(a) < rank(b); });
  return effects;
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
  auto multiply_den = [&g](const Eigen::VectorXd& factor) { g.den = PolynomialProduct(g.den, factor); };
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

EffectSimulator::EffectSimulator(const TransferFunction& plant, const Effect& effect,
                                 double sample_time, const EffectSimulationOptions& options)
    : EffectSimulator(plant, std::vector<Effect>{effect}, sample_time, options) {}

EffectSimulator::EffectSimulator(const TransferFunction& plant, const std::vector<Effect>& effects,
                                 double sample_time, const EffectSimulationOptions& options)
    : effects_(effects), play_state_(options.play_state) {
  Validate(plant);
  if (!std::isfinite(play_state_)) Fail("effect simulation: the play state before the record is not finite");
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
  // The delay line holds one slot per sample: a delay of more than 10^8 samples (11 days at
  // 100 Hz) is no record's, and would not fit in memory.
  if (!(linear.delay_s / sample_time <= 1e8))
    Fail("effect simulation: a delay of " + std::to_string(linear.delay_s) + " s is " +
         std::to_string(linear.delay_s / sample_time) + " samples, more than 10^8");
  if (feedback_) {
    // Friction and cubic stiffness act in feedback: the force depends on the plant's own state.
    // Continuous realisation with two inputs, u (through the drive) and the force w (into the
    // mechanics): x = [x_drive; x_mech], x_mech' = A_m x_mech + B_m (C_d x_drive + w), y = C_m x_mech.
    TransferFunction undelayed = Normalized(linear);
    undelayed.delay_s = 0.0;
    const ForcePath path = SplitAtForce(undelayed);
    StateSpace c;
    if (!path.split) {
      c = ToStateSpace(undelayed);
      c.B = (Eigen::MatrixXd(c.B.rows(), 2) << c.B.col(0), c.B.col(0)).finished();
      c.D = (Eigen::MatrixXd(1, 2) << c.D(0, 0), c.D(0, 0)).finished();
    } else {
      const StateSpace d = ToStateSpace(path.drive), m = ToStateSpace(path.mechanics);
      const long nd = d.A.rows(), nm = m.A.rows();
      c.A = Eigen::MatrixXd::Zero(nd + nm, nd + nm);
      c.A.topLeftCorner(nd, nd) = d.A;
      c.A.bottomRightCorner(nm, nm) = m.A;
      c.A.bottomLeftCorner(nm, nd) = m.B.col(0) * d.C.row(0);
      c.B = Eigen::MatrixXd::Zero(nd + nm, 2);
      c.B.col(0).head(nd) = d.B.col(0);
      c.B.col(0).tail(nm) = m.B.col(0) * d.D(0, 0);
      c.B.col(1).tail(nm) = m.B.col(0);
      c.C = Eigen::MatrixXd::Zero(1, nd + nm);
      c.C.rightCols(nm) = m.C.row(0);
      c.D = Eigen::MatrixXd::Zero(1, 2);
    }
    substeps_ = options.substeps;
    const StateSpace p = DiscretizeZoh(c, sample_time / substeps_);
    A_ = p.A;
    B_ = p.B.col(0);
    force_B_ = p.B.col(1);
    C_ = p.C.row(0);
    D_ = p.D(0, 0);
    velocity_row_ = c.C.row(0) * c.A;
    velocity_input_ = (c.C.row(0) * c.B.col(1))(0, 0);
    velocity_next_ = velocity_row_ * A_;  // (dy/dt) after one sub-step = v·(A x + B u + B_f w)
    velocity_drive_ = velocity_row_.dot(B_);
    velocity_force_ = velocity_row_.dot(force_B_);
    // The stick rule needs the force to reach dy/dt within a sub-step: relative degree 1 or 2
    // from the force to y (C B ≠ 0 or C A B ≠ 0), which the split guarantees. Without it no
    // force can stop the motion in one sub-step, and friction stays F_c·sign(dy/dt).
    const double cab = velocity_row_.dot(c.B.col(1));
    stick_ = velocity_input_ != 0.0 || std::abs(cab) > 1e-9 * velocity_row_.norm() * c.B.col(1).norm();
    // The delay's whole samples in the line; its fractional part f moves the instant within each
    // sample at which the drive sees the next command (Step). Rounded to whole samples instead,
    // a fit's cost was a staircase in τ, flat between the steps, and a delay beside friction
    // could not move from its start (`gap bench --seed 7102 --excitation steps --combos 0.5
    // --pairs any` case 11: 4.9 samples, fitted as one).
    const double samples = linear.delay_s / sample_time;
    delay_ = static_cast<long>(std::floor(samples + 1e-12));
    fraction_ = std::max(0.0, samples - static_cast<double>(delay_));
    if (fraction_ < 1e-9) fraction_ = 0.0;
  } else {
    const SampledPlant p = Sample(linear, sample_time);
    A_ = p.A;
    B_ = p.B;
    C_ = p.C;
    D_ = p.D;
    force_B_ = B_;
    delay_ = p.delay;
  }
  Reset();
}

void EffectSimulator::Reset() {
  x_ = Eigen::VectorXd::Zero(A_.rows());
  next_ = Eigen::VectorXd::Zero(A_.rows());
  delay_line_.assign(delay_, 0.0);
  delay_head_ = 0;
  previous_input_ = 0.0;
  backlash_.assign(effects_.size(), play_state_);
}

// Coulomb friction as a set-valued force (Filippov; Karnopp's discrete stick rule): the force
// f that brings dy/dt to zero at the end of this sub-step, f_stop = v_next(0)/(v_row B_f + v_in)
// with v_next(0) the velocity the sub-step gives without friction, is applied when
// |f_stop| ≤ F_c (the axis stops or stays stuck: static = kinetic friction); otherwise
// F_c·sign(f_stop), which opposes the motion the sub-step would give. Unlike F_c·sign(dy/dt)
// this does not chatter at reversals, so the result does not depend on the sub-step (a mass
// below its breakaway force does not creep). `w` is the other force on the mechanics (the
// cubic spring's) in this sub-step.
template <int N>
double EffectSimulator::FrictionForce(double u, double w, double limit) const {
  const double gain = velocity_force_ + velocity_input_;  // ∂(dy/dt)_next / ∂f
  if (!stick_ || !(std::abs(gain) > 1e-300)) return limit * Sign(Dot<N>(velocity_row_, x_) + velocity_input_ * (u + w));
  const double moving = Dot<N>(velocity_next_, x_) + velocity_drive_ * u + velocity_force_ * w + velocity_input_ * (u + w);
  return std::clamp(moving / gain, -limit, limit);
}

double EffectSimulator::Step(double u) {
  switch (x_.size()) {
    case 1: return StepN<1>(u);
    case 2: return StepN<2>(u);
    case 3: return StepN<3>(u);
    case 4: return StepN<4>(u);
    case 5: return StepN<5>(u);
    case 6: return StepN<6>(u);
    default: return StepN<0>(u);
  }
}

template <int N>
double EffectSimulator::StepN(double u) {
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
  // Whole-sample delay (a fractional part is in the sampled plant, or beside a feedback effect in
  // the sub-steps below).
  if (delay_ > 0) {
    const double delayed = delay_line_[delay_head_];
    delay_line_[delay_head_] = u;
    if (++delay_head_ == delay_) delay_head_ = 0;
    u = delayed;
  }
  double y;
  if (feedback_) {
    // A fractional delay f (in samples): the drive holds the previous command for the first f of
    // the sample and this one after it; the sub-step across that instant is driven by their
    // time-weighted mean (exact in the impulse it gives, O(h²) in the state), so the response,
    // and a fit's cost, move smoothly with the delay.
    const double previous = previous_input_, current = u;
    previous_input_ = current;
    y = 0.0;
    for (int j = 0; j < substeps_; ++j) {
      const double held = std::clamp(fraction_ * substeps_ - j, 0.0, 1.0);
      u = held * previous + (1.0 - held) * current;
      double w = 0.0;  // the feedback forces on the mechanics
      for (const Effect& e : effects_)
        if (e.kind == EffectKind::kCubicStiffness) {
          const double position = Dot<N>(C_, x_) + D_ * u;
          w -= e.params[0] * position * position * position;
        }
      for (const Effect& e : effects_)
        if (e.kind == EffectKind::kCoulombFriction) w -= FrictionForce<N>(u, w, e.params[0]);
      if (j == 0) y = Dot<N>(C_, x_) + D_ * (u + w);
      Advance<N>(A_, x_, B_, u, force_B_, w, next_);
      x_.swap(next_);
    }
  } else {
    y = Dot<N>(C_, x_) + D_ * u;
    Advance<N>(A_, x_, B_, u, force_B_, 0.0, next_);
    x_.swap(next_);
  }
  // Output side, in the order given.
  for (const Effect& e : effects_)
    y = e.kind == EffectKind::kOutputQuantization ? e.params[0] * std::round(y / e.params[0]) : OutputMap(e, y);
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
