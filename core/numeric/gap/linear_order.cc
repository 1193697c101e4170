// When the linear part is the problem (see gap_diagnosis.h): G0 lacks dynamics, so a linear
// model of higher order (ARX of order n0 + 2 refined by Steiglitz–McBride output-error
// iterations, time_domain/arx.h, then refitted here by the same output-error fit as every
// candidate, nuisance included) beats every single effect. It is judged by the rules an effect
// is judged by — Wilks' likelihood ratio against the refitted G0 on the estimation records,
// the signature check and the validation BIC against the best single candidate — and, when it
// wins, the verdict is `unmodelled_dynamics` and the diagnosis runs again on the higher-order
// model to report a static nonlinearity that the missing dynamics had hidden.
#include <cmath>

#include "core/numeric/gap/gap_internal.h"
#include "core/numeric/time_domain/arx.h"
#include "core/numeric/validation.h"

namespace idrig::gap_detail {

bool TestUnmodelledDynamics(const FitContext& ctx, const CandidateFit& top, GapReport& report,
                            TransferFunction* higher) {
  const GapOptions& options = *ctx.options;
  const GapRecord& first = ctx.estimation->front();
  const int n0 = ctx.g0->Order();
  ArxOptions arx;
  arx.order = n0 + 2;
  arx.oe_iterations = 8;
  arx.validate = false;
  ArxResult fit;
  try {
    fit = IdentifyArx(MakeIoRecord(first.u, first.y, first.sample_time), arx);
  } catch (const std::exception& e) {
    report.notes.push_back(std::string("linear order check skipped: ") + e.what());
    return false;
  }
  if (!fit.continuous_recovered) {
    report.notes.push_back("linear order check skipped: the order-" + std::to_string(arx.order) +
                           " ARX model has no continuous equivalent at this sample rate");
    return false;
  }
  TransferFunction g_hi = Normalized(fit.continuous_tf);
  CandidateSpec spec = SpecFor(ctx, {EffectKind::kParameterMismatch});
  const Candidate cand(g_hi, spec, ctx.scales, options.substeps);
  const Residuals residuals{&cand, ctx.estimation, ctx.n_est};
  const FitOutcome f = Minimise(residuals, Eigen::VectorXd::Zero(cand.Size()),
                                options.evaluations_polish * (cand.Size() + 1));
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
                n0, arx.order, lr, threshold, signature, nrmse, bic - top.bic, EffectName(top.effect.kind));
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
  v.linear_order = arx.order;
  v.linear_nrmse_after = nrmse;
  return true;
}

}  // namespace idrig::gap_detail
