#include "core/numeric/frequency_domain/levy.h"

#include <unsupported/Eigen/LevenbergMarquardt>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace idrig {

namespace {
using Complex = std::complex<double>;

Eigen::VectorXd CheckedWeights(const Eigen::VectorXd& weights, int lines, const char* who) {
  if (weights.size() == 0) return Eigen::VectorXd::Ones(lines);
  if (weights.size() != lines)
    throw std::invalid_argument(std::string(who) + ": " + std::to_string(weights.size()) +
                                " weights for " + std::to_string(lines) + " lines");
  for (int k = 0; k < lines; ++k)
    if (!(weights(k) > 0.0) || !std::isfinite(weights(k)))
      throw std::invalid_argument(std::string(who) + ": weight " + std::to_string(k) + " must be > 0 and finite");
  return weights;
}

// Ascending coefficients c evaluated at x (Horner).
Complex PolyAsc(const Eigen::VectorXd& c, Complex x) {
  Complex v = 0.0;
  for (int j = static_cast<int>(c.size()) - 1; j >= 0; --j) v = v * x + c(j);
  return v;
}

// Weighted output error r_k = w_k (B(p̃_k)/A(p̃_k) − G_k) of the scaled coefficients
// x = [ã_0 … ã_{n−1} | b̃_0 … b̃_m] (ã_n = 1), real and imaginary parts stacked; the Jacobian
// ∂r/∂ã_j = −w B p̃^j / A², ∂r/∂b̃_j = w p̃^j / A.
struct OutputErrorFunctor : Eigen::DenseFunctor<double> {
  OutputErrorFunctor(int n, int m, const Eigen::VectorXcd& p, const Eigen::VectorXcd& g, const Eigen::VectorXd& w)
      : Eigen::DenseFunctor<double>(n + m + 1, 2 * static_cast<int>(p.size())), n(n), m(m), p(p), g(g), w(w) {}
  int n, m;
  const Eigen::VectorXcd &p, &g;
  const Eigen::VectorXd& w;
  void Split(const Eigen::VectorXd& x, Eigen::VectorXd* a, Eigen::VectorXd* b) const {
    a->resize(n + 1);
    a->head(n) = x.head(n);
    (*a)(n) = 1.0;
    *b = x.tail(m + 1);
  }
  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& fvec) const {
    Eigen::VectorXd a, b;
    Split(x, &a, &b);
    const int lines = static_cast<int>(p.size());
    for (int k = 0; k < lines; ++k) {
      const Complex r = w(k) * (PolyAsc(b, p(k)) / PolyAsc(a, p(k)) - g(k));
      fvec(k) = r.real();
      fvec(lines + k) = r.imag();
    }
    return 0;
  }
  int df(const Eigen::VectorXd& x, Eigen::MatrixXd& jac) const {
    Eigen::VectorXd a, b;
    Split(x, &a, &b);
    const int lines = static_cast<int>(p.size());
    for (int k = 0; k < lines; ++k) {
      const Complex av = PolyAsc(a, p(k)), bv = PolyAsc(b, p(k));
      const Complex da = -w(k) * bv / (av * av), db = w(k) / av;
      Complex pj = 1.0;
      for (int j = 0; j <= std::max(n - 1, m); ++j, pj *= p(k)) {
        if (j < n) {
          jac(k, j) = (da * pj).real();
          jac(lines + k, j) = (da * pj).imag();
        }
        if (j <= m) {
          jac(k, n + j) = (db * pj).real();
          jac(lines + k, n + j) = (db * pj).imag();
        }
      }
    }
    return 0;
  }
};
}  // namespace

double FrfCost(const Frf& frf, const Eigen::VectorXcd& model, const Eigen::VectorXd& weights) {
  double cost = 0.0;
  for (int k = 0; k < frf.NumLines(); ++k) {
    const double w = weights.size() ? weights(k) : 1.0;
    cost += w * w * std::norm(model(k) - frf.h[k](0, 0));
  }
  return cost;
}

double FrfFitPercent(const Frf& frf, const Eigen::VectorXcd& model, const Eigen::VectorXd& weights) {
  double r = 0.0, g = 0.0;
  for (int k = 0; k < frf.NumLines(); ++k) {
    const double w2 = weights.size() ? weights(k) * weights(k) : 1.0;
    r += w2 * std::norm(model(k) - frf.h[k](0, 0));
    g += w2 * std::norm(frf.h[k](0, 0));
  }
  return g > 0.0 ? 100.0 * (1.0 - std::sqrt(r / g)) : 0.0;
}

LevyResult FitLevy(const Frf& frf, const LevyOptions& options) {
  ValidateFrf(frf);
  if (frf.NumOutputs() != 1 || frf.NumInputs() != 1)
    throw std::invalid_argument("Levy: a SISO FRF is expected (pick one output/input element)");
  const int n = options.denominator_degree, m = options.numerator_degree;
  if (n < 1) throw std::invalid_argument("Levy: denominator_degree must be >= 1");
  if (m < 0) throw std::invalid_argument("Levy: numerator_degree must be >= 0");
  const int lines = frf.NumLines(), unknowns = n + m + 1;
  if (2 * lines < unknowns)
    throw std::invalid_argument("Levy: " + std::to_string(lines) + " lines give " +
                                std::to_string(2 * lines) + " real equations for " +
                                std::to_string(unknowns) + " unknown coefficients; use more lines or lower degrees");
  if (options.max_sk_iterations < 0) throw std::invalid_argument("Levy: max_sk_iterations must be >= 0");
  const Eigen::VectorXd w = CheckedWeights(options.weights, lines, "Levy");
  const double ws = frf.omega.maxCoeff();  // frequency scaling p̃ = p/ω_s

  Eigen::VectorXcd p(lines), g(lines);
  for (int k = 0; k < lines; ++k) {
    p(k) = Complex(0.0, frf.omega(k) / ws);
    g(k) = frf.h[k](0, 0);
  }
  // Unknowns c = [a_0 … a_{n−1} | b_0 … b_m] (scaled variable), a_n = 1.
  // Eq. (5) of [Balda]: [G, pG, …, p^{n−1}G | −1, −p, …, −p^m] c ≐ −p^n G, real and imaginary
  // parts stacked, every row scaled by its weight. Eq. (7), c = A⁺y, by Householder QR reduced
  // block by block (R of [A | y] updated with 256 lines at a time): no 2L×(n+m+1) matrix is
  // ever formed, and the cost is linear in L.
  const int width = unknowns + 1;
  constexpr int kBlock = 256;
  Eigen::MatrixXd work(2 * kBlock + width, width);
  auto solve = [&](const Eigen::VectorXd& row_scale, Eigen::VectorXd* a, Eigen::VectorXd* b) {
    Eigen::MatrixXd r = Eigen::MatrixXd::Zero(width, width);
    for (int start = 0; start < lines; start += kBlock) {
      const int count = std::min(kBlock, lines - start);
      const int rows = 2 * count + width;
      work.topRows(width) = r;
      for (int i = 0; i < count; ++i) {
        const int k = start + i;
        const double s = row_scale(k);
        Complex pj = s;
        const int re = width + i, im = width + count + i;
        for (int j = 0; j <= std::max(n, m); ++j, pj *= p(k)) {
          if (j < n) {
            const Complex v = pj * g(k);
            work(re, j) = v.real();
            work(im, j) = v.imag();
          } else if (j == n) {
            const Complex v = -pj * g(k);
            work(re, unknowns) = v.real();
            work(im, unknowns) = v.imag();
          }
          if (j <= m) {
            work(re, n + j) = -pj.real();
            work(im, n + j) = -pj.imag();
          }
        }
      }
      auto block = work.topRows(rows);
      Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(block);
      r = block.topRows(width).triangularView<Eigen::Upper>();
    }
    // R c = Qᵀy: the first `unknowns` rows of the reduced [R | Qᵀy].
    const Eigen::MatrixXd rr = r.topLeftCorner(unknowns, unknowns);
    Eigen::VectorXd col(unknowns);
    for (int j = 0; j < unknowns; ++j) col(j) = rr.col(j).norm();  // = ‖A(:, j)‖
    const Eigen::VectorXd rel = rr.diagonal().cwiseAbs().cwiseQuotient(col.cwiseMax(1e-300));
    const bool deficient = !(rel.minCoeff() > 1e-13);
    const Eigen::VectorXd c = rr.triangularView<Eigen::Upper>().solve(r.col(unknowns).head(unknowns));
    a->resize(n + 1);
    a->head(n) = c.head(n);
    (*a)(n) = 1.0;
    *b = c.tail(m + 1);
    return deficient;
  };
  auto response = [&](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    Eigen::VectorXcd r(lines);
    for (int k = 0; k < lines; ++k) r(k) = PolyAsc(b, p(k)) / PolyAsc(a, p(k));
    return r;
  };

  LevyResult result;
  Eigen::VectorXd a, b;
  bool rank_deficient = solve(w, &a, &b);
  result.cost_history.push_back(FrfCost(frf, response(a, b), w));
  result.sk_converged = options.max_sk_iterations == 0;
  for (int l = 1; l <= options.max_sk_iterations; ++l) {
    // Eq. (8): divide equation k by w_k^(l+1) = |A^(l)(p_k)|.
    Eigen::VectorXd scale(lines);
    for (int k = 0; k < lines; ++k) scale(k) = w(k) / std::max(std::abs(PolyAsc(a, p(k))), 1e-300);
    Eigen::VectorXd a_new, b_new;
    rank_deficient = solve(scale, &a_new, &b_new);
    Eigen::VectorXd old_c(n + m + 2), new_c(n + m + 2);
    old_c << a, b;
    new_c << a_new, b_new;
    a = a_new;
    b = b_new;
    result.sk_iterations = l;
    result.relative_change = (new_c - old_c).norm() / std::max(new_c.norm(), 1e-300);
    result.cost_history.push_back(FrfCost(frf, response(a, b), w));
    if (!a.allFinite() || !b.allFinite()) break;
    if (result.relative_change < options.coefficient_tolerance) {
      result.sk_converged = true;
      break;
    }
  }
  result.sk_cost = result.cost_history.back();
  bool refine_stopped = false;
  if (options.refine_output_error && a.allFinite() && b.allFinite()) {
    OutputErrorFunctor functor(n, m, p, g, w);
    Eigen::VectorXd x(n + m + 1);
    x << a.head(n), b;
    Eigen::LevenbergMarquardt<OutputErrorFunctor> lm(functor);
    lm.setMaxfev(options.max_function_evaluations);
    lm.setFtol(1e-12);
    lm.setXtol(1e-12);
    const auto status = lm.minimize(x);
    Eigen::VectorXd a_r, b_r;
    functor.Split(x, &a_r, &b_r);
    const double cost = x.allFinite() ? FrfCost(frf, response(a_r, b_r), w) : std::numeric_limits<double>::infinity();
    result.refine_iterations = static_cast<int>(lm.iterations());
    if (cost < result.sk_cost) {
      a = a_r;
      b = b_r;
      result.refined = true;
      result.cost_history.push_back(cost);
      refine_stopped = status == Eigen::LevenbergMarquardtSpace::TooManyFunctionEvaluation;
    }
  }
  // Unscale: a_j = ã_j / ω_s^j, then make the denominator monic again.
  Eigen::VectorXd a_u(n + 1), b_u(m + 1);
  for (int j = 0; j <= n; ++j) a_u(j) = a(j) / std::pow(ws, j);
  for (int j = 0; j <= m; ++j) b_u(j) = b(j) / std::pow(ws, j);
  const double lead = a_u(n);
  result.model.den = a_u.reverse() / lead;
  result.model.num = b_u.reverse() / lead;
  result.iterations = 1 + result.sk_iterations + result.refine_iterations;
  const Eigen::VectorXcd fitted = response(a, b);
  result.final_cost = FrfCost(frf, fitted, w);
  result.fit_percent = FrfFitPercent(frf, fitted, w);
  if (!result.model.den.allFinite() || !result.model.num.allFinite()) {
    result.status = SolverStatus::kFailed;
    result.message = "the regression produced non-finite coefficients";
    return result;
  }
  result.poles = PolynomialRoots(result.model.den);
  result.stable = (result.poles.real().array() < 0.0).all();
  if (refine_stopped) {
    result.status = SolverStatus::kNotConverged;
    result.message = "the output-error refinement stopped at the function-evaluation limit (" +
                     std::to_string(options.max_function_evaluations) + ")";
  } else if (!result.sk_converged && !result.refined) {
    result.status = SolverStatus::kNotConverged;
    result.message = "Sanathanan-Koerner iterations did not settle in " +
                     std::to_string(options.max_sk_iterations) + " iterations (last relative change " +
                     std::to_string(result.relative_change) + ")";
  } else if (rank_deficient) {
    result.status = SolverStatus::kIllConditioned;
    result.message = "the regressor is rank deficient: lower the degrees";
  } else {
    result.status = SolverStatus::kOk;
    result.message = options.max_sk_iterations == 0
                         ? "plain Levy solution"
                         : (result.sk_converged ? "SK converged after " : "SK stopped after ") +
                               std::to_string(result.sk_iterations) + " iterations";
    if (result.refined)
      result.message += ", then the output error minimised (" + std::to_string(result.refine_iterations) +
                        " Levenberg-Marquardt iterations, cost " + std::to_string(result.sk_cost) + " -> " +
                        std::to_string(result.cost_history.back()) + ")";
  }
  if (!result.stable) result.message += "; the model is unstable (a pole has Re s >= 0)";
  return result;
}

}  // namespace idrig
