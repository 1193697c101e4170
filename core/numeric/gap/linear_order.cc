// When the linear part is the problem (see gap_diagnosis.h): G0 lacks dynamics, so a linear
// model of higher order (n0 + 2: G0 times two more poles and zeros, all coefficients free,
// fitted by the same output-error fit as every candidate, nuisance included) beats every
// single effect. It is judged by the rules an effect
// is judged by — Wilks' likelihood ratio against the refitted G0 on the estimation records,
// the signature check and the validation BIC against the best single candidate — and, when it
// wins, the verdict is `unmodelled_dynamics` and the diagnosis runs again on the higher-order
// model to report a static nonlinearity that the missing dynamics had hidden.
#include <cmath>

#include "core/numeric/gap/gap_internal.h"
#include <memory>
#include "core/numeric/validation.h"

namespace idrig::gap_detail {

namespace {

Eigen::VectorXd Multiply(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(a.size() + b.size() - 1);
  for (int i = 0; i < a.size(); ++i)
    for (int j = 0; j < b.size(); ++j) c(i + j) += a(i) * b(j);
  return c;
}

}  // namespace

bool TestUnmodelledDynamics(const FitContext& ctx, const CandidateFit& top, GapReport& report,
                            TransferFunction* higher) {
  const GapOptions& options = *ctx.options;
  const int n0 = ctx.g0->Order();
  const int order = n0 + 2;
  // Starts: G0·P(s)/P(s) with P = s² + ω s + ω² (ζ = 0.5) at three frequencies across the band:
  // exactly G0, and every coefficient of numerator and denominator then moves (log multipliers),
  // so the fit can place two more poles and zeros anywhere. Continuous by construction, which an
  // ARX model of higher order at a high sample rate often is not (poles on the negative axis).
  FitOutcome best;
  std::unique_ptr<Candidate> best_cand;
  for (double share : {0.02, 0.1, 0.4}) {
    const double w = share * M_PI / ctx.scales.ts;
    const Eigen::Vector3d p(1.0, w, w * w);
    TransferFunction g = *ctx.g0;
    g.num = Multiply(g.num, p);
    g.den = Multiply(g.den, p);
    g = Normalized(g);
    auto cand = std::make_unique<Candidate>(g, SpecFor(ctx, {EffectKind::kParameterMismatch}), ctx.scales,
                                            options.substeps);
    const Residuals residuals{cand.get(), ctx.estimation, ctx.n_est};
    Eigen::VectorXd x0 = Eigen::VectorXd::Zero(cand->Size());
    const FitOutcome f = Minimise(residuals, x0, options.evaluations_polish * (cand->Size() + 1));
    if (!(f.mse >= best.mse)) best = f, best_cand = std::move(cand);
  }
  const Candidate& cand = *best_cand;
  const FitOutcome& f = best;

  const Eigen::VectorXd y_hat = Stack(*ctx.validation, [&](const GapRecord& r) { return cand.Predict(f.x, r); });
  const int dof = std::max(1, cand.Size() - ctx.refit_size);
  const double lr = ctx.n_est * std::log(ctx.refit_fit.mse / std::max(f.mse, 1e-300));
  const double threshold = ChiSquareQuantile(1 - options.significance / ctx.k_effects, dof);
  const double validation_mse = (ctx.y_val - y_hat).squaredNorm() / ctx.n_val;
  const double bic = ctx.n_val * std::log(std::max(validation_mse, 1e-300)) +
                     cand.Size() * std::log(double(ctx.n_est));
  const double signature = Correlation(y_hat - ctx.y_refit_val, ctx.y_val - ctx.y_refit_val);
  const double nrmse = Nrmse(ctx.y_val, y_hat)(0);
  char line[300];
  std::snprintf(line, sizeof line,
                "linear order check: order %d → %d, LR %.1f (threshold %.1f), signature %.2f, "
                "validation NRMSE %.4f, ΔBIC %.1f against the best single candidate (%s)",
                n0, order, lr, threshold, signature, nrmse, bic - top.bic, EffectName(top.effect.kind));
  report.notes.push_back(line);
  if (!(lr > threshold && signature >= options.min_signature && bic < top.bic - options.ambiguity_bic))
    return false;
  *higher = cand.Plant(f.x);
  GapVerdict& v = report.verdict;
  v.effect = "unmodelled_dynamics";
  v.tied.clear();
  v.confidence = 1.0;
  v.params = Effect{};
  v.param_std.clear();
  v.effects.clear();
  v.effects_std.clear();
  v.plant = *higher;
  v.nrmse_after = nrmse;
  v.linear_order = order;
  v.linear_nrmse_after = nrmse;
  return true;
}

}  // namespace idrig::gap_detail
