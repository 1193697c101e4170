#include "core/numeric/time_domain/arx.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace idrig {
namespace {

[[noreturn]] void Fail(const std::string& what) { throw std::invalid_argument("arx: " + what); }

using ConstVec = Eigen::Ref<const Eigen::VectorXd>;

// Equation layout of (2.9)–(2.10): predicted samples k = k0, k0 + q, …, at most L of them.
struct EquationPlan {
  int order = 0, delay = 1, q = 1;
  long first = 0, count = 0;
  long Index(long i) const { return first + i * q; }
};

EquationPlan PlanEquations(long samples, int order, const ArxOptions& options) {
  EquationPlan plan;
  plan.order = order;
  plan.delay = options.input_delay;
  plan.q = options.decimation;
  const long earliest = std::max<long>(order, order + options.input_delay - 1);
  plan.first = options.first_equation >= 0 ? options.first_equation : earliest;
  if (plan.first < earliest)
    Fail("first equation k = " + std::to_string(plan.first) + " needs samples before 0; use k >= " +
         std::to_string(earliest));
  plan.count = plan.first < samples ? (samples - 1 - plan.first) / plan.q + 1 : 0;
  if (options.max_equations > 0) plan.count = std::min<long>(plan.count, options.max_equations);
  return plan;
}

// Row f_{k−1} of (2.8): (y_{k−1} … y_{k−n} | u_{k−nk} … u_{k−nk−n+1}).
template <typename Row>
void FillRow(ConstVec y, ConstVec u, const EquationPlan& plan, long k,
             Row&& row) {
  const int n = plan.order;
  for (int i = 0; i < n; ++i) row(i) = y(k - 1 - i);
  for (int i = 0; i < n; ++i) row(n + i) = u(k - plan.delay - i);
}

// QR in blocks of [F_L Y_L]: returns the (p+1)×(p+1) upper triangle R with RᵀR = [F Y]ᵀ[F Y].
Eigen::MatrixXd TriangleOfEquations(ConstVec y, ConstVec u,
                                    const EquationPlan& plan) {
  const int p = 2 * plan.order;
  constexpr long kBlockRows = 1024;
  Eigen::MatrixXd stack(kBlockRows + p + 1, p + 1);
  Eigen::MatrixXd triangle = Eigen::MatrixXd::Zero(p + 1, p + 1);
  long i = 0;
  while (i < plan.count) {
    const long rows = std::min(kBlockRows, plan.count - i);
    stack.topRows(p + 1) = triangle;
    for (long r = 0; r < rows; ++r, ++i) {
      const long k = plan.Index(i);
      auto row = stack.row(p + 1 + r);
      FillRow(y, u, plan, k, row);
      row(p) = y(k);
    }
    const auto used = stack.topRows(p + 1 + rows);
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(used);
    triangle = qr.matrixQR().topRows(p + 1).triangularView<Eigen::Upper>();
  }
  return triangle;
}

struct TriangleSolve {
  Eigen::VectorXd g;
  double epsilon = 0.0;
  double rss = 0.0;
  double effective_parameters = 0.0;
  double condition_number = 0.0;
  Eigen::MatrixXd unscaled_covariance;  // (F'F+εE)⁻¹ F'F (F'F+εE)⁻¹
};

// Regularised solution (2.11) from the triangle: with R11 = U S Vᵀ and z = Uᵀ R12,
// ĝ(ε) = V diag(s/(s²+ε)) z,  RSS(ε) = ρ² + Σ (ε z_i/(s_i²+ε))².
TriangleSolve SolveFromTriangle(const Eigen::MatrixXd& triangle, long equations, double epsilon) {
  const int p = static_cast<int>(triangle.rows()) - 1;
  const Eigen::MatrixXd r11 = triangle.topLeftCorner(p, p);
  const Eigen::VectorXd r12 = triangle.topRightCorner(p, 1);
  const double rho2 = triangle(p, p) * triangle(p, p);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(r11, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::VectorXd s = svd.singularValues();
  const Eigen::VectorXd z = svd.matrixU().transpose() * r12;
  auto rss_at = [&](double eps) {
    double rss = rho2;
    for (int i = 0; i < p; ++i) {
      const double r = eps * z(i) / (s(i) * s(i) + eps);
      rss += r * r;
    }
    return rss;
  };
  auto trace_at = [&](double eps) {
    double tr = 0.0;
    for (int i = 0; i < p; ++i) tr += s(i) * s(i) / (s(i) * s(i) + eps);
    return tr;
  };
  TriangleSolve out;
  out.condition_number = s(p - 1) > 0.0 ? s(0) / s(p - 1) : std::numeric_limits<double>::infinity();
  if (epsilon < 0.0) {
    // GCV(ε) = L·RSS(ε)/(L − tr H(ε))², minimised on a logarithmic grid spanning the squared
    // singular values, then refined by golden section in log ε.
    const double smax2 = std::max(s(0) * s(0), std::numeric_limits<double>::min());
    auto gcv = [&](double log_eps) {
      const double eps = std::exp(log_eps);
      const double dof = static_cast<double>(equations) - trace_at(eps);
      if (dof <= 0.0) return std::numeric_limits<double>::infinity();
      return equations * rss_at(eps) / (dof * dof);
    };
    const double lo = std::log(smax2 * 1e-18), hi = std::log(smax2);
    constexpr int kGrid = 120;
    int best = 0;
    double best_value = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= kGrid; ++i) {
      const double v = gcv(lo + (hi - lo) * i / kGrid);
      if (v < best_value) { best_value = v; best = i; }
    }
    double a = lo + (hi - lo) * std::max(0, best - 1) / kGrid;
    double b = lo + (hi - lo) * std::min(kGrid, best + 1) / kGrid;
    const double ratio = (std::sqrt(5.0) - 1.0) / 2.0;
    for (int it = 0; it < 60; ++it) {
      const double x1 = b - ratio * (b - a), x2 = a + ratio * (b - a);
      if (gcv(x1) < gcv(x2)) b = x2; else a = x1;
    }
    epsilon = std::exp(0.5 * (a + b));
  }
  out.epsilon = epsilon;
  Eigen::VectorXd filter(p), cov_weights(p);
  for (int i = 0; i < p; ++i) {
    const double denom = s(i) * s(i) + epsilon;
    filter(i) = denom > 0.0 ? s(i) / denom : 0.0;
    cov_weights(i) = denom > 0.0 ? s(i) * s(i) / (denom * denom) : 0.0;
  }
  out.g = svd.matrixV() * filter.cwiseProduct(z);
  out.rss = rss_at(epsilon);
  out.effective_parameters = trace_at(epsilon);
  out.unscaled_covariance = svd.matrixV() * cov_weights.asDiagonal() * svd.matrixV().transpose();
  return out;
}

// Filters x through 1/A(q), A(q) = 1 + c_1 q⁻¹ + … + c_n q⁻ⁿ, from rest.
Eigen::VectorXd FilterByInverseA(ConstVec x, const Eigen::VectorXd& c) {
  Eigen::VectorXd out(x.size());
  for (long k = 0; k < x.size(); ++k) {
    double v = x(k);
    for (int i = 0; i < c.size() && k - 1 - i >= 0; ++i) v -= c(i) * out(k - 1 - i);
    out(k) = v;
  }
  return out;
}

// Reflects the roots of A(z) outside the unit circle to 1/conj(z) so that 1/A is a stable filter.
Eigen::VectorXd StabilisedDenominator(const Eigen::VectorXd& c) {
  Eigen::VectorXd den(c.size() + 1);
  den << 1.0, c;
  Eigen::VectorXcd roots = PolynomialRoots(den);
  for (int i = 0; i < roots.size(); ++i)
    if (std::abs(roots(i)) >= 1.0) roots(i) = 1.0 / std::conj(roots(i));
  return PolynomialFromRoots(roots).tail(c.size());
}

Eigen::VectorXd SimulateDifferenceEquation(ConstVec u, const Eigen::VectorXd& c,
                                           const Eigen::VectorXd& d, int delay) {
  const int n = static_cast<int>(c.size());
  Eigen::VectorXd y = Eigen::VectorXd::Zero(u.size());
  for (long k = 0; k < u.size(); ++k) {
    double v = 0.0;
    for (int i = 0; i < n; ++i) {
      if (k - 1 - i >= 0) v -= c(i) * y(k - 1 - i);
      if (k - delay - i >= 0) v += d(i) * u(k - delay - i);
    }
    y(k) = v;
  }
  return y;
}

Eigen::VectorXd OneStepResiduals(ConstVec y, ConstVec u,
                                 const EquationPlan& plan, const Eigen::VectorXd& g) {
  EquationPlan all = plan;
  all.q = 1;
  all.first = std::max<long>(plan.order, plan.order + plan.delay - 1);
  all.count = y.size() - all.first;
  Eigen::VectorXd e(std::max<long>(all.count, 0));
  Eigen::VectorXd f(g.size());
  for (long i = 0; i < all.count; ++i) {
    const long k = all.Index(i);
    FillRow(y, u, all, k, f);
    e(i) = y(k) - f.dot(g);
  }
  return e;
}

// Steiglitz–McBride iterations (Ljung, System Identification, 2nd ed., §10.4): refit on u, y
// prefiltered by 1/Â(q); the fixed point is the output-error estimate, which is unbiased under
// white output noise where equation-error ARX is not. Returns the number of fits made.
// *last_change: relative change of g in the last fit (0 when no refinement ran).
int RefineOutputError(ConstVec y, ConstVec u, int order,
                      const ArxOptions& options, Eigen::VectorXd* g, double* last_change);

struct Fit {
  TriangleSolve solve;
  EquationPlan plan;
  Eigen::VectorXd c, d;
  int iterations = 1;
  double oe_change = 0.0;  // relative change of g in the last Steiglitz–McBride fit
};

Fit FitOrder(ConstVec y, ConstVec u, int order,
             const ArxOptions& options) {
  Fit fit;
  fit.plan = PlanEquations(y.size(), order, options);
  if (fit.plan.count < 2 * order)
    Fail("order " + std::to_string(order) + " needs at least " + std::to_string(2 * order) +
         " equations (2n parameters), the record gives " + std::to_string(fit.plan.count) + " (" +
         std::to_string(y.size()) + " samples, q = " + std::to_string(options.decimation) + ")");
  const Eigen::MatrixXd triangle = TriangleOfEquations(y, u, fit.plan);
  fit.solve = SolveFromTriangle(triangle, fit.plan.count, options.epsilon);
  if (options.oe_iterations > 0)
    fit.iterations = RefineOutputError(y, u, order, options, &fit.solve.g, &fit.oe_change);
  fit.c = -fit.solve.g.head(order);
  fit.d = fit.solve.g.tail(order);
  return fit;
}

int RefineOutputError(ConstVec y, ConstVec u, int order,
                      const ArxOptions& options, Eigen::VectorXd* g, double* last_change) {
  int fits = 1;
  *last_change = 0.0;
  for (int it = 0; it < options.oe_iterations; ++it) {
    const Eigen::VectorXd c_now = StabilisedDenominator(-g->head(order));
    const Eigen::VectorXd uf = FilterByInverseA(u, c_now), yf = FilterByInverseA(y, c_now);
    const EquationPlan plan = PlanEquations(y.size(), order, options);
    const TriangleSolve refit = SolveFromTriangle(TriangleOfEquations(yf, uf, plan), plan.count, options.epsilon);
    const double change = (refit.g - *g).norm() / std::max(1e-300, g->norm());
    *g = refit.g;
    ++fits;
    *last_change = change;
    if (change < 1e-10) break;
  }
  return fits;
}

}  // namespace

RegularisedSolution SolveRegularised(const Eigen::MatrixXd& F, const Eigen::VectorXd& Y,
                                     double epsilon) {
  if (F.rows() != Y.size()) Fail("F has " + std::to_string(F.rows()) + " rows but Y has " + std::to_string(Y.size()));
  if (!F.allFinite() || !Y.allFinite()) Fail("F or Y contains NaN or Inf");
  RegularisedSolution out;
  const Eigen::MatrixXd gram = F.transpose() * F;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(F);
  const auto& s = svd.singularValues();
  out.condition_number = s(s.size() - 1) > 0 ? s(0) / s(s.size() - 1) : std::numeric_limits<double>::infinity();
  // Eq. (2.11) literally: (εE + FᵀF)⁻¹ FᵀY.
  const Eigen::MatrixXd lhs = gram + epsilon * Eigen::MatrixXd::Identity(F.cols(), F.cols());
  Eigen::LDLT<Eigen::MatrixXd> ldlt(lhs);
  out.g = ldlt.solve(F.transpose() * Y);
  out.epsilon = epsilon;
  out.residual_sum_squares = (Y - F * out.g).squaredNorm();
  const double rcond = ldlt.rcond();
  if (ldlt.info() != Eigen::Success || !out.g.allFinite()) out.status = SolverStatus::kFailed;
  else if (rcond < 1e-14) out.status = SolverStatus::kIllConditioned;
  return out;
}

std::string ArxResult::DifferenceEquation() const {
  std::ostringstream s;
  s.precision(6);
  s << "y[k]";
  for (int i = 0; i < c.size(); ++i) s << (c(i) < 0 ? " - " : " + ") << std::abs(c(i)) << " y[k-" << i + 1 << "]";
  s << " =";
  for (int i = 0; i < d.size(); ++i)
    s << (i == 0 ? (d(i) < 0 ? " -" : " ") : (d(i) < 0 ? " - " : " + ")) << std::abs(d(i)) << " u[k-"
      << input_delay + i << "]";
  return s.str();
}

ArxResult IdentifyArx(const IoRecord& record, const ArxOptions& options) {
  if (record.NumInputs() != 1 || record.NumOutputs() != 1)
    Fail("the ARX method is single-input single-output; the record has " +
         std::to_string(record.NumInputs()) + " inputs and " + std::to_string(record.NumOutputs()) +
         " outputs (select one pair of columns)");
  ValidateIoRecord(record, 3);
  if (options.order < 0 || options.max_order < 1) Fail("order must be >= 1 (or 0 for automatic)");
  if (options.decimation < 1) Fail("decimation q must be >= 1");
  if (options.input_delay < 1) Fail("input delay nk must be >= 1 sample");
  if (!std::isfinite(options.epsilon)) Fail("epsilon must be a finite number (or negative for GCV)");
  const ConstVec y = record.y.col(0);
  const ConstVec u = record.u.col(0);
  const double u_spread = u.maxCoeff() - u.minCoeff();
  if (!(u_spread > 1e-12 * std::max(1.0, u.cwiseAbs().maxCoeff())))
    Fail("the input is constant (" + std::to_string(u(0)) +
         "): it is not persistently exciting, so no dynamics can be identified; for a step "
         "response use the step path (auxiliary link, Eqs. (2.5)-(2.6))");

  ArxResult result;
  result.sample_time = record.sample_time;
  result.input_delay = options.input_delay;
  int order = options.order;
  if (order == 0) {
    // Order by cross-validation: fit each n on the first two thirds, simulate the whole record
    // from rest and score the last third; take the smallest n within 2 % of the best NRMSE.
    // (MDL on equation errors is reported too, but over-fits when the noise is not ARX noise.)
    const long split = 2 * static_cast<long>(y.size()) / 3;
    const Eigen::VectorXd y_est = y.head(split), u_est = u.head(split);
    double best_nrmse = std::numeric_limits<double>::infinity();
    for (int n = 1; n <= options.max_order; ++n) {
      const EquationPlan plan = PlanEquations(split, n, options);
      if (plan.count < 2 * n + 1) break;
      const Fit fit = FitOrder(y_est, u_est, n, options);
      ArxOrderCandidate cand;
      cand.order = n;
      cand.equations = static_cast<int>(plan.count);
      cand.residual_sum_squares = fit.solve.rss;
      const double per_eq = std::max(fit.solve.rss / plan.count, std::numeric_limits<double>::min());
      cand.mdl = plan.count * std::log(per_eq) + 2.0 * n * std::log(static_cast<double>(plan.count));
      cand.epsilon = fit.solve.epsilon;
      const Eigen::VectorXd sim = SimulateDifferenceEquation(u, fit.c, fit.d, options.input_delay);
      const long tail = y.size() - split;
      cand.validation_nrmse = Nrmse(y.tail(tail), sim.tail(tail))(0);
      cand.fit_percent = 100.0 * (1.0 - cand.validation_nrmse);
      if (!std::isfinite(cand.validation_nrmse)) cand.validation_nrmse = std::numeric_limits<double>::infinity();
      best_nrmse = std::min(best_nrmse, cand.validation_nrmse);
      result.order_table.push_back(cand);
    }
    for (const auto& cand : result.order_table) {
      if (cand.validation_nrmse <= 1.02 * best_nrmse + 1e-9) { order = cand.order; break; }
    }
    if (order == 0) Fail("the record is too short for any order (" + std::to_string(y.size()) + " samples)");
  }
  Fit fit = FitOrder(y, u, order, options);
  result.order = order;
  result.equations = static_cast<int>(fit.plan.count);
  result.epsilon = fit.solve.epsilon;
  result.epsilon_rule = options.epsilon < 0.0 ? "gcv" : "user";
  result.condition_number = fit.solve.condition_number;
  result.g = fit.solve.g;
  if (!result.g.allFinite()) {
    std::ostringstream m;
    m << "the least-squares solution is not finite (order " << order
      << "): the record's sums of squares overflow (max |u| " << u.cwiseAbs().maxCoeff()
      << ", max |y| " << y.cwiseAbs().maxCoeff() << "); rescale the record";
    Fail(m.str());
  }
  result.iterations = fit.iterations;
  const double dof = std::max(1.0, fit.plan.count - fit.solve.effective_parameters);
  result.noise_variance = fit.solve.rss / dof;
  result.covariance = result.noise_variance * fit.solve.unscaled_covariance;
  result.final_cost = fit.solve.rss;
  result.c = -result.g.head(order);
  result.d = result.g.tail(order);
  result.g_std = result.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  if (options.oe_iterations > 0)
    result.warnings.push_back("covariance is that of the first least-squares fit (before the output-error refinement)");

  // Steps 2–3: Rd1 by (1.12)–(1.13) and W(z) by (1.14).
  Eigen::VectorXd den_z(order + 1);
  den_z(0) = 1.0;
  den_z.tail(order) = result.c;
  result.discrete_compact = CompactObservableForm(result.d, den_z);
  result.discrete_tf.num = result.d;
  result.discrete_tf.den = den_z;
  result.discrete_tf.sample_time = record.sample_time;
  result.discrete_tf.delay_s = (options.input_delay - 1) * record.sample_time;
  // y(∞) by (2.4) and by (1.15).
  result.y_inf_sum = result.d.sum() / (1.0 + result.c.sum());
  {
    const Eigen::MatrixXd e_minus_phi = Eigen::MatrixXd::Identity(order, order) - result.discrete_compact.A;
    result.y_inf_matrix = (result.discrete_compact.H * e_minus_phi.fullPivLu().solve(result.discrete_compact.B))(0);
  }

  if (options.validate) {
    // Validation on the record: simulation fit and one-step residuals.
    const Eigen::VectorXd sim = SimulateDifferenceEquation(u, result.c, result.d, options.input_delay);
    result.fit_percent = FitPercent(y, sim)(0);
    // Residuals: one-step prediction errors for ARX; simulation errors for the output-error fit,
    // whose noise model is white output noise.
    const Eigen::VectorXd e = options.oe_iterations > 0 ? Eigen::VectorXd(y - sim)
                                                        : OneStepResiduals(y, u, fit.plan, result.g);
    const Eigen::VectorXd u_aligned = u.tail(e.size());
    ResidualTestOptions rto = options.residual_test;
    rto.max_lag = std::min<int>(rto.max_lag, std::max<int>(1, static_cast<int>(e.size()) / 4));
    if (e.size() > rto.max_lag + 2) {
      result.residuals = TestResiduals(e, u_aligned, rto);
      if (!result.residuals.white && options.oe_iterations == 0)
        result.warnings.push_back(
            "one-step residuals are not white: the noise is not the equation error ARX assumes "
            "(e.g. output measurement noise), so these least-squares estimates are biased; "
            "try the output-error refinement (method arx-oe)");
    }
  }

  result.status = SolverStatus::kOk;
  if (result.condition_number > 1e12 && result.epsilon == 0.0) {
    result.status = SolverStatus::kIllConditioned;
    result.message = "F_L is ill-conditioned (cond " + std::to_string(result.condition_number) +
                     ") and epsilon = 0: the solution is not determined; use epsilon > 0";
  }
  result.oe_relative_change = fit.oe_change;
  std::string not_converged;
  if (options.oe_iterations > 0 && !(fit.oe_change <= options.oe_tolerance)) {
    result.status = SolverStatus::kNotConverged;
    std::ostringstream m;
    m << "the Steiglitz-McBride iterations did not converge: the parameters still changed by "
      << fit.oe_change << " (relative) in the last of " << options.oe_iterations
      << " fits (tolerance " << options.oe_tolerance << "); raise oe_iterations or lower the order";
    not_converged = m.str();
    result.warnings.push_back(not_converged);
  }

  // Steps 4–7: R* by (1.16), R1* by (1.7), W(p) by (1.3)–(1.4).
  if (options.recover_continuous) {
    const Eigen::VectorXcd zpoles = PolynomialRoots(den_z);
    bool negative_real = false;
    for (int i = 0; i < zpoles.size(); ++i)
      if (zpoles(i).real() <= 0.0 && std::abs(zpoles(i).imag()) < 1e-9) negative_real = true;
    result.log_series = ContinuousFromDiscreteBySeries(result.discrete_compact.A, result.discrete_compact.B,
                                                       record.sample_time, options.log_series_terms);
    if (negative_real || !result.log_series.converged) {
      result.continuous_message =
          "no continuous equivalent: W(z) has a pole on the non-positive real axis "
          "(the logarithmic series (1.16) diverges, rho(X) = " +
          std::to_string(result.log_series.spectral_radius_x) +
          "); lower the order or the sample time";
      result.warnings.push_back(result.continuous_message);
    } else {
      try {
        result.continuous_compact =
            ToCompactForm(result.log_series.A, result.log_series.B, result.discrete_compact.H);
        Eigen::VectorXd num, den;
        CompactFormCoefficients(result.continuous_compact, &num, &den);
        result.continuous_tf.num = num;
        result.continuous_tf.den = den;
        result.continuous_tf.delay_s = (options.input_delay - 1) * record.sample_time;
        result.continuous_recovered = true;
      } catch (const std::invalid_argument& ex) {
        result.continuous_message = std::string("no continuous compact form: ") + ex.what();
        result.warnings.push_back(result.continuous_message);
      }
    }
  }
  if (result.message.empty()) {
    std::ostringstream m;
    m << "order " << order << ", " << result.equations << " equations, epsilon " << result.epsilon
      << " (" << result.epsilon_rule << "), fit " << result.fit_percent << " %";
    result.message = m.str();
  }
  if (!not_converged.empty()) result.message += "; " + not_converged;
  return result;
}

ArxResult IdentifyArxFromStep(const Eigen::VectorXd& step_response, double sample_time,
                              const StepArxOptions& options) {
  if (!(sample_time > 0.0)) Fail("step path: sample time must be positive");
  if (!step_response.allFinite()) Fail("step path: the step response contains NaN or Inf");
  if (!(std::abs(options.step_amplitude) > 0.0)) Fail("step path: step amplitude must be non-zero");
  const long n = step_response.size();
  if (n < 8) Fail("step path: at least 8 samples of the step response are needed");
  const Eigen::VectorXd h = step_response / options.step_amplitude;
  const double ta = options.auxiliary_time_constant > 0.0 ? options.auxiliary_time_constant
                                                          : 0.1 * n * sample_time;
  // Eq. (2.5): u(p) = U(p)/p with U(p) = 1/(T_a p + 1), i.e. u(t) = 1 − e^(−t/T_a), on the grid.
  Eigen::VectorXd u(n), f = Eigen::VectorXd::Zero(n);
  for (long k = 0; k < n; ++k) u(k) = 1.0 - std::exp(-k * sample_time / ta);
  // Eq. (2.6): f = U(p)·h(p) — for a held input, superposition of step responses.
  for (long j = 0; j < n; ++j) {
    const double du = u(j) - (j > 0 ? u(j - 1) : 0.0);
    if (du == 0.0) continue;
    f.tail(n - j) += du * h.head(n - j);
  }
  IoRecord record = MakeIoRecord(u, f, sample_time);
  return IdentifyArx(record, options.arx);
}

}  // namespace idrig
