// When the linear part is the problem (see gap_diagnosis.h): G0 lacks dynamics, so a linear
// model of higher order (n0 + 2: G0 times two more poles and zeros, all coefficients free,
// fitted by the same output-error fit as every candidate, nuisance included) beats every
// single effect. It is judged by the rules an effect
// is judged by — Wilks' likelihood ratio against the refitted G0 on the estimation records,
// the signature check and the validation BIC against the best single candidate — and, when it
// wins, the verdict is `unmodelled_dynamics` and the diagnosis runs again on the higher-order
// model to report a static nonlinearity that the missing dynamics had hidden.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/numeric/gap/gap_internal.h"
#include "core/numeric/model/lti_model.h"
#include "core/numeric/time_domain/subspace.h"
#include "core/numeric/validation.h"

namespace idrig::gap_detail {

namespace {

// The prediction `y_hat` given also the free response of `plant` on every shooting segment of the
// validation records: per segment, the residual y − ŷ regressed on [1, F] (F = the plant's free
// response from the segment's start; OffsetAndStateFit, as a candidate's own nuisance) and the
// fit added to ŷ. Under multiple
// shooting every segment's state is fitted, on validation records too, so a model with more
// states follows more of a slow wander within each segment (a load's walk on an integrator)
// through its free response alone. Two models, each given the other's free response, differ only
// in what the input does through them.
Eigen::VectorXd GivenFreeResponse(const FitContext& ctx, const TransferFunction& plant, const Eigen::VectorXd& y_hat) {
  Eigen::VectorXd out = y_hat;
  if (plant.den.size() == 0) return out;
  const StateSpace d = SampledUndelayed(plant, ctx.scales.ts);
  long offset = 0;
  for (const GapRecord& r : *ctx.validation) {
    for (const auto& [start, len] : Segments(r, ctx.nuisance.segment)) {
      const long at = offset + start - r.score_from;
      const Eigen::MatrixXd f = FreeResponse(d, len);
      const Eigen::VectorXd coef = OffsetAndStateFit(ctx.y_val.segment(at, len) - y_hat.segment(at, len), f);
      out.segment(at, len).array() += coef(0);
      if (f.cols() > 0) out.segment(at, f.rows()) += f * coef.tail(f.cols());
    }
    offset += r.y.size() - r.score_from;
  }
  return out;
}

// The linear part of a verdict: its plant with the lag, resonance or delay among its effects.
TransferFunction VerdictLinearPart(const GapVerdict& v) {
  TransferFunction g = v.plant;
  for (const Effect& e : v.effects)
    if (IsLinearEffect(e.kind)) g = ApplyLinearEffect(g, e);
  return g;
}

// Validation BIC of a verdict with one or two effects: N_val ln V_val + k ln N_est, V_val from
// its validation NRMSE, k = the first candidate's parameters plus the second effect's.
double VerdictBic(const FitContext& ctx, const GapVerdict& v, int first_parameters) {
  const double spread2 = (ctx.y_val.array() - ctx.y_val.mean()).square().sum() / ctx.n_val;
  const double mse = v.nrmse_after * v.nrmse_after * spread2;
  int k = first_parameters;
  if (v.effects.size() > 1) {
    const Effect& second = v.effects[1];
    k += Candidate::NumEffectParams(second.kind, IsAbsoluteSensor(second) ? std::vector<double>{1.0}
                                                                          : std::vector<double>{});
  }
  return ValidationBic(ctx.n_val, ctx.n_est, mse, k, v.nuisance_validation);
}

// Oscillatory poles of `g` whose free response outlasts `horizon_s`: a complex pole whose
// envelope e^{Re(s)·t} is still above 1 % at its end (−Re(s)·T < ln 100; an unstable one counts).
// Slow real poles are not counted: a free response that creeps reproduces a drift, which the
// nuisance already fits, not a hum.
int LastingModes(const TransferFunction& g, double horizon_s) {
  const Eigen::VectorXcd poles = Poles(g);
  int lasting = 0;
  for (long i = 0; i < poles.size(); ++i)
    if (std::abs(poles(i).imag()) > 1e-9 * std::abs(poles(i)) && OutlastsRecord(-poles(i).real(), horizon_s))
      ++lasting;
  return lasting;
}

// A data-driven start for the linear part (the linear-in-parameters first estimate that every
// structure with one gets): the best linear approximation of the rig from the longest estimation
// record, by subspace identification (CVA, [VODM] Table 3.1; order n0 + 2, G0's whole-sample
// delay, means removed), its poles taken to continuous time (s = ln z / Ts; a pole outside the
// unit circle reflected, one on the negative real axis — which no continuous model of this order
// samples to — placed at the Nyquist frequency on the real axis), and the numerator of the
// structure's degree by linear least squares on the output with those poles fixed: one column
// per coefficient b_j (the simulated s^j/den(s) driven by u, with G0's delay), a constant per
// record and, on an integrating G0, the same columns driven by 1 for the actuator offset. The
// fit's G0·P/P starts hold two poles and zeros that cancel, where the new ones have no gradient
// apart and the fit can stall in whichever basin the start's frequency is nearest; this start is
// already near the rig's own. Empty when the identification fails (a record too short for the
// block rows, an input that is not persistently exciting).
std::optional<TransferFunction> SubspaceStart(const FitContext& ctx, int order, long num_degree) {
  const std::vector<GapRecord>& records = *ctx.estimation;
  const GapRecord* longest = &records.front();
  for (const GapRecord& r : records)
    if (r.u.size() > longest->u.size()) longest = &r;
  const double ts = longest->sample_time;
  const TransferFunction g0n = Normalized(*ctx.g0);
  try {
    SubspaceOptions so;
    so.order = order;
    so.max_order = std::max(10, order);
    so.weighting = SubspaceWeighting::kCva;
    so.feedthrough = g0n.num.size() == g0n.den.size();
    so.input_delay = static_cast<int>(std::floor(ctx.g0->delay_s / ts + 1e-9));
    const Eigen::VectorXd u = longest->u.array() - longest->u.mean();
    const Eigen::VectorXd y = longest->y.array() - longest->y.mean();
    const SubspaceResult sub = IdentifySubspace(MakeIoRecord(u, y, ts), so);
    const Eigen::VectorXcd z = sub.model.A.eigenvalues();
    Eigen::VectorXcd s(z.size());
    for (long i = 0; i < z.size(); ++i) {
      const double r = std::max(std::abs(z(i)), 1e-12);
      const double radius = r > 1.0 ? 1.0 / r : r;
      if (z(i).real() < 0 && std::abs(z(i).imag()) < 1e-9 * r)
        s(i) = std::log(radius) / ts - M_PI / ts;
      else
        s(i) = std::complex<double>(std::log(radius), std::arg(z(i))) / ts;
    }
    const Eigen::VectorXd den = PolynomialFromRoots(s);
    // Columns: b_j (j = 0..num_degree, descending), then du's, then one constant per record.
    const bool du = ctx.integrating;
    const long nb = num_degree + 1, cols = nb * (du ? 2 : 1) + static_cast<long>(records.size());
    long rows = 0;
    for (const GapRecord& r : records) rows += r.u.size();
    Eigen::MatrixXd phi = Eigen::MatrixXd::Zero(rows, cols);
    Eigen::VectorXd target(rows);
    long row = 0;
    for (size_t k = 0; k < records.size(); ++k) {
      const GapRecord& r = records[k];
      const long n = r.u.size();
      for (long j = 0; j < nb; ++j) {
        TransferFunction basis;
        basis.num = Eigen::VectorXd::Zero(nb);
        basis.num(j) = 1.0;
        basis.den = den;
        basis.delay_s = ctx.g0->delay_s;
        phi.block(row, j, n, 1) = SimulateWithEffect(basis, Effect{}, r.u, r.sample_time);
        if (du)
          phi.block(row, nb + j, n, 1) =
              SimulateWithEffect(basis, Effect{}, Eigen::VectorXd::Ones(n), r.sample_time);
      }
      phi.block(row, cols - static_cast<long>(records.size()) + static_cast<long>(k), n, 1).setOnes();
      target.segment(row, n) = r.y;
      row += n;
    }
    const Eigen::VectorXd b = phi.colPivHouseholderQr().solve(target);
    TransferFunction g;
    g.num = b.head(nb);
    g.den = den;
    g.delay_s = ctx.g0->delay_s;
    if (!g.num.allFinite() || !g.den.allFinite() || g.num.cwiseAbs().maxCoeff() == 0.0) return std::nullopt;
    return Normalized(g);
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

}  // namespace

LinearOrderCheck CheckLinearOrder(const FitContext& ctx, const CandidateFit& top, GapReport& report) {
  const GapOptions& options = *ctx.options;
  const int n0 = ctx.g0->Order();
  const int order = n0 + 2;
  // Starts of two kinds, each fitted briefly, the best polished (as every candidate's starts):
  //  - G0·P(s)/P(s) with P = s² + ω s + ω² (ζ = 0.5) at three frequencies across the band:
  //    exactly G0, and every coefficient of numerator and denominator then moves (log
  //    multipliers), so the fit can place two more poles and zeros anywhere. At this exact
  //    pole–zero cancellation the new poles and zeros have no gradient apart (a change of P in
  //    the numerator and the same change in the denominator cancel to first order), so the fit
  //    can stall near G0;
  //  - the linear model each fitted linear effect of the ranking is (G0'/(T s + 1),
  //    G0'·ω²/(s² + 2ζωs + ω²): the missing dynamics that effect already found), padded to the
  //    same structure (denominator of degree n0 + 2, numerator of degree m0 + 2) by poles and
  //    zeros a decade above the Nyquist frequency. Those leave the response in the band within
  //    about 1 % of the effect's, but make every coefficient non-zero and so free under the log
  //    multipliers; the fit then starts where the best linear effect is and can only improve
  //    on it (LR against that effect ≥ 0 on the estimation records).
  // Continuous by construction, which an ARX model of higher order at a high sample rate often
  // is not (poles on the negative real axis).
  const TransferFunction g0n = Normalized(*ctx.g0);
  const long num_degree = g0n.num.size() - 1 + 2;
  std::vector<std::pair<std::string, TransferFunction>> starts;
  for (double share : {0.02, 0.1, 0.4}) {
    const double w = share * M_PI / ctx.scales.ts;
    const Eigen::Vector3d p(1.0, w, w * w);
    TransferFunction g = g0n;
    g.num = PolynomialProduct(g.num, p);
    g.den = PolynomialProduct(g.den, p);
    char name[64];
    std::snprintf(name, sizeof name, "G0·P/P at %.2f × Nyquist", share);
    starts.emplace_back(name, Normalized(g));
  }
  const double w_high = 10 * M_PI / ctx.scales.ts;
  const Eigen::Vector2d high(1.0 / w_high, 1.0);  // s/Ω + 1, Ω a decade above Nyquist
  for (const CandidateFit& c : report.ranking) {
    if (c.effects.size() != 1 || (c.effect.kind != EffectKind::kActuatorLag &&
                                  c.effect.kind != EffectKind::kUnmodelledResonance))
      continue;
    if (!(c.estimation_mse < ctx.refit_fit.mse)) continue;  // found nothing the refit misses
    TransferFunction g = ApplyLinearEffect(Normalized(c.plant), c.effect);
    if (g.Order() > order || g.num.size() - 1 > num_degree || g.delay_s != ctx.g0->delay_s) continue;
    while (g.Order() < order) g.den = PolynomialProduct(g.den, high);
    while (g.num.size() - 1 < num_degree) g.num = PolynomialProduct(g.num, high);
    starts.emplace_back(std::string("the fitted ") + EffectName(c.effect.kind), Normalized(g));
  }
  if (const std::optional<TransferFunction> g = SubspaceStart(ctx, order, num_degree))
    starts.emplace_back("the subspace estimate", *g);
  // An oscillatory mode whose free response lasts over the record, where G0 has none, can reproduce an
  // output disturbance (mains hum, a vibration from elsewhere) through the free initial state
  // rather than through the input — the reason a resonance is set aside when G0's residual
  // does not follow the input (gap_report.cc). The subspace estimate takes such a disturbance
  // as a mode of the plant (a 3σ hum at 0.23 × the sample rate on a delay case: an undamped
  // pair, and the verdict `unmodelled_dynamics`). A fit with more lasting oscillatory modes than
  // G0 is not the linear part.
  const double horizon_s = LongestScored(*ctx.validation) * ctx.scales.ts;
  const int g0_lasting = LastingModes(*ctx.g0, horizon_s);
  std::vector<std::string> set_aside;
  FitOutcome best;
  std::unique_ptr<Candidate> best_cand;
  std::string best_start;
  int evaluations = 0;
  for (const auto& [name, g] : starts) {
    auto cand = std::make_unique<Candidate>(g, SpecFor(ctx, {EffectKind::kParameterMismatch}), ctx.scales,
                                            options.substeps);
    const Residuals residuals{cand.get(), ctx.estimation, ctx.n_est};
    Eigen::VectorXd x0 = Eigen::VectorXd::Zero(cand->Size());
    if (ctx.refit_size > 0 && cand->NuisanceParams() > 0)  // du of the refit, when fitted
      x0(cand->PlantParams()) = ctx.refit_fit.x(ctx.refit_size - 1);
    const FitOutcome f = Minimise(residuals, x0, options.evaluations_per_start * (cand->Size() + 1));
    evaluations += f.evaluations;
    if (LastingModes(cand->Plant(f.x), horizon_s) > g0_lasting) {
      set_aside.push_back(name);
      continue;
    }
    if (!(f.mse >= best.mse)) best = f, best_cand = std::move(cand), best_start = name;
  }
  std::string lasting_note;
  if (!set_aside.empty()) {
    lasting_note = "; set aside (a ringing mode that outlasts the record, where G0 has none):";
    for (const std::string& name : set_aside) lasting_note += " " + name;
  }
  if (!best_cand) {
    report.notes.push_back("linear order check: every fit of order " + std::to_string(order) +
                           " holds a ringing mode that outlasts the record where G0 has none (it could stand in for an "
                           "output disturbance): not tried" + lasting_note);
    return LinearOrderCheck{};
  }
  {
    const Residuals residuals{best_cand.get(), ctx.estimation, ctx.n_est};
    const FitOutcome polished =
        Minimise(residuals, best.x, options.evaluations_polish * (best_cand->Size() + 1));
    evaluations += polished.evaluations;
    if (polished.mse < best.mse && LastingModes(best_cand->Plant(polished.x), horizon_s) <= g0_lasting)
      best = polished;
  }
  const Candidate& cand = *best_cand;
  const FitOutcome& f = best;

  const Eigen::VectorXd y_hat = Stack(*ctx.validation, [&](const GapRecord& r) { return cand.Predict(f.x, r); });
  const long extra_nuisance = std::max<long>(0, cand.NuisanceColumns(f.x, *ctx.estimation) - ctx.refit_nuisance_est);
  const long nuisance_validation = cand.NuisanceColumns(f.x, *ctx.validation);
  const int dof = std::max(1, cand.Size() - ctx.refit_size + static_cast<int>(extra_nuisance));
  const double lr = ctx.n_est * std::log(ctx.refit_fit.mse / std::max(f.mse, 1e-300));
  const double threshold = ChiSquareQuantile(1 - options.significance / ctx.k_effects, dof);
  const double validation_mse = ValidationMse(ctx, y_hat);
  const double bic = ValidationBic(ctx.n_val, ctx.n_est, validation_mse, cand.Size(), nuisance_validation);
  const double signature = Correlation(y_hat - ctx.y_refit_val, ctx.y_val - ctx.y_refit_val);
  const double nrmse = Nrmse(ctx.y_val, y_hat)(0);
  char line[400];
  std::snprintf(line, sizeof line,
                "linear order check: order %d → %d, LR %.1f (threshold %.1f), signature %.2f, "
                "validation NRMSE %.4f, ΔBIC %.1f against the best single candidate (%s); best of %zu "
                "starts: %s, %d evaluations",
                n0, order, lr, threshold, signature, nrmse, bic - top.bic, EffectName(top.effect.kind),
                starts.size(), best_start.c_str(), evaluations);
  report.notes.push_back(line + lasting_note);
  LinearOrderCheck check;
  if (!(lr > threshold && signature >= options.min_signature)) return check;
  // Two ways to win. (a) The higher-order linear part alone beats every single candidate.
  // (b) It beats every linear explanation (the refit, a delay, a lag, a resonance: the linear
  // part lacks dynamics) but a static effect on G0 is better still, because the rig has both:
  // then, after the pair search, AdoptHigherOrder decides (gap_internal.h).
  double linear_bic = INFINITY;
  for (const CandidateFit& c : report.ranking)
    if (c.effects.size() <= 1 && (c.effect.kind == EffectKind::kParameterMismatch || IsLinearEffect(c.effect.kind)) &&
        (c.eligible || c.effect.kind == EffectKind::kParameterMismatch))
      linear_bic = std::min(linear_bic, c.bic);
  check.wins = bic < top.bic - options.ambiguity_bic;
  check.beats_linear = bic < linear_bic - options.ambiguity_bic;
  check.linear_delta_bic = bic - linear_bic;
  check.bic = bic;
  check.plant = cand.Plant(f.x);
  check.nuisance_validation = nuisance_validation;
  check.order = order;
  check.nrmse = nrmse;
  check.y_val = y_hat;
  return check;
}

bool AdoptHigherOrder(const FitContext& ctx, const LinearOrderCheck& check, const CandidateFit& top,
                      GapReport& report, HigherOrderMode mode, std::optional<bool> verdict_follows_input) {
  GapVerdict& v = report.verdict;
  const bool compare = mode != HigherOrderMode::kAdopt;
  const bool against_pair = mode == HigherOrderMode::kAgainstPair;
  // The verdict so far: the top single candidate, or the pair kept after it.
  const double current_bic = compare ? VerdictBic(ctx, v, top.parameters) : 0;
  const std::string current = v.effects.size() > 1 ? v.effect + " + " + EffectName(v.effects[1].kind) : v.effect;
  GapOptions inner_options = *ctx.options;
  inner_options.check_linear_order = false;
  inner_options.bridge_glitches = false;  // bridged already
  inner_options.find_sensor_steps = false;  // the records carry this diagnosis's steps
  // The same fit scheme as here (the part of order n0 + 2 may decay faster than G0, and would get
  // single shooting): its NRMSEs and BICs are compared with this diagnosis's.
  inner_options.fixed_segment = ctx.nuisance.segment;
  inner_options.second_effect_at_floor = false;  // its pair could not be confirmed on longer segments
  inner_options.fixed_integrating = ctx.integrating;
  GapReport after;
  try {
    after = DiagnoseGap(check.plant, *ctx.estimation, *ctx.validation, inner_options);
  } catch (const std::exception& e) {
    report.notes.push_back(std::string("diagnosis on the higher-order linear part failed: ") + e.what());
    if (compare) return false;
  }
  const GapVerdict& a = after.verdict;
  // What the higher-order part leaves must be a static or feedback effect: a lag, resonance or
  // delay found on it is more missing dynamics, not an effect beside them (an output
  // saturation on an integrating plant came out unmodelled_dynamics + actuator_lag +
  // unmodelled_resonance).
  const bool found = !a.effects.empty() && a.effect != "ambiguous" && a.effect != "parameter_mismatch" &&
                     a.effect != "none" && a.effect != "unexplained" && !after.ranking.empty() &&
                     a.nrmse_after < check.nrmse &&  // the effect on it must improve on the part alone
                     std::none_of(a.effects.begin(), a.effects.end(),
                                  [](const Effect& e) { return IsLinearEffect(e.kind); });
  if (compare) {
    // What the higher-order part is measured against: it lost to `top` (it beats only the
    // linear explanations), or it beat every single but a pair came after.
    const std::string lost_to = against_pair
                                    ? "every single candidate, and the pair " + current + " was found after"
                                    : std::string("every linear explanation, but not ") + EffectName(top.effect.kind);
    char line[500];
    if (!found) {
      // Nothing static on it: the higher-order part alone, when it beat every single.
      if (!against_pair) return false;
      std::snprintf(line, sizeof line,
                    "linear order check: order %d beat %s; alone: validation NRMSE %.4f, ΔBIC %.1f "
                    "against %s (NRMSE %.4f)",
                    check.order, lost_to.c_str(), check.nrmse, check.bic - current_bic, current.c_str(),
                    v.nrmse_after);
      report.notes.push_back(line);
      if (!(check.bic < current_bic - ctx.options->ambiguity_bic)) return false;
    } else {
      const double inner_bic = VerdictBic(ctx, a, after.ranking.front().parameters);
      std::snprintf(line, sizeof line,
                    "linear order check: order %d beat %s (ΔBIC %.1f against the linear explanations); "
                    "with %s on it: validation NRMSE %.4f, ΔBIC %.1f against %s (NRMSE %.4f)",
                    check.order, lost_to.c_str(), check.linear_delta_bic, a.effect.c_str(), a.nrmse_after,
                    inner_bic - current_bic, current.c_str(), v.nrmse_after);
      report.notes.push_back(line);
      if (!(inner_bic < current_bic - ctx.options->ambiguity_bic)) return false;
    }
  }
  // The BIC counts every validation sample as independent. Under coloured noise (correlation
  // time τ) a higher-order part that follows the noise's slow wander gains τ times too much, so
  // the gain must also hold as a Diebold–Mariano z with a Newey–West standard error (robust to
  // the autocorrelation of the squared-error differences), at the tests' level.
  const Eigen::VectorXd& adopted = found && after.validation_prediction.size() == ctx.y_val.size()
                                       ? after.validation_prediction
                                       : check.y_val;
  if (report.validation_prediction.size() == ctx.y_val.size() && adopted.size() == ctx.y_val.size()) {
    const double z = ValidationGainZ(ctx.y_val, report.validation_prediction, adopted, 0.0, true);
    const double z_crit = NormalUpperQuantile(ctx.options->significance);
    // Under multiple shooting the higher order's extra states are fitted on every validation
    // segment. Where what the verdict leaves does not follow the input (a disturbance, a load's
    // walk), the gain must also hold with each model given the other's free response there
    // (GivenFreeResponse), else it came from following that wander through the free states.
    // Where it follows the input, the missing dynamics have the input's path to explain, and a
    // missing integrator's own response over a segment is much like a free one (DaISy ballbeam).
    double z_free = INFINITY;
    std::string input_note;
    const bool wander = ctx.nuisance.segment > 0 &&
                        !(verdict_follows_input ? *verdict_follows_input
                                                : ResidualFollowsInput(*ctx.validation,
                                                                       ctx.y_val - report.validation_prediction,
                                                                       &input_note));
    if (wander)
      z_free = ValidationGainZ(ctx.y_val, GivenFreeResponse(ctx, found ? a.plant : check.plant, report.validation_prediction),
                               GivenFreeResponse(ctx, VerdictLinearPart(v), adopted), 0.0, true);
    const bool gains = z > z_crit && z_free > z_crit;
    char line[420];
    char given[200] = "";
    if (wander)
      std::snprintf(given, sizeof given,
                    "; what the verdict leaves does not follow the input, and with each given the other's free "
                    "response on every shooting segment z = %.2f",
                    z_free);
    std::snprintf(line, sizeof line,
                  "linear order check: validation gain over the verdict so far z = %.2f (Newey–West, "
                  "automatic lag; needs > %.2f)%s%s",
                  z, z_crit, given, gains ? "" : ": not significant, the verdict stays");
    report.notes.push_back(line);
    if (!gains) return false;
  }
  report.validation_prediction = adopted;
  v.effect = "unmodelled_dynamics";
  v.tied.clear();
  v.confidence = 1.0;
  v.params = Effect{};
  v.param_std.clear();
  v.effects.clear();
  v.effects_std.clear();
  v.plant = check.plant;
  v.nrmse_after = check.nrmse;
  v.nuisance_validation = check.nuisance_validation;
  v.linear_order = check.order;
  v.linear_nrmse_after = check.nrmse;
  if (found) {
    v.effects = a.effects;
    v.effects_std = a.effects_std;
    v.params = a.params;
    v.param_std = a.param_std;
    v.plant = a.plant;
    v.nrmse_after = a.nrmse_after;
    v.nuisance = a.nuisance;
    v.nuisance_validation = a.nuisance_validation;
  }
  if (!after.ranking.empty())
    report.notes.push_back("after the linear part is fixed (order " + std::to_string(check.order) + "): " +
                           a.effect + ", validation NRMSE " + std::to_string(a.nrmse_after));
  return true;
}

}  // namespace idrig::gap_detail
