#include "core/numeric/frequency_domain/stable_nls.h"

#include <unsupported/Eigen/LevenbergMarquardt>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/numeric/model/lti_model.h"

namespace idrig {

namespace {
using Complex = std::complex<double>;

// One factor 1 + a p̃ (+ b p̃²) of (9); params hold √a, √b when squared, else a, b.
struct Section {
  bool quadratic = true;
  bool numerator = false;
  bool squared = true;
};

struct Layout {
  std::vector<Section> sections;  // parameter x: [gain, then per section 1 or 2 values]
  int Size() const {
    int s = 1;
    for (const auto& sec : sections) s += sec.quadratic ? 2 : 1;
    return s;
  }
};

Layout MakeLayout(int n, int m, bool square_numerator) {
  Layout layout;
  for (int j = 0; j < n / 2; ++j) layout.sections.push_back({true, false, true});
  if (n % 2) layout.sections.push_back({false, false, true});
  for (int j = 0; j < m / 2; ++j) layout.sections.push_back({true, true, square_numerator});
  if (m % 2) layout.sections.push_back({false, true, square_numerator});
  return layout;
}

struct Functor : Eigen::DenseFunctor<double> {
  Functor(const Layout& layout, const Eigen::VectorXcd& p, const Eigen::VectorXcd& g, const Eigen::VectorXd& w)
      : Eigen::DenseFunctor<double>(layout.Size(), 2 * static_cast<int>(p.size())), layout(layout), p(p), g(g), w(w) {}
  const Layout& layout;
  const Eigen::VectorXcd &p, &g;
  const Eigen::VectorXd& w;

  // Coefficient value from a parameter (squared or not) and d(value)/d(param).
  static double Coef(double x, bool squared) { return squared ? x * x : x; }
  static double DCoef(double x, bool squared) { return squared ? 2.0 * x : 1.0; }

  Complex Model(const Eigen::VectorXd& x, int k) const {
    Complex v = x(0);
    int i = 1;
    for (const auto& s : layout.sections) {
      Complex f = 1.0 + Coef(x(i), s.squared) * p(k);
      if (s.quadratic) f += Coef(x(i + 1), s.squared) * p(k) * p(k);
      v = s.numerator ? v * f : v / f;
      i += s.quadratic ? 2 : 1;
    }
    return v;
  }
  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& fvec) const {
    const int lines = static_cast<int>(p.size());
    for (int k = 0; k < lines; ++k) {
      const Complex r = w(k) * (Model(x, k) - g(k));  // Eq. (10) of [Balda], weighted
      fvec(k) = r.real();
      fvec(lines + k) = r.imag();
    }
    return 0;
  }
  int df(const Eigen::VectorXd& x, Eigen::MatrixXd& jac) const {
    const int lines = static_cast<int>(p.size());
    for (int k = 0; k < lines; ++k) {
      const Complex gm = Model(x, k);
      auto put = [&](int col, Complex d) {
        d *= w(k);
        jac(k, col) = d.real();
        jac(lines + k, col) = d.imag();
      };
      // Gain: G = G(0)·P, ∂G/∂G(0) = P (computed without dividing by G(0)).
      Eigen::VectorXd x1 = x;
      x1(0) = 1.0;
      put(0, Model(x1, k));
      int i = 1;
      for (const auto& s : layout.sections) {
        Complex f = 1.0 + Coef(x(i), s.squared) * p(k);
        if (s.quadratic) f += Coef(x(i + 1), s.squared) * p(k) * p(k);
        const Complex sign_g = (s.numerator ? 1.0 : -1.0) * gm / f;  // ∂G/∂f
        put(i, sign_g * DCoef(x(i), s.squared) * p(k));
        if (s.quadratic) put(i + 1, sign_g * DCoef(x(i + 1), s.squared) * p(k) * p(k));
        i += s.quadratic ? 2 : 1;
      }
    }
    return 0;
  }
};

// Roots (scaled) → section coefficients (a, b) of ∏(1 − p̃/r). Roots are reflected into the
// left half-plane when `reflect`; tiny roots are clamped. Returns pairs in section order.
std::vector<std::pair<double, double>> SectionsFromRoots(Eigen::VectorXcd roots, int degree, bool reflect) {
  for (int i = 0; i < roots.size(); ++i) {
    if (reflect && roots(i).real() > 0.0) roots(i) = Complex(-roots(i).real(), roots(i).imag());
    if (std::abs(roots(i)) < 1e-6) roots(i) = Complex(-1e-6, roots(i).imag());
  }
  std::vector<Complex> complex_roots;
  std::vector<double> real_roots;
  for (int i = 0; i < roots.size(); ++i) {
    if (std::abs(roots(i).imag()) > 1e-9 * std::abs(roots(i))) {
      if (roots(i).imag() > 0.0) complex_roots.push_back(roots(i));
    } else {
      real_roots.push_back(roots(i).real());
    }
  }
  std::sort(real_roots.begin(), real_roots.end());
  std::vector<std::pair<double, double>> quads, out;
  for (const Complex& r : complex_roots) quads.push_back({-2.0 * r.real() / std::norm(r), 1.0 / std::norm(r)});
  size_t ri = 0;
  std::vector<double> linear;
  while (ri + 1 < real_roots.size() && static_cast<int>(quads.size()) < degree / 2) {
    const double r1 = real_roots[ri], r2 = real_roots[ri + 1];
    quads.push_back({-(1.0 / r1 + 1.0 / r2), 1.0 / (r1 * r2)});
    ri += 2;
  }
  for (; ri < real_roots.size(); ++ri) linear.push_back(-1.0 / real_roots[ri]);
  // Fit into the layout: degree/2 quadratics then an optional linear section; missing ones
  // start as (almost) 1, extra roots (cannot happen for matching degrees) are dropped.
  while (static_cast<int>(quads.size()) < degree / 2) {
    if (linear.size() >= 2) {
      const double a1 = linear.back(); linear.pop_back();
      const double a2 = linear.back(); linear.pop_back();
      quads.push_back({a1 + a2, a1 * a2});
    } else {
      quads.push_back({linear.empty() ? 1e-3 : linear.back(), 1e-6});
      if (!linear.empty()) linear.pop_back();
    }
  }
  for (int j = 0; j < degree / 2; ++j) out.push_back(quads[j]);
  if (degree % 2) out.push_back({linear.empty() ? 1e-3 : linear.back(), 0.0});
  return out;
}
}  // namespace

StableNlsResult FitStableNls(const Frf& frf, const StableNlsOptions& options) {
  if (options.numerator_degree > options.denominator_degree)
    throw std::invalid_argument("stable NLS: numerator_degree must not exceed denominator_degree");
  if (options.max_function_evaluations < 1)
    throw std::invalid_argument("stable NLS: max_function_evaluations must be >= 1");
  LevyOptions levy;
  levy.denominator_degree = options.denominator_degree;
  levy.numerator_degree = options.numerator_degree;
  levy.max_sk_iterations = options.sk_iterations;
  levy.weights = options.weights;
  StableNlsResult result;
  result.start = FitLevy(frf, levy);  // validates the FRF, degrees, line count, weights
  const int lines = frf.NumLines(), n = options.denominator_degree, m = options.numerator_degree;
  const Eigen::VectorXd w = options.weights.size() ? options.weights : Eigen::VectorXd::Ones(lines);
  const double ws = frf.omega.maxCoeff();
  Eigen::VectorXcd p(lines), g(lines);
  for (int k = 0; k < lines; ++k) {
    p(k) = Complex(0.0, frf.omega(k) / ws);
    g(k) = frf.h[k](0, 0);
  }
  const Layout layout = MakeLayout(n, m, options.square_numerator);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.Size());
  // Start from the Levy/SK roots (scaled by 1/ω_s), unstable ones reflected.
  Eigen::VectorXcd poles = result.start.model.den.allFinite() ? PolynomialRoots(result.start.model.den)
                                                              : Eigen::VectorXcd::Constant(n, -1.0);
  Eigen::VectorXcd zeros = (m > 0 && result.start.model.num.allFinite()) ? PolynomialRoots(result.start.model.num)
                                                                         : Eigen::VectorXcd();
  if (poles.size() != n) poles = Eigen::VectorXcd::Constant(n, -ws);
  poles /= ws;
  zeros /= ws;
  const auto den = SectionsFromRoots(poles, n, true);
  const auto num = SectionsFromRoots(zeros, m, options.square_numerator);
  {
    int i = 1;
    size_t di = 0, ni = 0;
    for (const auto& s : layout.sections) {
      const auto& ab = s.numerator ? num[ni++] : den[di++];
      auto param = [&](double v) { return s.squared ? std::sqrt(std::max(v, 1e-12)) : v; };
      x(i) = param(ab.first);
      if (s.quadratic) x(i + 1) = param(ab.second);
      i += s.quadratic ? 2 : 1;
    }
  }
  Functor functor(layout, p, g, w);
  // Gain by linear least squares given the sections: G = G(0)·P.
  {
    x(0) = 1.0;
    double num_acc = 0.0, den_acc = 0.0;
    for (int k = 0; k < lines; ++k) {
      const Complex pk = functor.Model(x, k);
      num_acc += w(k) * w(k) * std::real(std::conj(pk) * g(k));
      den_acc += w(k) * w(k) * std::norm(pk);
    }
    x(0) = den_acc > 0.0 ? num_acc / den_acc : 1.0;
  }
  Eigen::VectorXd fvec(2 * lines);
  functor(x, fvec);
  result.start_cost = fvec.squaredNorm();

  Eigen::LevenbergMarquardt<Functor> lm(functor);
  lm.setMaxfev(options.max_function_evaluations);
  lm.setFtol(options.tolerance);
  lm.setXtol(options.tolerance);
  const auto status = lm.minimize(x);
  result.lm_status = static_cast<int>(status);
  result.iterations = static_cast<int>(lm.iterations());
  result.function_evaluations = static_cast<int>(lm.nfev());

  // Assemble the transfer function in p (descending powers), monic denominator.
  Eigen::VectorXd num_poly = Eigen::VectorXd::Constant(1, x(0)), den_poly = Eigen::VectorXd::Ones(1);
  int i = 1;
  for (const auto& s : layout.sections) {
    const double a = Functor::Coef(x(i), s.squared) / ws;
    Eigen::VectorXd f;
    if (s.quadratic) {
      f = Eigen::Vector3d(Functor::Coef(x(i + 1), s.squared) / (ws * ws), a, 1.0);
    } else {
      f = Eigen::Vector2d(a, 1.0);
    }
    if (s.numerator) num_poly = PolynomialProduct(num_poly, f); else den_poly = PolynomialProduct(den_poly, f);
    i += s.quadratic ? 2 : 1;
  }
  const double lead = den_poly(0);
  result.model.den = den_poly / lead;
  result.model.num = num_poly / lead;
  functor(x, fvec);
  result.final_cost = fvec.squaredNorm();
  Eigen::VectorXcd fitted(lines);
  for (int k = 0; k < lines; ++k) fitted(k) = functor.Model(x, k);
  result.fit_percent = FrfFitPercent(frf, fitted, w);
  if (!result.model.den.allFinite() || lead == 0.0) {
    result.status = SolverStatus::kFailed;
    result.message = "a denominator section degenerated (leading coefficient 0)";
    return result;
  }
  result.poles = PolynomialRoots(result.model.den);
  result.stable = (result.poles.real().array() < 0.0).all();
  using namespace Eigen::LevenbergMarquardtSpace;
  if (status == TooManyFunctionEvaluation) {
    result.status = SolverStatus::kNotConverged;
    result.message = "Levenberg-Marquardt stopped at the function-evaluation limit (" +
                     std::to_string(options.max_function_evaluations) + ")";
  } else if (status == ImproperInputParameters) {
    result.status = SolverStatus::kFailed;
    result.message = "Levenberg-Marquardt rejected its input";
  } else {
    result.status = SolverStatus::kOk;
    result.message = "Levenberg-Marquardt converged (status " + std::to_string(result.lm_status) + ")";
  }
  return result;
}

}  // namespace idrig
