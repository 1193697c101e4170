// Step-response identification with multiple complex poles, [Vidinčev] (seed 000): the driver —
// x(∞) (6), the spacing h (9), the order by minimum residual (36)–(41), multiplicities. The other
// parts are listed in step_prony_internal.h.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/numeric/time_domain/step_prony_internal.h"
#include "core/numeric/validation.h"

namespace idrig {

using namespace step_prony_detail;  // NOLINT: the internal parts of this one method

namespace {

[[noreturn]] void Fail(const std::string& what) { throw std::invalid_argument("step-prony: " + what); }


}  // namespace

StepPronyResult IdentifyStepResponse(const Eigen::VectorXd& x_in, double sample_time,
                                     double step_amplitude, const StepPronyOptions& options) {
  const int n = static_cast<int>(x_in.size());
  if (!(sample_time > 0.0) || !std::isfinite(sample_time)) Fail("sample time must be positive");
  if (!(std::abs(step_amplitude) > 0.0) || !std::isfinite(step_amplitude))
    Fail("the step amplitude C must be non-zero (the input does not step)");
  for (int k = 0; k < n; ++k)
    if (!std::isfinite(x_in(k))) Fail("output sample " + std::to_string(k) + " is NaN or infinite");
  if (options.order < 0 || options.max_order < 1) Fail("order must be >= 0 and max_order >= 1");
  if (options.spacing < 0 || options.blocks < 0) Fail("spacing and blocks must be >= 0");
  if (!(options.tail_fraction > 0.0 && options.tail_fraction < 0.5)) Fail("tail_fraction must be in (0, 0.5)");
  const int min_order = std::max(options.order, 1);
  if (n < 2 * min_order + 1 || n < 10)
    Fail("too few samples for order " + std::to_string(min_order) + ": the linear prediction (20) needs at least " +
         std::to_string(std::max(2 * min_order + 1, 10)) + " samples, the record has " + std::to_string(n));

  StepPronyResult result;
  result.sample_time = sample_time;
  result.step_amplitude = step_amplitude;
  result.averaging = options.averaging;
  result.solver = options.solver;
  result.t = Eigen::VectorXd::LinSpaced(n, 0.0, (n - 1) * sample_time);
  result.measured = x_in;
  const Eigen::VectorXd& t = result.t;
  const Eigen::VectorXd& x = x_in;

  // x(∞) and the noise level from the tail: a straight line through the last samples. A slope
  // that moves the output by more than the tolerance over the tail means the record has not
  // settled and x(∞) (6) cannot be read off.
  const int tail = std::max(5, static_cast<int>(options.tail_fraction * n));
  const Eigen::VectorXd tt = t.tail(tail).array() - t(n - tail);
  const Eigen::VectorXd xt = x.tail(tail);
  Eigen::MatrixXd line(tail, 2);
  line.col(0).setOnes();
  line.col(1) = tt;
  const Eigen::Vector2d coef = line.colPivHouseholderQr().solve(xt);
  const double sigma = std::sqrt((xt - line * coef).squaredNorm() / std::max(1, tail - 2));
  const double range = (x.array() - x(0)).abs().maxCoeff();
  if (!(range > 0.0)) Fail("the output does not respond to the step (constant record)");
  const double drift = std::abs(coef(1)) * tt(tail - 1);
  const double allowed = options.settle_tolerance * range + 4.0 * sigma * std::sqrt(12.0 / tail);
  if (std::isnan(options.x_inf) && drift > allowed)
    Fail("the record never settles, so x(inf) (Eq. (6)) cannot be estimated: the output still moves by " +
         Num(drift) + " over the last " + Num(tt(tail - 1)) + " s (" + Num(100.0 * drift / range) +
         " % of its range, allowed " + Num(100.0 * allowed / range) +
         " %); record longer, or give x_inf explicitly");
  result.noise_sigma = sigma;
  result.x_inf_estimated = std::isnan(options.x_inf);
  result.x_inf = result.x_inf_estimated ? xt.mean() : options.x_inf;
  result.x_inf_tail = xt.mean();
  const Eigen::VectorXd xbar = result.x_inf - x.array();  // Eq. (7), for the transient length

  // Duration of the transient: last time the smoothed |x̄| exceeds 2 % of the range (or 4σ).
  const int smooth = std::max(1, n / 100);
  int last = 0;
  {
    double acc = 0.0;
    for (int k = 0; k < n; ++k) {
      acc += xbar(k);
      if (k >= smooth) acc -= xbar(k - smooth);
      const double mean = acc / std::min(k + 1, smooth);
      if (std::abs(mean) > std::max(0.02 * range, 4.0 * sigma / std::sqrt(smooth))) last = k;
    }
  }
  const double transient = std::max(last, 10) * sample_time;

  // Spacing h (9) and sub-intervals B (25).
  Grid grid;
  grid.averaging = options.averaging;
  grid.sample_time = sample_time;
  const int target_order = options.order > 0 ? options.order : options.max_order;
  grid.spacing = options.spacing > 0 ? options.spacing
                                     : std::max(1, static_cast<int>(std::lround(transient / (sample_time * 4.0 * target_order))));
  grid.blocks = options.averaging == StepAveraging::kBlock ? (options.blocks > 0 ? options.blocks : grid.spacing) : 1;
  if (grid.spacing % grid.blocks != 0)
    Fail("blocks B = " + std::to_string(grid.blocks) + " must divide the spacing " + std::to_string(grid.spacing) +
         " (samples per h) so that the sub-points of (25) fall on samples");
  const double h = grid.spacing * sample_time;
  result.h = h;
  result.spacing = grid.spacing;
  result.blocks = grid.blocks;

  const int points_all = grid.Points(n);
  const int horizon = static_cast<int>(std::ceil(options.horizon_factor * transient / h)) + 1;
  if (points_all < 2 * min_order + 1)
    Fail("too few samples for order " + std::to_string(min_order) + ": spacing h = " + Num(h) + " s gives " +
         std::to_string(points_all) + " LP points, at least " + std::to_string(2 * min_order + 1) +
         " are needed; give a smaller spacing or a longer record");
  const int usable = n - grid.Extent();  // start samples with a complete value
  const int length = std::min(usable, std::max(horizon * grid.spacing, (2 * min_order + 3) * grid.spacing + 1));
  // The LP sequence: (25), the integral, or point values of x̄ = x(∞) − x (7).
  auto make_sequence = [&](double x_inf) {
    const Eigen::VectorXd xbar_now = x_inf - x.array();  // Eq. (7)
    Eigen::VectorXd w(length);
    for (int k = 0; k < length; ++k) w(k) = grid.ReduceAt(xbar_now, k);
    return w;
  };
  Eigen::VectorXd lp_sequence = make_sequence(result.x_inf);
  const int lp_length = static_cast<int>(lp_sequence.size());
  // Equation starts: every sample (sliding) or the grid α h of the paper.
  const int stride = options.sliding ? 1 : grid.spacing;
  auto starts_for = [&](int m) {
    std::vector<int> starts;
    for (int k = 0; k + m * grid.spacing < lp_length; k += stride) starts.push_back(k);
    return starts;
  };
  const double noise_var = std::max(sigma * sigma, 1e-24 * x.squaredNorm() / n);

  // One candidate order: LP (20)/(30) → roots (18) → b (16) (a negative real root taken with
  // |z|) → refinement → least-squares fit over all samples.
  struct Candidate {
    LpSolution lp;
    Eigen::VectorXcd lp_poles, roots_z;  // roots_z after refinement
    double rss = 0.0, lp_residual = 0.0, x_inf_model = 0.0;
    int iterations = 0;
  };
  auto fit_order = [&](int m) {
    Candidate c;
    const std::vector<int> starts = starts_for(m);
    c.lp = SolveLp(lp_sequence, m, grid.spacing, starts, options.solver, options.columns);
    Eigen::VectorXd d1(m + 1);
    d1 << 1.0, c.lp.d;
    // (38)/(39): the residual of the prediction equations, divided by |(1, D)| (the noise part
    // then does not grow with m).
    const Eigen::VectorXd r = LpRows(lp_sequence, m, grid.spacing, starts) * d1 / d1.norm();
    c.lp_residual = std::sqrt(r.squaredNorm() / std::max<Eigen::Index>(1, r.size()));
    Eigen::VectorXcd b(c.lp.roots.size());
    for (int i = 0; i < b.size(); ++i) {
      const cd z = c.lp.roots(i);
      b(i) = std::abs(z.imag()) <= 1e-9 * (1.0 + std::abs(z)) ? cd(-std::log(std::abs(z.real())) / h, 0.0)
                                                              : -std::log(z) / h;  // Eq. (16)
    }
    c.lp_poles = -b;
    if (options.refine) b = RefineRoots(b, t, x, &c.iterations);
    c.roots_z = (-b * h).array().exp();
    std::vector<std::string> ignored;
    std::vector<StepPole> poles = ClusterRoots(c.roots_z, 0.0, h, &ignored);
    double cond = 0.0;
    c.rss = FitResiduesLs(x, t, step_amplitude, &poles, &cond);
    cd gain = 0.0;
    for (const auto& p : poles)
      for (int j = 1; j <= p.multiplicity; ++j) {
        const cd term = p.residues_ls(j - 1) / std::pow(p.b, p.multiplicity + 1 - j);  // Eq. (6)
        gain += p.complex_pair ? 2.0 * term.real() : term.real();
      }
    c.x_inf_model = step_amplitude * gain.real();
    return c;
  };

  // Order (36)–(41): every candidate m is reported with its prediction residual (38)/(39) and
  // the residual of the fitted model over all samples. The order is the smallest m whose
  // fitted residual is within the noise of the minimum (σ² χ²_0.999 of the extra parameters):
  // under noise the prediction residual alone flattens at the noise level.
  int order = options.order;
  Candidate chosen_candidate;
  if (order == 0) {
    std::vector<Candidate> candidates;
    for (int m = 1; m <= options.max_order; ++m) {
      if (static_cast<int>(starts_for(m).size()) < m + 1 ||
          (options.solver == StepLpSolver::kSubspace && m * grid.spacing * 3 >= lp_length))
        break;
      candidates.push_back(fit_order(m));
      StepOrderRow row;
      row.order = m;
      row.residual = candidates.back().lp_residual;
      row.condition_number = candidates.back().lp.cond;
      row.fit_rss = candidates.back().rss;
      result.order_table.push_back(row);
    }
    if (candidates.empty()) Fail("too few samples for order 1 with spacing h = " + Num(h) + " s");
    double best = std::numeric_limits<double>::infinity();
    for (const auto& c : candidates) best = std::min(best, c.rss);
    for (size_t i = 0; i < candidates.size(); ++i) {
      const int extra = 2 * static_cast<int>(candidates.size() - i);
      if (candidates[i].rss <= best + noise_var * ChiSquareQuantile(0.999, extra) + 1e-18 * x.squaredNorm()) {
        order = static_cast<int>(i) + 1;
        chosen_candidate = candidates[i];
        break;
      }
    }
  } else {
    if (static_cast<int>(starts_for(order).size()) < order)
      Fail("too few samples for order " + std::to_string(order) + ": " + std::to_string(starts_for(order).size()) +
           " LP equations for " + std::to_string(order) + " unknowns");
    chosen_candidate = fit_order(order);
  }
  const int m = order;
  result.order = m;
  // x(∞) read off the tail carries the tail's ringing and noise, and a constant error in x̄ is
  // an extra root z = 1 that the order-m LP cannot hold: take x(∞) of the fitted model (6)
  // and solve the LP again.
  if (result.x_inf_estimated && options.refit_x_inf && std::isfinite(chosen_candidate.x_inf_model)) {
    result.x_inf = chosen_candidate.x_inf_model;
    lp_sequence = make_sequence(result.x_inf);
    const int iterations = result.iterations + chosen_candidate.iterations;
    chosen_candidate = fit_order(m);
    result.iterations = iterations;
  }
  result.lp_equations = static_cast<int>(starts_for(m).size());
  result.lp_coefficients = chosen_candidate.lp.d;
  result.lp_condition_number = chosen_candidate.lp.cond;
  result.roots_z = chosen_candidate.lp.roots;
  result.lp_poles = chosen_candidate.lp_poles;
  result.refined = options.refine;
  result.iterations += chosen_candidate.iterations;
  const Eigen::VectorXcd roots_z = chosen_candidate.roots_z;

  // Multiplicities: merge nearby roots when the least-squares fit over all samples does not
  // worsen beyond what the noise explains (χ² spread of σ²·N, σ from the tail).
  // Candidate structures: single-linkage clusters of the roots at every pairwise distance up to
  // max_cluster_distance (z-plane). Each is refined (when refining) and kept when its fit is
  // within the noise of the unmerged fit: ΔRSS ≤ σ²·χ²_0.999(parameters removed) (σ from the tail),
  // the tolerance "tied to the noise" of the multiplicity decision.
  std::vector<double> distances{0.0};
  for (int i = 0; i < roots_z.size(); ++i)
    for (int j = i + 1; j < roots_z.size(); ++j) {
      const double d = std::abs(roots_z(i) - roots_z(j));
      if (d <= options.max_cluster_distance) distances.push_back(d * (1.0 + 1e-12));
    }
  std::sort(distances.begin(), distances.end());
  std::vector<StepPole> chosen;
  double chosen_rss = 0.0, base_rss = 0.0, cond_ls = 0.0;
  int base_params = 0;
  size_t last_count = 0;
  std::vector<std::string> cluster_warnings;
  for (size_t i = 0; i < distances.size(); ++i) {
    std::vector<std::string> warn;
    std::vector<StepPole> poles = ClusterRoots(roots_z, distances[i], h, &warn);
    const size_t distinct = DistinctRoots(poles);
    if (i > 0 && distinct == last_count) continue;  // same partition as before
    last_count = distinct;
    const int params = StructureParameters(poles);
    if (options.refine && i > 0) RefineStructure(&poles, t, x, step_amplitude, &result.iterations);
    double cond = 0.0;
    const double rss = FitResiduesLs(x, t, step_amplitude, &poles, &cond);
    if (i == 0) {
      base_rss = rss;
      base_params = params;
    } else if (!(rss <= base_rss + noise_var * ChiSquareQuantile(0.999, std::max(1, base_params - params)) +
                           1e-18 * x.squaredNorm())) {
      continue;
    }
    if (i == 0 || distinct < DistinctRoots(chosen)) {
      chosen = poles;
      chosen_rss = rss;
      cond_ls = cond;
      cluster_warnings = warn;
      result.cluster_tolerance = distances[i];
    }
  }
  result.warnings.insert(result.warnings.end(), cluster_warnings.begin(), cluster_warnings.end());

  // Residues both ways; keep the better fit.
  result.residue_rss_ls = chosen_rss;
  result.residue_condition_ls = cond_ls;
  FitResiduesEq20(lp_sequence, t, step_amplitude, grid, &chosen, &result.residue_condition_eq20);
  result.residue_rss_eq20 = Rss(chosen, false, step_amplitude, t, x);
  const bool use_ls = !(result.residue_rss_eq20 < result.residue_rss_ls);
  result.residue_method = use_ls ? "least_squares" : "eq20";
  for (auto& p : chosen) p.residues = use_ls ? p.residues_ls : p.residues_eq20;
  result.poles = chosen;

  result.fitted = StepPronyResponse(result.poles, step_amplitude, t);
  result.fit_percent = FitPercent(x, result.fitted)(0);
  result.final_cost = std::min(result.residue_rss_ls, result.residue_rss_eq20);
  result.iterations = std::max(result.iterations, 1);
  result.tf = StepPolesToTransferFunction(result.poles);
  cd gain = 0.0;
  for (const auto& p : result.poles)
    for (int j = 1; j <= p.multiplicity; ++j) {
      const cd term = p.residues(j - 1) / std::pow(p.b, p.multiplicity + 1 - j);  // Eq. (6)
      gain += p.complex_pair ? 2.0 * term.real() : term.real();
    }
  result.x_inf_model = step_amplitude * gain.real();

  const double cond_limit = 1e12;
  result.status = SolverStatus::kOk;
  std::ostringstream msg;
  msg << "order " << m << ", " << result.poles.size() << " distinct poles, LP condition number "
      << Num(result.lp_condition_number) << ", residues by " << result.residue_method;
  if (result.lp_condition_number > cond_limit) {
    result.status = SolverStatus::kIllConditioned;
    msg << "; the LP system (20)/(30) is ill-conditioned (nearly collinear rows): try a larger spacing or a lower order";
  }
  for (const auto& p : result.poles)
    if (p.b.real() <= 0.0) {
      result.status = SolverStatus::kIllConditioned;
      msg << "; a pole does not decay";
      break;
    }
  result.message = msg.str();
  return result;
}

StepPronyResult IdentifyStepResponse(const IoRecord& record, const StepPronyOptions& options) {
  ValidateIoRecord(record, 10);
  if (record.NumInputs() != 1 || record.NumOutputs() != 1)
    Fail("needs a SISO record (t,u,y); got " + std::to_string(record.NumInputs()) + " inputs and " +
         std::to_string(record.NumOutputs()) + " outputs");
  const int n = record.NumSamples();
  const Eigen::VectorXd u = record.u.col(0), y = record.y.col(0);
  const int tail = std::max(5, static_cast<int>(options.tail_fraction * n));
  const double u1 = u.tail(tail).mean();
  double u0 = u(0);
  // An input already at its final level at the first sample: the step of (4) was applied at
  // t = 0 from rest (zero initial conditions), so the level before it is 0.
  if (std::abs(u1 - u0) <= 1e-12 * (1.0 + std::abs(u1)) && std::abs(u1) > 0.0) u0 = 0.0;
  const double c = u1 - u0;
  if (!(std::abs(c) > 1e-12 * (1.0 + u.cwiseAbs().maxCoeff())))
    Fail("the input does not step: its final level equals its initial level " + Num(u0));
  int k0 = 0;
  while (k0 < n && std::abs(u(k0) - u0) < 0.5 * std::abs(c)) ++k0;
  for (int k = k0; k < n; ++k)
    if (std::abs(u(k) - u1) > 0.05 * std::abs(c))
      Fail("the input is not a step: u(" + Num(record.t(k)) + " s) = " + Num(u(k)) + " differs from the final level " +
           Num(u1) + " after the step at " + Num(record.t(k0)) + " s");
  const double baseline = k0 > 0 ? y.head(k0).mean() : 0.0;
  const Eigen::VectorXd x = y.tail(n - k0).array() - baseline;
  StepPronyOptions o = options;
  if (!std::isnan(o.x_inf)) o.x_inf -= baseline;
  StepPronyResult r = IdentifyStepResponse(x, record.sample_time, c, o);
  r.step_time = record.t(k0);
  if (k0 > 0) r.warnings.push_back("step at t = " + Num(r.step_time) + " s; output baseline " + Num(baseline) + " removed");
  return r;
}

}  // namespace idrig
