#pragma once
// The effect library: unmodelled effects that make a rig depart from its linear simulation
// model G0 (input u, output y). Shared by the rig simulator (which adds an effect to a plant)
// and the sim-to-real gap diagnosis (which fits every effect to measured records).
//
// Each effect augments a continuous SISO plant G0(s) = num(s)/den(s) with 0–4 parameters:
//
//   name                   parameters (units of u, y, s)      model
//   none                   —                                  y = G0 u
//   parameter_mismatch     —  (the plant's coefficients move)  y = G0' u
//   time_delay             tau_s                              y = G0 u(t − τ)
//   actuator_lag           T_s                                y = G0/(T s + 1) u
//   unmodelled_resonance   omega_rad_s, zeta                  y = G0 ω²/(s² + 2ζωs + ω²) u
//   input_saturation       u_lo, u_hi                         y = G0 clip(u, u_lo, u_hi)
//   dead_zone              d                                  u_eff = sign(u)·max(|u| − d, 0)
//   backlash               r                                  w = max(u − r, min(u + r, w_prev))
//   coulomb_friction       F_c                                force −f on the mechanics, f = F_c·sign(dy/dt)
//                                                             while sliding, |f| ≤ F_c stuck
//   cubic_stiffness        k3                                 force −k3·y³ on the mechanics
//   output_saturation      y_lo, y_hi                         y_m = clip(y, y_lo, y_hi)
//   sensor_nonlinearity    a1, a2, a3, absolute               y_m = a1 y + a2 y² + a3 y³,
//                                                             or a1·|y| when absolute != 0
//   output_quantization    q                                  y_m = q·round(y/q)
//
// Simulation is sampled with a zero-order hold on u at Ts; the feedback effects (friction,
// cubic stiffness) are integrated with `substeps` ZOH sub-steps per sample, dy/dt taken from
// the continuous state. They act where a force acts: on the mechanics (SplitAtForce below) —
// the plant's input when its relative degree is ≤ 2, else the input of its slowest two poles
// behind the rest of the plant (the drive). Everything here is Eigen-only and I/O-free.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/numeric/model/lti_model.h"

namespace idrig {

enum class EffectKind {
  kNone,
  kParameterMismatch,
  kTimeDelay,
  kActuatorLag,
  kUnmodelledResonance,
  kInputSaturation,
  kDeadZone,
  kBacklash,
  kCoulombFriction,
  kCubicStiffness,
  kOutputSaturation,
  kSensorNonlinearity,
  kOutputQuantization,
};

// The fixed vocabulary, in the order above.
const std::vector<EffectKind>& AllEffects();
const char* EffectName(EffectKind kind);
// Throws std::invalid_argument listing the names when `name` is unknown.
EffectKind EffectFromName(const std::string& name);
// Parameter names of an effect, in the order of Effect::params.
const std::vector<std::string>& EffectParameterNames(EffectKind kind);
// Effects acting on the plant's input, on its output, or in feedback around it.
bool IsLinearEffect(EffectKind kind);    // time_delay, actuator_lag, unmodelled_resonance
bool IsFeedbackEffect(EffectKind kind);  // coulomb_friction, cubic_stiffness
bool IsInputMap(EffectKind kind);        // input_saturation, dead_zone, backlash

struct Effect {
  EffectKind kind = EffectKind::kNone;
  std::vector<double> params;  // EffectParameterNames(kind) order
};

// The effects with their input maps in a rig's order — the amplifier's limit, then the dead zone
// (a valve's overlap, a motor's breakaway), then the gears' play — and the rest as given. The
// simulator applies input maps in the order given; a diagnosis that found them in another order
// models them in this one (a limit on the play's input is not a limit on its output).
std::vector<Effect> InRigOrder(std::vector<Effect> effects);

// The sensor map's |y| variant (absolute = 1): it folds the output at zero.
bool IsAbsoluteSensor(const Effect& e);

// Throws std::invalid_argument naming the problem (wrong count, NaN, negative width, …).
void ValidateEffect(const Effect& effect);

// G0 with a linear effect folded in (delay, lag or resonance); other effects return G0.
TransferFunction ApplyLinearEffect(const TransferFunction& plant, const Effect& effect);

// G0 = drive·mechanics, where the feedback effects' force acts. Relative degree ≤ 2: the force
// acts at G0's input (drive = 1, split = false). Higher: friction at the input of a lag chain
// would be a relay behind a filter — no Filippov sliding, and a result that depends on the
// integration step — so the plant is split at the mass: `mechanics` = the slowest two poles
// (a complex pair, or two real poles, integrators first) with the static gain, `drive` = the
// rest with the zeros, drive(0) = 1, so F_c and k3 stay in units of u. When that split does not
// exist (a zero at s = 0, more than two integrators) the force acts at G0's input.
struct ForcePath {
  TransferFunction drive, mechanics;
  bool split = false;
};
ForcePath SplitAtForce(const TransferFunction& plant);

struct EffectSimulationOptions {
  int substeps = 4;  // ZOH sub-steps per sample for the feedback effects
  // The backlash's (play operator's) output before the first sample: where the play was left
  // before the record. 0 = from rest at the origin.
  double play_state = 0.0;
};

// Sample-by-sample simulation of the plant with the effect (the rig simulator's core): Step(u_k)
// returns y_k and advances one sample. Starts at rest.
class EffectSimulator {
 public:
  // Throws std::invalid_argument for a discrete plant, bad parameters or sample time.
  EffectSimulator(const TransferFunction& plant, const Effect& effect, double sample_time,
                  const EffectSimulationOptions& options = {});
  // Several effects at once (two-effect diagnosis, combined rig effects): input-side maps in the
  // order given, linear effects folded into the plant in series, the feedback terms summed,
  // output-side maps in the order given.
  EffectSimulator(const TransferFunction& plant, const std::vector<Effect>& effects,
                  double sample_time, const EffectSimulationOptions& options = {});
  double Step(double u);
  void Reset();
  const Effect& effect() const { return effects_.front(); }
  const std::vector<Effect>& effects() const { return effects_; }

 private:
  // The friction force on the mechanics in this sub-step for driving input u and other force w
  // (effects.cc).
  template <int N>
  double FrictionForce(double u, double w, double limit) const;
  // Step for a state of N (1–6; 0: any) elements, which Step chooses.
  template <int N>
  double StepN(double u);

  std::vector<Effect> effects_;
  bool feedback_ = false;
  bool stick_ = false;  // friction by the stick rule (force to velocity within a sub-step), else F_c·sign(dy/dt)
  int substeps_ = 1;
  Eigen::MatrixXd A_;
  Eigen::VectorXd B_, force_B_, x_, next_;  // force_B_: where the feedback force enters
  Eigen::RowVectorXd C_, velocity_row_, velocity_next_;
  double velocity_drive_ = 0.0, velocity_force_ = 0.0;
  double D_ = 0.0, velocity_input_ = 0.0;
  long delay_ = 0;             // whole samples in the line
  double fraction_ = 0.0;      // the delay's fractional part in samples, beside a feedback effect
  double previous_input_ = 0.0;  // the line's output one sample ago (held for fraction_ of a sample)
  std::vector<double> delay_line_;
  long delay_head_ = 0;
  std::vector<double> backlash_;  // play-operator state per effect (used by backlash)
  double play_state_ = 0.0;       // backlash_ before the first sample (EffectSimulationOptions)
};

// Output of the plant with the effect for input samples u (Ts apart, plant at rest at k = 0).
// `plant` must be continuous. Throws std::invalid_argument on bad sizes or parameters.
Eigen::VectorXd SimulateWithEffect(const TransferFunction& plant, const Effect& effect,
                                   const Eigen::VectorXd& u, double sample_time,
                                   const EffectSimulationOptions& options = {});

// The same with several effects (see EffectSimulator).
Eigen::VectorXd SimulateWithEffects(const TransferFunction& plant, const std::vector<Effect>& effects,
                                    const Eigen::VectorXd& u, double sample_time,
                                    const EffectSimulationOptions& options = {});

// The static and hysteretic maps, exposed for tests and for the diagnosis's signatures.
double DeadZone(double u, double width);
// Play operator of half-width r over a whole sequence, starting from w = clip(0, u0 ± r).
Eigen::VectorXd Backlash(const Eigen::VectorXd& u, double half_width);
// sensor_nonlinearity: k·|y| where params[3] ≠ 0, else the polynomial y·(a + b·y + c·y²).
inline double SensorMap(double y, const std::vector<double>& p) {
  if (p[3] != 0.0) return p[0] * std::abs(y);
  return y * (p[0] + y * (p[1] + y * p[2]));
}
// An output-side static map (output_saturation or sensor_nonlinearity) at y, and its slope
// d map/dy there when asked (0 where the saturation clips); y itself, slope 1, for any other
// effect. The simulator, the bench's rig and the diagnosis's nuisance fit all apply it, the last
// on every sample of every segment of every prediction behind a map: inline, so that the call
// costs nothing there (out of line it took a sixth of a diagnosis's time).
inline double OutputMap(const Effect& e, double y, double* slope = nullptr) {
  const auto& p = e.params;
  switch (e.kind) {
    case EffectKind::kOutputSaturation:
      if (slope) *slope = y > p[0] && y < p[1] ? 1.0 : 0.0;
      return std::clamp(y, p[0], p[1]);
    case EffectKind::kSensorNonlinearity:
      if (slope) *slope = p[3] != 0.0 ? p[0] * (y < 0 ? -1.0 : 1.0) : p[0] + y * (2 * p[1] + 3 * p[2] * y);
      return SensorMap(y, p);
    default:
      if (slope) *slope = 1.0;
      return y;
  }
}

}  // namespace idrig
