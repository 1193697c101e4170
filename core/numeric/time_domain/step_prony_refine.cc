// Step-response identification with multiple complex poles, [Vidinčev] (seed 000): refinement of the LP poles by variable projection (beyond the paper).
#include "core/numeric/time_domain/step_prony_internal.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <unsupported/Eigen/LevenbergMarquardt>
#include <unsupported/Eigen/NumericalDiff>

namespace idrig {
namespace step_prony_detail {
namespace {

// The denominator is kept as linear factors (p + b) and quadratic factors (p + σ)² − d, whose
// modes e^(−σt)·{cosh √d t, sinh(√d t)/√d} pass continuously through the double pole at d = 0,
// so a double pole split by noise into two reals or a complex pair can close up. The residues
// are eliminated by linear least squares; the step-response columns are f(0) − f(t) (x(0) = 0).
struct Factors {
  int linear = 0, quadratic = 0;  // parameters: b_1..b_linear, then (σ, d) per quadratic
};

Eigen::MatrixXd FactorColumns(const Factors& f, const Eigen::VectorXd& theta, const Eigen::VectorXd& t) {
  const int n = static_cast<int>(t.size());
  Eigen::MatrixXd g(n, f.linear + 2 * f.quadratic);
  for (int i = 0; i < f.linear; ++i) {
    const double b = theta(i);
    for (int k = 0; k < n; ++k) g(k, i) = 1.0 - std::exp(-b * t(k));
  }
  for (int q = 0; q < f.quadratic; ++q) {
    const double sigma = theta(f.linear + 2 * q), d = theta(f.linear + 2 * q + 1);
    const double r = std::sqrt(std::abs(d));
    for (int k = 0; k < n; ++k) {
      double c, sn;
      if (r * t(k) < 1e-8) {
        c = 1.0;
        sn = t(k);
      } else if (d > 0) {
        c = std::cosh(r * t(k));
        sn = std::sinh(r * t(k)) / r;
      } else {
        c = std::cos(r * t(k));
        sn = std::sin(r * t(k)) / r;
      }
      const double e = std::exp(-sigma * t(k));
      g(k, f.linear + 2 * q) = 1.0 - e * c;
      g(k, f.linear + 2 * q + 1) = -e * sn;
    }
  }
  return g;
}

struct VarProFunctor : Eigen::DenseFunctor<double> {
  VarProFunctor(const Factors& f, const Eigen::VectorXd& t, const Eigen::VectorXd& x)
      : Eigen::DenseFunctor<double>(f.linear + 2 * f.quadratic, static_cast<int>(t.size())), f(f), t(t), x(x) {}
  int operator()(const Eigen::VectorXd& theta, Eigen::VectorXd& residual) const {
    const Eigen::MatrixXd g = FactorColumns(f, theta, t);
    Eigen::VectorXd scale = g.colwise().norm().transpose();
    for (int i = 0; i < scale.size(); ++i)
      if (!(scale(i) > 0)) scale(i) = 1.0;
    const Eigen::MatrixXd gs = g * scale.cwiseInverse().asDiagonal();
    residual = x - gs * gs.colPivHouseholderQr().solve(x);
    return 0;
  }
  Factors f;
  Eigen::VectorXd t, x;
};

// Refines the b of a fixed multiplicity structure by variable projection: the residues are the
// least-squares solution over all samples for every trial b. Returns the final Σ (x − x̂)².
struct StructureFunctor : Eigen::DenseFunctor<double> {
  StructureFunctor(const std::vector<StepPole>& poles, const Eigen::VectorXd& t, const Eigen::VectorXd& x, double c)
      : Eigen::DenseFunctor<double>(Count(poles), static_cast<int>(t.size())), poles(poles), t(t), x(x), c(c) {}
  static int Count(const std::vector<StepPole>& poles) {
    int n = 0;
    for (const auto& p : poles) n += p.complex_pair ? 2 : 1;
    return n;
  }
  Eigen::VectorXd Pack() const {
    Eigen::VectorXd theta(Count(poles));
    int i = 0;
    for (const auto& p : poles) {
      theta(i++) = p.b.real();
      if (p.complex_pair) theta(i++) = p.b.imag();
    }
    return theta;
  }
  std::vector<StepPole> Unpack(const Eigen::VectorXd& theta) const {
    std::vector<StepPole> out = poles;
    int i = 0;
    for (auto& p : out) {
      const double re = theta(i++);
      p.b = p.complex_pair ? cd(re, theta(i++)) : cd(re, 0.0);
    }
    return out;
  }
  int operator()(const Eigen::VectorXd& theta, Eigen::VectorXd& residual) const {
    std::vector<StepPole> trial = Unpack(theta);
    double cond = 0.0;
    FitResiduesLs(x, t, c, &trial, &cond);
    for (auto& p : trial) p.residues = p.residues_ls;
    residual = x - StepPronyResponse(trial, c, t);
    return 0;
  }
  std::vector<StepPole> poles;
  Eigen::VectorXd t, x;
  double c;
};

}  // namespace

// Refines the roots b (one entry per root, conjugates included) on all samples; returns the
// refined roots (same count) and the number of LM iterations.
Eigen::VectorXcd RefineRoots(const Eigen::VectorXcd& b_in, const Eigen::VectorXd& t, const Eigen::VectorXd& x,
                             int* iterations) {
  std::vector<cd> complex_upper;
  std::vector<double> reals;
  for (int i = 0; i < b_in.size(); ++i) {
    const cd b = b_in(i);
    if (std::abs(b.imag()) <= 1e-9 * (1.0 + std::abs(b))) reals.push_back(b.real());
    else if (b.imag() < 0) complex_upper.push_back(b);  // pole −b has Im > 0
  }
  std::sort(reals.begin(), reals.end());
  Factors f;
  f.quadratic = static_cast<int>(complex_upper.size()) + static_cast<int>(reals.size()) / 2;
  f.linear = static_cast<int>(reals.size()) % 2;
  Eigen::VectorXd theta(f.linear + 2 * f.quadratic);
  int q = 0;
  // Adjacent reals form a quadratic; with an odd count the one farthest from its neighbours is linear.
  size_t skip = reals.size();
  if (f.linear) {
    double best_gap = -1.0;
    for (size_t i = 0; i < reals.size(); i += 2) {  // candidate positions leaving pairs (0,1),(2,3)…
      const double left = i > 0 ? reals[i] - reals[i - 1] : std::numeric_limits<double>::infinity();
      const double right = i + 1 < reals.size() ? reals[i + 1] - reals[i] : std::numeric_limits<double>::infinity();
      const double gap = std::min(left, right);
      if (gap > best_gap) {
        best_gap = gap;
        skip = i;
      }
    }
    theta(0) = reals[skip];
  }
  std::vector<double> paired;
  for (size_t i = 0; i < reals.size(); ++i)
    if (i != skip) paired.push_back(reals[i]);
  for (size_t i = 0; i + 1 < paired.size(); i += 2, ++q) {
    theta(f.linear + 2 * q) = 0.5 * (paired[i] + paired[i + 1]);
    theta(f.linear + 2 * q + 1) = std::pow(0.5 * (paired[i + 1] - paired[i]), 2);
  }
  for (const cd& b : complex_upper) {
    theta(f.linear + 2 * q) = b.real();
    theta(f.linear + 2 * q + 1) = -b.imag() * b.imag();
    ++q;
  }
  VarProFunctor functor(f, t, x);
  Eigen::NumericalDiff<VarProFunctor> diff(functor);
  Eigen::LevenbergMarquardt<Eigen::NumericalDiff<VarProFunctor>> lm(diff);
  lm.setMaxfev(200 * (static_cast<int>(theta.size()) + 1));
  Eigen::VectorXd start = theta;
  Eigen::VectorXd r0, r1;
  functor(start, r0);
  lm.minimize(theta);
  functor(theta, r1);
  if (!(r1.squaredNorm() <= r0.squaredNorm()) || !theta.allFinite()) theta = start;
  *iterations = static_cast<int>(lm.iterations());
  Eigen::VectorXcd out(b_in.size());
  int k = 0;
  for (int i = 0; i < f.linear; ++i) out(k++) = theta(i);
  for (int j = 0; j < f.quadratic; ++j) {
    const double sigma = theta(f.linear + 2 * j), d = theta(f.linear + 2 * j + 1);
    if (d >= 0) {
      out(k++) = sigma - std::sqrt(d);
      out(k++) = sigma + std::sqrt(d);
    } else {
      out(k++) = cd(sigma, -std::sqrt(-d));
      out(k++) = cd(sigma, std::sqrt(-d));
    }
  }
  return out;
}

int StructureParameters(const std::vector<StepPole>& poles) { return StructureFunctor::Count(poles); }

double RefineStructure(std::vector<StepPole>* poles, const Eigen::VectorXd& t, const Eigen::VectorXd& x, double c,
                       int* iterations) {
  StructureFunctor functor(*poles, t, x, c);
  Eigen::VectorXd theta = functor.Pack();
  const Eigen::VectorXd start = theta;
  Eigen::VectorXd r0, r1;
  functor(start, r0);
  Eigen::NumericalDiff<StructureFunctor> diff(functor);
  Eigen::LevenbergMarquardt<Eigen::NumericalDiff<StructureFunctor>> lm(diff);
  lm.setMaxfev(100 * (static_cast<int>(theta.size()) + 1));
  lm.minimize(theta);
  functor(theta, r1);
  if (!theta.allFinite() || !(r1.squaredNorm() <= r0.squaredNorm())) {
    theta = start;
    r1 = r0;
  }
  *iterations += static_cast<int>(lm.iterations());
  *poles = functor.Unpack(theta);
  return r1.squaredNorm();
}

}  // namespace step_prony_detail
}  // namespace idrig
