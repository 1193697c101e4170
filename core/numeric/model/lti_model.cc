#include "core/numeric/model/lti_model.h"

#include <unsupported/Eigen/MatrixFunctions>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/numeric/model/realisation.h"

namespace idrig {
namespace {

[[noreturn]] void Fail(const std::string& what) { throw std::invalid_argument(what); }

bool AllFinite(const Eigen::MatrixXd& m) { return m.allFinite(); }

// D⁻¹ M D with D a diagonal of powers of 2 that balances the off-diagonal row and column norms
// (Parlett and Reinsch 1969, as LAPACK's xGEBAL; the scaling is exact in floating point, so the
// eigenvalues are M's). A companion realisation at a high sample rate has coefficients up to ωⁿ
// (1e25 for order 6 at 51.2 kHz); the balanced matrix has entries of the order of ω.
Eigen::MatrixXd Balanced(const Eigen::MatrixXd& m, Eigen::VectorXd* scaling) {
  const long n = m.rows();
  Eigen::VectorXd d = Eigen::VectorXd::Ones(n);
  Eigen::MatrixXd b = m;
  bool changed = b.allFinite();
  for (int sweep = 0; changed && sweep < 200; ++sweep) {
    changed = false;
    for (long i = 0; i < n; ++i) {
      double c = 0, r = 0;
      for (long j = 0; j < n; ++j)
        if (j != i) c += std::abs(b(j, i)), r += std::abs(b(i, j));
      if (c == 0 || r == 0) continue;
      const double before = c + r;
      double f = 1;
      while (c < r / 2) c *= 2, r /= 2, f *= 2;
      while (c >= 2 * r) c /= 2, r *= 2, f /= 2;
      if (c + r < 0.95 * before) {
        d(i) *= f;
        b.row(i) /= f;
        b.col(i) *= f;
        changed = true;
      }
    }
  }
  if (scaling) *scaling = d;
  return b;
}

// exp(M) = D·exp(D⁻¹ M D)·D⁻¹: the scaling and squaring of the unbalanced M·T at a high sample
// rate loses every digit (Φ came out 0), the balanced one has entries of the order of ω·T.
Eigen::MatrixXd BalancedExp(const Eigen::MatrixXd& m) {
  if (!m.allFinite()) return m.exp();
  Eigen::VectorXd d;
  const Eigen::MatrixXd b = Balanced(m, &d);
  return d.asDiagonal() * b.exp() * d.cwiseInverse().asDiagonal();
}

// M's eigenvalues, from the balanced matrix.
Eigen::VectorXcd BalancedEigenvalues(const Eigen::MatrixXd& m) {
  return Eigen::EigenSolver<Eigen::MatrixXd>(Balanced(m, nullptr), false).eigenvalues();
}

// The coefficients (descending) of Π(s + |λ_i|): the i-th is the sum of the products of i of the
// |λ|, an upper bound on the i-th coefficient of the polynomial with roots λ and the size of the
// rounding it carries when computed from them.
Eigen::VectorXd CoefficientScale(const Eigen::VectorXcd& roots) {
  return PolynomialFromRoots(-roots.cwiseAbs().cast<std::complex<double>>());
}

void CheckTimes(double sample_time, double delay_s, const char* what) {
  if (!std::isfinite(sample_time) || sample_time < 0.0)
    Fail(std::string(what) + ": sample time must be 0 (continuous) or a positive number of seconds");
  if (!std::isfinite(delay_s) || delay_s < 0.0)
    Fail(std::string(what) + ": input delay must be a non-negative number of seconds");
  if (sample_time > 0.0) {
    const double samples = delay_s / sample_time;
    if (std::abs(samples - std::round(samples)) > 1e-9 * std::max(1.0, samples))
      Fail(std::string(what) + ": a discrete model's delay (" + std::to_string(delay_s) +
           " s) must be a whole number of samples of " + std::to_string(sample_time) + " s");
  }
}

Eigen::VectorXd TrimLeadingZeros(const Eigen::VectorXd& p) {
  int first = 0;
  while (first < p.size() - 1 && p(first) == 0.0) ++first;
  return p.tail(p.size() - first);
}

}  // namespace

void Validate(const TransferFunction& tf) {
  if (tf.den.size() == 0) Fail("transfer function: empty denominator");
  if (tf.num.size() == 0) Fail("transfer function: empty numerator");
  if (!AllFinite(tf.num) || !AllFinite(tf.den))
    Fail("transfer function: numerator or denominator contains NaN or Inf");
  const Eigen::VectorXd den = TrimLeadingZeros(tf.den);
  if (den.size() == 1 && den(0) == 0.0) Fail("transfer function: denominator is zero");
  if (TrimLeadingZeros(tf.num).size() > den.size())
    Fail("transfer function: improper (numerator degree " +
         std::to_string(TrimLeadingZeros(tf.num).size() - 1) + " > denominator degree " +
         std::to_string(den.size() - 1) + ")");
  CheckTimes(tf.sample_time, tf.delay_s, "transfer function");
}

void Validate(const StateSpace& ss) {
  const auto n = ss.A.rows();
  if (ss.A.cols() != n) Fail("state space: A must be square");
  if (ss.B.rows() != n) Fail("state space: B must have as many rows as A (" + std::to_string(n) + ")");
  if (ss.C.cols() != n) Fail("state space: C must have as many columns as A (" + std::to_string(n) + ")");
  if (ss.D.rows() != ss.C.rows() || ss.D.cols() != ss.B.cols())
    Fail("state space: D must be " + std::to_string(ss.C.rows()) + "x" + std::to_string(ss.B.cols()));
  if (ss.B.cols() == 0 || ss.C.rows() == 0) Fail("state space: no inputs or no outputs");
  if (!AllFinite(ss.A) || !AllFinite(ss.B) || !AllFinite(ss.C) || !AllFinite(ss.D))
    Fail("state space: a matrix contains NaN or Inf");
  CheckTimes(ss.sample_time, ss.delay_s, "state space");
}

TransferFunction Normalized(const TransferFunction& tf) {
  Validate(tf);
  TransferFunction out = tf;
  out.den = TrimLeadingZeros(tf.den);
  out.num = TrimLeadingZeros(tf.num);
  const double lead = out.den(0);
  out.den /= lead;
  out.num /= lead;
  return out;
}

StateSpace ToStateSpace(const TransferFunction& tf) {
  const TransferFunction w = Normalized(tf);
  const int n = w.Order();
  // Pad the numerator to n+1 coefficients (descending), then split off the direct term.
  Eigen::VectorXd num = Eigen::VectorXd::Zero(n + 1);
  num.tail(w.num.size()) = w.num;
  const double direct = num(0);
  StateSpace ss;
  ss.sample_time = w.sample_time;
  ss.delay_s = w.delay_s;
  ss.D = Eigen::MatrixXd::Constant(1, 1, direct);
  if (n == 0) {
    ss.A.resize(0, 0);
    ss.B.resize(0, 1);
    ss.C.resize(1, 0);
    return ss;
  }
  const Eigen::VectorXd strictly_proper = num.tail(n) - direct * w.den.tail(n);
  const CompactForm r1 = CompactObservableForm(strictly_proper, w.den);
  ss.A = r1.A;
  ss.B = r1.B;
  ss.C = r1.H;
  return ss;
}

StateSpace ToStateSpace(const LtiModel& model) {
  if (const auto* tf = std::get_if<TransferFunction>(&model)) return ToStateSpace(*tf);
  const auto& ss = std::get<StateSpace>(model);
  Validate(ss);
  return ss;
}

Eigen::VectorXcd PolynomialRoots(const Eigen::VectorXd& descending) {
  const Eigen::VectorXd p = TrimLeadingZeros(descending);
  const int n = static_cast<int>(p.size()) - 1;
  if (n <= 0) return Eigen::VectorXcd();
  // Companion matrix eigenvalues (balanced by Eigen's EigenSolver).
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  companion.row(0) = -p.tail(n).transpose() / p(0);
  if (n > 1) companion.bottomLeftCorner(n - 1, n - 1).setIdentity();
  return Eigen::EigenSolver<Eigen::MatrixXd>(companion, false).eigenvalues();
}

Eigen::VectorXd PolynomialProduct(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  if (a.size() == 0 || b.size() == 0) return Eigen::VectorXd();
  Eigen::VectorXd c = Eigen::VectorXd::Zero(a.size() + b.size() - 1);
  for (int i = 0; i < a.size(); ++i) c.segment(i, b.size()) += a(i) * b;
  return c;
}

Eigen::VectorXd PolynomialFromRoots(const Eigen::VectorXcd& roots) {
  Eigen::VectorXcd p = Eigen::VectorXcd::Zero(roots.size() + 1);
  p(0) = 1.0;
  for (int k = 0; k < roots.size(); ++k) {
    for (int j = k + 1; j >= 1; --j) p(j) -= roots(k) * p(j - 1);
  }
  return p.real();
}

std::complex<double> PolyVal(const Eigen::VectorXd& descending, std::complex<double> x) {
  std::complex<double> acc = 0.0;
  for (int i = 0; i < descending.size(); ++i) acc = acc * x + descending(i);
  return acc;
}

Eigen::VectorXcd Poles(const TransferFunction& tf) { return PolynomialRoots(Normalized(tf).den); }

Eigen::VectorXcd Poles(const StateSpace& ss) {
  Validate(ss);
  if (ss.Order() == 0) return Eigen::VectorXcd();
  return Eigen::EigenSolver<Eigen::MatrixXd>(ss.A, false).eigenvalues();
}

Eigen::VectorXcd Zeros(const TransferFunction& tf) { return PolynomialRoots(Normalized(tf).num); }

TransferFunction ToTransferFunction(const StateSpace& ss, int output, int input) {
  Validate(ss);
  if (output < 0 || output >= ss.NumOutputs() || input < 0 || input >= ss.NumInputs())
    Fail("transfer function of channel (" + std::to_string(output) + "," + std::to_string(input) +
         "): the model has " + std::to_string(ss.NumOutputs()) + " outputs and " +
         std::to_string(ss.NumInputs()) + " inputs");
  const int n = ss.Order();
  TransferFunction tf;
  tf.sample_time = ss.sample_time;
  tf.delay_s = ss.delay_s;
  const double d = ss.D(output, input);
  if (n == 0) {
    tf.num = Eigen::VectorXd::Constant(1, d);
    tf.den = Eigen::VectorXd::Ones(1);
    return tf;
  }
  const Eigen::VectorXd b = ss.B.col(input);
  const Eigen::RowVectorXd c = ss.C.row(output);
  // det(sI − A + b c) = det(sI − A)·(1 + c (sI − A)^{-1} b), so
  // num = charpoly(A − b c) − charpoly(A) + d·charpoly(A).
  // Both sets of eigenvalues from balanced matrices: at a high sample rate the realisation's
  // entries span 25 orders of magnitude, and without balancing the leading coefficients, of the
  // order of ω, drown in the rounding of the largest, of the order of ωⁿ.
  const Eigen::VectorXcd poles = BalancedEigenvalues(ss.A);
  const Eigen::VectorXcd closed_poles = BalancedEigenvalues(ss.A - b * c);
  const Eigen::VectorXd den = PolynomialFromRoots(poles);
  tf.num = PolynomialFromRoots(closed_poles) - den + d * den;
  tf.den = den;
  // Drop leading numerator terms that are rounding noise: each against the size of the terms it
  // is the difference of (a single scale for all, the largest coefficient, took the s⁵ term of a
  // sixth-order model at 51.2 kHz, ~3e5 against ~5e24, for noise).
  const Eigen::VectorXd scale = CoefficientScale(poles) * (1.0 + std::abs(d)) + CoefficientScale(closed_poles);
  int first = 0;
  while (first < n && std::abs(tf.num(first)) < 1e-13 * std::max(1.0, scale(first))) ++first;
  tf.num = tf.num.tail(n + 1 - first).eval();
  return tf;
}

PartialFractions Residues(const TransferFunction& tf, double distinct_tol) {
  const TransferFunction w = Normalized(tf);
  const int n = w.Order();
  PartialFractions pf;
  Eigen::VectorXd num = Eigen::VectorXd::Zero(n + 1);
  num.tail(w.num.size()) = w.num;
  pf.direct = num(0);
  const Eigen::VectorXd strictly = num - pf.direct * w.den;  // leading coefficient now zero
  pf.poles = PolynomialRoots(w.den);
  pf.residues.resize(n);
  // Derivative of the monic denominator.
  Eigen::VectorXd dden(n);
  for (int i = 0; i < n; ++i) dden(i) = w.den(i) * (n - i);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < i; ++j) {
      if (std::abs(pf.poles(i) - pf.poles(j)) <= distinct_tol * std::max(1.0, std::abs(pf.poles(i))))
        Fail("residues: repeated pole near " + std::to_string(pf.poles(i).real()) + "+" +
             std::to_string(pf.poles(i).imag()) + "j; partial fractions need distinct poles");
    }
    pf.residues(i) = PolyVal(strictly, pf.poles(i)) / PolyVal(dden, pf.poles(i));
  }
  return pf;
}

namespace {
std::complex<double> Frequency(double sample_time, double omega) {
  const std::complex<double> jw(0.0, omega);
  return sample_time > 0.0 ? std::exp(jw * sample_time) : jw;
}
}  // namespace

std::complex<double> FrequencyResponse(const TransferFunction& tf, double omega) {
  const std::complex<double> x = Frequency(tf.sample_time, omega);
  return PolyVal(tf.num, x) / PolyVal(tf.den, x) * std::exp(std::complex<double>(0.0, -omega * tf.delay_s));
}

Eigen::VectorXcd FrequencyResponse(const TransferFunction& tf, const Eigen::VectorXd& omega) {
  Validate(tf);
  Eigen::VectorXcd h(omega.size());
  for (int k = 0; k < omega.size(); ++k) h(k) = FrequencyResponse(tf, omega(k));
  return h;
}

Eigen::MatrixXcd FrequencyResponse(const StateSpace& ss, double omega) {
  const std::complex<double> x = Frequency(ss.sample_time, omega);
  const int n = ss.Order();
  Eigen::MatrixXcd h = ss.D.cast<std::complex<double>>();
  if (n > 0) {
    const Eigen::MatrixXcd resolvent = x * Eigen::MatrixXcd::Identity(n, n) - ss.A.cast<std::complex<double>>();
    h += ss.C.cast<std::complex<double>>() * resolvent.partialPivLu().solve(ss.B.cast<std::complex<double>>());
  }
  return h * std::exp(std::complex<double>(0.0, -omega * ss.delay_s));
}

Eigen::MatrixXd DcGain(const StateSpace& ss) {
  Validate(ss);
  const int n = ss.Order();
  if (n == 0) return ss.D;
  const Eigen::MatrixXd m = ss.IsDiscrete() ? Eigen::MatrixXd(Eigen::MatrixXd::Identity(n, n) - ss.A)
                                            : Eigen::MatrixXd(-ss.A);
  Eigen::FullPivLU<Eigen::MatrixXd> lu(m);
  if (!lu.isInvertible())
    return Eigen::MatrixXd::Constant(ss.NumOutputs(), ss.NumInputs(), std::numeric_limits<double>::infinity());
  return ss.C * lu.solve(ss.B) + ss.D;
}

bool IsStable(const StateSpace& ss, double margin) {
  const Eigen::VectorXcd p = Poles(ss);
  for (int i = 0; i < p.size(); ++i) {
    if (ss.IsDiscrete() ? std::abs(p(i)) >= 1.0 - margin : p(i).real() >= -margin) return false;
  }
  return true;
}

StateSpace DiscretizeZoh(const StateSpace& continuous, double sample_time) {
  Validate(continuous);
  if (continuous.IsDiscrete()) Fail("DiscretizeZoh: the model is already discrete");
  if (!(sample_time > 0.0) || !std::isfinite(sample_time))
    Fail("DiscretizeZoh: sample time must be positive");
  const int n = continuous.Order();
  const int nu = continuous.NumInputs();
  const long whole = static_cast<long>(std::floor(continuous.delay_s / sample_time + 1e-12));
  const double frac = continuous.delay_s - whole * sample_time;  // 0 <= frac < Ts
  // exp([[A B],[0 0]]·t) = [[Φ(t) Γ(t)],[0 I]].
  auto phi_gamma = [&](double t, Eigen::MatrixXd* phi, Eigen::MatrixXd* gamma) {
    Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n + nu, n + nu);
    m.topLeftCorner(n, n) = continuous.A * t;
    m.topRightCorner(n, nu) = continuous.B * t;
    const Eigen::MatrixXd e = BalancedExp(m);
    *phi = e.topLeftCorner(n, n);
    *gamma = e.topRightCorner(n, nu);
  };
  StateSpace d;
  d.sample_time = sample_time;
  d.delay_s = whole * sample_time;
  if (frac <= 1e-12 * sample_time) {
    Eigen::MatrixXd phi, gamma;
    phi_gamma(sample_time, &phi, &gamma);
    d.A = phi;
    d.B = gamma;
    d.C = continuous.C;
    d.D = continuous.D;
    return d;
  }
  // Fractional delay θ: x[k+1] = Φ x[k] + Γ1 u[k] + Γ0 u[k−1] with
  // Γ1 = Γ(T−θ), Γ0 = Φ(T−θ)Γ(θ); the previous input becomes extra states.
  Eigen::MatrixXd phi, gamma_rest, phi_rest, gamma_theta, unused;
  phi_gamma(sample_time, &phi, &unused);
  phi_gamma(sample_time - frac, &phi_rest, &gamma_rest);
  phi_gamma(frac, &unused, &gamma_theta);
  const Eigen::MatrixXd gamma0 = phi_rest * gamma_theta;
  d.A = Eigen::MatrixXd::Zero(n + nu, n + nu);
  d.A.topLeftCorner(n, n) = phi;
  d.A.topRightCorner(n, nu) = gamma0;
  d.B = Eigen::MatrixXd::Zero(n + nu, nu);
  d.B.topRows(n) = gamma_rest;
  d.B.bottomRows(nu).setIdentity();
  d.C = Eigen::MatrixXd::Zero(continuous.NumOutputs(), n + nu);
  d.C.leftCols(n) = continuous.C;
  // The direct term sees u(t − θ) = u[k−1] inside the sample (ZOH): it reads the stored input.
  d.D = Eigen::MatrixXd::Zero(continuous.NumOutputs(), nu);
  d.C.rightCols(nu) = continuous.D;
  return d;
}

Eigen::MatrixXd Simulate(const StateSpace& model, const Eigen::MatrixXd& u, double sample_time,
                         const Eigen::VectorXd& x0) {
  Validate(model);
  if (u.cols() != model.NumInputs())
    Fail("simulate: input has " + std::to_string(u.cols()) + " columns but the model has " +
         std::to_string(model.NumInputs()) + " inputs");
  if (!u.allFinite()) Fail("simulate: input contains NaN or Inf");
  StateSpace d;
  if (model.IsDiscrete()) {
    if (sample_time > 0.0 && std::abs(sample_time - model.sample_time) > 1e-9 * model.sample_time)
      Fail("simulate: record sample time " + std::to_string(sample_time) +
           " s differs from the discrete model's " + std::to_string(model.sample_time) + " s");
    d = model;
  } else {
    d = DiscretizeZoh(model, sample_time);
  }
  const long delay = std::lround(d.delay_s / d.sample_time);
  const int n = d.Order();
  if (x0.size() != 0 && x0.size() != model.Order())
    Fail("simulate: initial state has " + std::to_string(x0.size()) + " entries, model order is " +
         std::to_string(model.Order()));
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  if (x0.size() != 0) x.head(x0.size()) = x0;
  const long samples = u.rows();
  Eigen::MatrixXd y(samples, d.NumOutputs());
  Eigen::VectorXd uk(d.NumInputs());
  for (long k = 0; k < samples; ++k) {
    if (k - delay >= 0) uk = u.row(k - delay).transpose(); else uk.setZero();
    y.row(k) = (d.C * x + d.D * uk).transpose();
    x = d.A * x + d.B * uk;
  }
  return y;
}

Eigen::MatrixXd Simulate(const LtiModel& model, const Eigen::MatrixXd& u, double sample_time) {
  return Simulate(ToStateSpace(model), u, sample_time);
}

Eigen::MatrixXd StepResponse(const StateSpace& model, double sample_time, int samples, int input) {
  Validate(model);
  if (input < 0 || input >= model.NumInputs()) Fail("step response: no input " + std::to_string(input));
  if (samples < 1) Fail("step response: need at least one sample");
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(samples, model.NumInputs());
  u.col(input).setOnes();
  return Simulate(model, u, sample_time);
}

std::vector<Eigen::MatrixXd> ImpulseResponse(const StateSpace& model, double sample_time,
                                             int samples) {
  Validate(model);
  if (samples < 1) Fail("impulse response: need at least one sample");
  std::vector<Eigen::MatrixXd> g;
  g.reserve(samples);
  if (model.IsDiscrete()) {
    const long delay = std::lround(model.delay_s / model.sample_time);
    Eigen::MatrixXd power_b = model.B;  // A^{k-1} B
    for (int k = 0; k < samples; ++k) {
      const long j = k - delay;
      if (j < 0) g.push_back(Eigen::MatrixXd::Zero(model.NumOutputs(), model.NumInputs()));
      else if (j == 0) g.push_back(model.D);
      else {
        g.push_back(model.C * power_b);
        power_b = model.A * power_b;
      }
    }
    return g;
  }
  if (!(sample_time > 0.0)) Fail("impulse response: sample time must be positive");
  for (int k = 0; k < samples; ++k) {
    const double t = k * sample_time - model.delay_s;
    if (t < -1e-12) {
      g.push_back(Eigen::MatrixXd::Zero(model.NumOutputs(), model.NumInputs()));
      continue;
    }
    g.push_back(model.C * (model.A * t).exp() * model.B);
  }
  return g;
}

}  // namespace idrig
