#pragma once
// Linear time-invariant models: transfer functions (SISO) and state space (MIMO), in continuous
// time (sample_time == 0) or discrete time (sample_time = Ts > 0, seconds).
//
//   continuous:  x' = A x + B u(t − τ),      y = C x + D u(t − τ)
//   discrete:    x[k+1] = A x[k] + B u[k − m], y[k] = C x[k] + D u[k − m],  τ = m·Ts
//   transfer function: W(s) = num(s)/den(s) · e^(−sτ), coefficients in descending powers.
//
// Sizes: A n×n, B n×nu, C ny×n, D ny×nu. Units: time in seconds, frequency in rad/s.
#include <Eigen/Dense>
#include <complex>
#include <variant>
#include <vector>

namespace idrig {

struct TransferFunction {
  Eigen::VectorXd num;        // descending powers of s (or z)
  Eigen::VectorXd den;        // descending powers; den(0) != 0
  double sample_time = 0.0;   // 0: continuous; > 0: discrete with this Ts [s]
  double delay_s = 0.0;       // input delay τ [s]; for discrete models a multiple of Ts
  bool IsDiscrete() const { return sample_time > 0.0; }
  int Order() const { return static_cast<int>(den.size()) - 1; }
};

struct StateSpace {
  Eigen::MatrixXd A, B, C, D;
  double sample_time = 0.0;
  double delay_s = 0.0;
  bool IsDiscrete() const { return sample_time > 0.0; }
  int Order() const { return static_cast<int>(A.rows()); }
  int NumInputs() const { return static_cast<int>(B.cols()); }
  int NumOutputs() const { return static_cast<int>(C.rows()); }
};

using LtiModel = std::variant<TransferFunction, StateSpace>;

// Throws std::invalid_argument naming the problem (sizes, NaN, zero leading denominator, a
// discrete delay that is not a whole number of samples, negative delay or Ts).
void Validate(const TransferFunction& tf);
void Validate(const StateSpace& ss);

// Removes leading zeros and makes den monic (num scaled alike).
TransferFunction Normalized(const TransferFunction& tf);

// Realisation of a proper SISO transfer function in the compact observable form R1,
// Eqs. (1.3)–(1.4) of [Ivanovsky] (plus D for a biproper W).
StateSpace ToStateSpace(const TransferFunction& tf);
StateSpace ToStateSpace(const LtiModel& model);
// SISO channel (output, input) of a state-space model as a transfer function.
TransferFunction ToTransferFunction(const StateSpace& ss, int output = 0, int input = 0);

// Polynomial helpers (descending coefficients).
Eigen::VectorXcd PolynomialRoots(const Eigen::VectorXd& descending);
Eigen::VectorXd PolynomialFromRoots(const Eigen::VectorXcd& roots);  // monic, real part kept
Eigen::VectorXd PolynomialProduct(const Eigen::VectorXd& a, const Eigen::VectorXd& b);  // a·b (a convolution)
std::complex<double> PolyVal(const Eigen::VectorXd& descending, std::complex<double> x);

Eigen::VectorXcd Poles(const TransferFunction& tf);
Eigen::VectorXcd Poles(const StateSpace& ss);
Eigen::VectorXcd Zeros(const TransferFunction& tf);

// Partial fractions W(s) = Σ r_i/(s − p_i) + direct, for distinct poles (strictly proper part).
struct PartialFractions {
  Eigen::VectorXcd poles, residues;
  double direct = 0.0;
};
// Throws std::invalid_argument when two poles coincide within `distinct_tol` (relative).
PartialFractions Residues(const TransferFunction& tf, double distinct_tol = 1e-8);

// Frequency response at ω [rad/s]; s = jω or z = e^(jωTs), times e^(−jωτ).
std::complex<double> FrequencyResponse(const TransferFunction& tf, double omega);
Eigen::MatrixXcd FrequencyResponse(const StateSpace& ss, double omega);
// W at each ω_k of `omega` [rad/s].
Eigen::VectorXcd FrequencyResponse(const TransferFunction& tf, const Eigen::VectorXd& omega);

// Steady-state gain (W(0) or W(z=1)); +inf when the model has an integrator.
Eigen::MatrixXd DcGain(const StateSpace& ss);

bool IsStable(const StateSpace& ss, double margin = 0.0);

// Exact zero-order-hold discretisation (matrix exponential of [[A B],[0 0]]·Ts). A
// fractional input delay is carried exactly by augmenting the state (modified z-transform);
// whole-sample delay stays in delay_s.
StateSpace DiscretizeZoh(const StateSpace& continuous, double sample_time);

// Simulation of sampled records. `u` is N×nu, one row per sample; returns N×ny.
// Continuous models are simulated exactly under a zero-order hold on `sample_time`.
// Discrete models must have the same sample time. x0 defaults to zero.
Eigen::MatrixXd Simulate(const StateSpace& model, const Eigen::MatrixXd& u,
                         double sample_time, const Eigen::VectorXd& x0 = Eigen::VectorXd());
Eigen::MatrixXd Simulate(const LtiModel& model, const Eigen::MatrixXd& u, double sample_time);
// Unit-step response from input `input`, N samples at sample_time: N×ny.
Eigen::MatrixXd StepResponse(const StateSpace& model, double sample_time, int samples,
                             int input = 0);
// Impulse response samples g(kTs): continuous models give C e^{A k Ts} B (the D δ part is not
// sampled); discrete models give the Markov parameters (D, CB, CAB, ...).
// Returns a vector of ny×nu matrices.
std::vector<Eigen::MatrixXd> ImpulseResponse(const StateSpace& model, double sample_time,
                                             int samples);

}  // namespace idrig
