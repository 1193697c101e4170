// The gap diagnosis' entry point and report (see gap_diagnosis.h): input checks, the continuous
// sim model, the data's scales, G0 and its refit, the candidates fitted in parallel
// (candidate_fit.cc), ranked (ranking.cc), and the verdict. Localisation is gap_where.cc.
#include <unsupported/Eigen/MatrixFunctions>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <thread>

#include "core/numeric/gap/gap_internal.h"
#include "core/numeric/validation.h"

namespace idrig {
namespace gap_detail {

[[noreturn]] void Fail(const std::string& message) {
  throw std::invalid_argument("gap diagnosis: " + message);
}

double Quantile(std::vector<double> v, double p) {
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(p * (v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

// Simulation over the scored samples of every record, concatenated.
Eigen::VectorXd Stack(const std::vector<GapRecord>& records,
                      const std::function<Eigen::VectorXd(const GapRecord&)>& f) {
  long total = 0;
  for (const auto& r : records) total += r.u.size() - r.score_from;
  Eigen::VectorXd out(total);
  long offset = 0;
  for (const auto& r : records) {
    const long n = r.u.size() - r.score_from;
    out.segment(offset, n) = f(r).tail(n);
    offset += n;
  }
  return out;
}

}  // namespace gap_detail

using namespace gap_detail;

namespace {

// ---------------------------------------------------------------------------------------------
// Input checks and the continuous sim model.

void CheckRecords(const std::vector<GapRecord>& records, const std::string& what, double ts,
                  int min_samples) {
  for (size_t r = 0; r < records.size(); ++r) {
    const GapRecord& rec = records[r];
    const std::string name = what + " record " + std::to_string(r + 1);
    if (rec.u.size() != rec.y.size())
      Fail(name + ": u has " + std::to_string(rec.u.size()) + " samples but y has " +
           std::to_string(rec.y.size()));
    for (long k = 0; k < rec.u.size(); ++k)
      if (!std::isfinite(rec.u(k)) || !std::isfinite(rec.y(k)))
        Fail(name + ": sample " + std::to_string(k + 1) + " is NaN or Inf");
    if (rec.u.size() - rec.score_from < min_samples)
      Fail(name + ": " + std::to_string(rec.u.size() - rec.score_from) +
           " samples are too few for the sim model (need at least " + std::to_string(min_samples) +
           ")");
    if (std::abs(rec.sample_time - ts) > 1e-9 * ts)
      Fail(name + ": sample time " + std::to_string(rec.sample_time) + " s differs from " +
           std::to_string(ts) + " s of the first record");
    if (rec.u.maxCoeff() - rec.u.minCoeff() <= 1e-12 * std::max(1.0, rec.u.cwiseAbs().maxCoeff()))
      Fail(name + ": the input is constant, so it carries no information about the gap");
  }
}

TransferFunction ContinuousSimModel(const TransferFunction& sim, double ts) {
  Validate(sim);
  if (sim.num.size() > sim.den.size()) Fail("the sim model is improper (num order > den order)");
  if (!sim.IsDiscrete()) return Normalized(sim);
  if (std::abs(sim.sample_time - ts) > 1e-9 * ts)
    Fail("the sim model is discrete with Ts = " + std::to_string(sim.sample_time) +
         " s but the data's sample time is " + std::to_string(ts) +
         " s; give a continuous model or one sampled at the data's rate");
  TransferFunction undelayed = sim;
  undelayed.delay_s = 0;
  const StateSpace d = ToStateSpace(undelayed);
  const int n = d.Order();
  const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(n, n);
  const Eigen::VectorXcd poles = d.A.eigenvalues();
  for (int i = 0; i < poles.size(); ++i)
    if (std::abs(poles(i).imag()) < 1e-9 * std::max(1.0, std::abs(poles(i))) && poles(i).real() <= 1e-9)
      Fail("the discrete sim model has a pole at z = " + std::to_string(poles(i).real()) +
           " on the non-positive real axis, so it has no continuous equivalent; give a continuous "
           "model (or identify one of lower order)");
  if (std::abs((d.A - identity).determinant()) < 1e-12)
    Fail("the discrete sim model has a pole at z = 1; give a continuous model");
  StateSpace c = d;
  c.A = d.A.log() / ts;
  c.B = (d.A - identity).partialPivLu().solve(c.A * d.B);
  c.sample_time = 0;
  TransferFunction tf = Normalized(ToTransferFunction(c));
  tf.delay_s = sim.delay_s;
  return tf;
}

// Slowest time constant of the plant [s] (from its poles), for scaling lags and delays.
double SlowTimeConstant(const TransferFunction& plant, double ts, double duration) {
  double slow = 0;
  const Eigen::VectorXcd p = Poles(plant);
  for (int i = 0; i < p.size(); ++i)
    if (std::abs(p(i)) > 1e-9) slow = std::max(slow, 1.0 / std::abs(p(i)));
  if (slow == 0) slow = duration / 10;
  return std::clamp(slow, 2 * ts, duration);
}

}  // namespace

TransferFunction SimModelTransferFunction(const LtiModel& model) {
  if (const auto* tf = std::get_if<TransferFunction>(&model)) return *tf;
  const StateSpace& ss = std::get<StateSpace>(model);
  if (ss.NumInputs() != 1 || ss.NumOutputs() != 1)
    Fail("the sim model must be SISO; it has " + std::to_string(ss.NumInputs()) + " inputs and " +
         std::to_string(ss.NumOutputs()) + " outputs");
  TransferFunction tf = ToTransferFunction(ss);
  tf.delay_s = ss.delay_s;
  return tf;
}

GapRecord ToGapRecord(const IoRecord& record) {
  if (record.NumInputs() != 1 || record.NumOutputs() != 1)
    Fail("the records must be SISO (t,u,y); this one has " + std::to_string(record.NumInputs()) +
         " inputs and " + std::to_string(record.NumOutputs()) + " outputs");
  GapRecord r;
  r.u = record.u.col(0);
  r.y = record.y.col(0);
  r.sample_time = record.sample_time;
  return r;
}

void SplitRecord(const GapRecord& record, std::vector<GapRecord>& estimation,
                 std::vector<GapRecord>& validation) {
  const long n = record.u.size();
  const long half = n / 2;
  GapRecord est = record;
  est.u = record.u.head(half);
  est.y = record.y.head(half);
  est.score_from = 0;
  GapRecord val = record;
  val.score_from = static_cast<int>(half);
  estimation.push_back(est);
  validation.push_back(val);
}

GapReport DiagnoseGap(const TransferFunction& sim_model, const std::vector<GapRecord>& estimation_in,
                      const std::vector<GapRecord>& validation_in, const GapOptions& options) {
  if (estimation_in.empty()) Fail("no estimation records");
  const double ts = estimation_in.front().sample_time;
  if (!(ts > 0)) Fail("the records' sample time must be positive");
  const TransferFunction g0 = ContinuousSimModel(sim_model, ts);
  const int order = g0.Order();
  const int min_samples = std::max(20, 10 * (order + 4));

  GapReport report;
  std::vector<GapRecord> estimation, validation;
  if (validation_in.empty()) {
    if (estimation_in.size() == 1) {
      if (estimation_in.front().u.size() < 2 * min_samples)
        Fail("the record has " + std::to_string(estimation_in.front().u.size()) +
             " samples: too short to split into estimation and validation halves (need " +
             std::to_string(2 * min_samples) + ")");
      SplitRecord(estimation_in.front(), estimation, validation);
      report.notes.push_back(
          "one record and no validation record: estimation on the first half, validation on the "
          "second half (simulated through the first half to carry the state)");
    } else {
      estimation.assign(estimation_in.begin(), estimation_in.end() - 1);
      validation.push_back(estimation_in.back());
      report.notes.push_back("no validation record: the last estimation record is held out");
    }
  } else {
    estimation = estimation_in;
    validation = validation_in;
  }
  CheckRecords(estimation, "estimation", ts, min_samples);
  CheckRecords(validation, "validation", ts, min_samples);

  Scales scales;
  scales.ts = ts;
  std::vector<double> all_u, all_y;
  double duration = 0;
  for (const auto& r : estimation) {
    all_u.insert(all_u.end(), r.u.data(), r.u.data() + r.u.size());
    all_y.insert(all_y.end(), r.y.data(), r.y.data() + r.y.size());
    duration = std::max(duration, r.u.size() * ts);
  }
  scales.slow = SlowTimeConstant(g0, ts, duration);
  scales.u_max = std::max(1e-12, std::max(std::abs(*std::max_element(all_u.begin(), all_u.end())),
                                          std::abs(*std::min_element(all_u.begin(), all_u.end()))));
  scales.y_max = std::max(1e-12, std::max(std::abs(*std::max_element(all_y.begin(), all_y.end())),
                                          std::abs(*std::min_element(all_y.begin(), all_y.end()))));
  const double uq[5] = {0.02, 0.15, 0.5, 0.85, 0.98};
  for (int i = 0; i < 5; ++i) scales.u_quantile[i] = Quantile(all_u, uq[i]);
  const double yq[4] = {0.005, 0.02, 0.98, 0.995};
  for (int i = 0; i < 4; ++i) scales.y_quantile[i] = Quantile(all_y, yq[i]);

  long n_est = 0, n_val = 0;
  for (const auto& r : estimation) n_est += r.u.size() - r.score_from;
  for (const auto& r : validation) n_val += r.u.size() - r.score_from;
  report.estimation_samples = static_cast<int>(n_est);
  report.validation_samples = static_cast<int>(n_val);

  const std::vector<EffectKind> kinds = options.candidates.empty() ? AllEffects() : options.candidates;
  const Eigen::VectorXd y_val = Stack(validation, [](const GapRecord& r) { return r.y; });

  // G0 as given, and G0 refitted (parameter_mismatch): the references for every effect.
  Candidate as_is(g0, EffectKind::kNone, false, scales, options.substeps);
  const Eigen::VectorXd no_params(0);
  const Eigen::VectorXd y0_val =
      Stack(validation, [&](const GapRecord& r) { return as_is.Simulate(no_params, r); });

  const double as_is_mse = Mse(Residuals{&as_is, &estimation, n_est}, no_params);
  Candidate refit(g0, EffectKind::kParameterMismatch, true, scales, options.substeps);
  Residuals refit_residuals{&refit, &estimation, n_est};
  const FitOutcome refit_fit = Minimise(refit_residuals, Eigen::VectorXd::Zero(refit.Size()),
                                        options.evaluations_polish * (refit.Size() + 1));
  const Eigen::VectorXd y_refit_val =
      Stack(validation, [&](const GapRecord& r) { return refit.Simulate(refit_fit.x, r); });

  const Eigen::VectorXd zero_plant = Eigen::VectorXd::Zero(refit.Size());
  {
    // Lag that best aligns G0's output with the measured one (a delay's natural start).
    const GapRecord& first = estimation.front();
    const Eigen::VectorXd y0 = as_is.Simulate(no_params, first);
    const long n = first.y.size();
    const long max_lag = std::min<long>(n / 4, static_cast<long>(10 * scales.slow / ts) + 1);
    double best = -INFINITY;
    for (long lag = 0; lag <= max_lag; ++lag) {
      const double c = first.y.tail(n - lag).dot(y0.head(n - lag)) / std::sqrt(double(n - lag));
      if (c > best) best = c, scales.lag_of_best_match = lag * ts;
    }
  }
  double q_strength = 0;
  const double q_step = QuantisationStep(estimation, &q_strength);

  FitContext ctx;
  ctx.g0 = &g0;
  ctx.estimation = &estimation;
  ctx.validation = &validation;
  ctx.options = &options;
  ctx.scales = scales;
  ctx.n_est = n_est;
  ctx.n_val = n_val;
  ctx.y_val = y_val;
  ctx.y0_val = y0_val;
  ctx.y_refit_val = y_refit_val;
  ctx.as_is_mse = as_is_mse;
  ctx.refit_fit = refit_fit;
  ctx.refit_size = refit.Size();
  ctx.q_step = q_step;
  ctx.q_strength = q_strength;
  ctx.k_effects = std::max<int>(1, static_cast<int>(kinds.size()) - 2);
  auto fit_one = [&](EffectKind kind) {
    CandidateWork w;
    CandidateFit& c = w.fit;
    if (kind == EffectKind::kNone) {
      c.effect.kind = kind;
      c.plant = g0;
      c.estimation_mse = as_is_mse;
      w.y_val = y0_val;
      c.significant = true;
    } else if (kind == EffectKind::kParameterMismatch) {
      c.effect = refit.EffectOf(refit_fit.x);
      c.plant = refit.Plant(refit_fit.x);
      c.parameters = refit.Size();
      c.estimation_mse = refit_fit.mse;
      c.evaluations = refit_fit.evaluations;
      w.y_val = y_refit_val;
    } else {
      FitEffect(ctx, kind, w);
    }
    ScoreCandidate(ctx, w);
    return w;
  };
  // The candidates are independent: fit them on `threads` threads (results do not depend on
  // the schedule; each candidate is fitted deterministically).
  std::vector<CandidateWork> work(kinds.size());
  {
    const int threads = std::max(1, std::min<int>(static_cast<int>(kinds.size()),
                                                  options.threads > 0 ? options.threads
                                                                      : static_cast<int>(std::thread::hardware_concurrency())));
    std::atomic<size_t> next{0};
    std::vector<std::string> errors(kinds.size());
    auto run = [&] {
      for (size_t i = next++; i < kinds.size(); i = next++) {
        try {
          work[i] = fit_one(kinds[i]);
        } catch (const std::exception& e) {
          errors[i] = e.what();
        }
      }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(run);
    run();
    for (auto& t : pool) t.join();
    for (size_t i = 0; i < kinds.size(); ++i)
      if (!errors[i].empty())
        throw std::invalid_argument(std::string("gap diagnosis: fitting ") + EffectName(kinds[i]) +
                                    " failed: " + errors[i]);
  }

  report.ranking = RankCandidates(std::move(work), options);

  // Noise floor, estimated without the candidates (gap_noise.h); records too short for it fall
  // back to the smallest estimation residual among the candidates (said in the method).
  NoiseFloor floor;
  try {
    floor = EstimateNoiseFloor(estimation, validation);
  } catch (const std::invalid_argument&) {
    double noise_mse = std::numeric_limits<double>::infinity();
    for (const auto& c : report.ranking) noise_mse = std::min(noise_mse, c.estimation_mse);
    floor.method = "best_candidate_residual";
    floor.sigma = std::sqrt(noise_mse);
    floor.samples = n_est;
  }
  const double y_val_spread = (y_val.array() - y_val.mean()).matrix().norm() / std::sqrt(double(n_val));

  const CandidateFit& top = report.ranking.front();
  GapVerdict& v = report.verdict;
  v.effect = EffectName(top.effect.kind);
  v.confidence = top.score;
  v.params = top.effect;
  v.param_std = top.param_std;
  v.plant = top.plant;
  v.nrmse_before = Nrmse(y_val, y0_val)(0);
  v.nrmse_after = top.nrmse_after;
  const double noise_nrmse = floor.sigma / std::max(y_val_spread, 1e-300);
  ApplyNoiseFloor(noise_nrmse, v);
  if (report.ranking.size() > 1 && report.ranking[1].eligible &&
      report.ranking[1].bic - top.bic < options.ambiguity_bic) {
    v.effect = "ambiguous";
    v.tied = {EffectName(top.effect.kind), EffectName(report.ranking[1].effect.kind)};
  }
  // A two-valued input (PRBS, random binary) passes a dead zone, backlash or a symmetric
  // saturation as a mere gain: when the gap is a pure gain change, those cannot be told from a
  // parameter mismatch with this data.
  if (v.effect == "parameter_mismatch" && BinaryInput(estimation) && BinaryInput(validation)) {
    Candidate gain(g0, EffectKind::kParameterMismatch, true, scales, options.substeps);
    gain.SetGainOnly();
    Residuals gain_residuals{&gain, &estimation, n_est};
    const FitOutcome gain_fit = Minimise(gain_residuals, Eigen::VectorXd::Zero(1), 200);
    const double lr = n_est * std::log(gain_fit.mse / refit_fit.mse);
    const int dof = std::max(1, refit.Size() - 1);
    if (lr < ChiSquareQuantile(1 - options.significance, dof)) {
      v.effect = "ambiguous";
      v.tied = {"parameter_mismatch", "dead_zone", "backlash", "input_saturation"};
      v.confidence = 1.0 / v.tied.size();  // nothing in the data prefers one of them
      report.notes.push_back(
          "the input takes two values only, and the gap is a pure gain change (gain-only refit "
          "not worse: LR " + std::to_string(lr) + "): input dead zone, backlash and symmetric "
          "saturation act as a gain on such a signal and cannot be told from a parameter "
          "mismatch; excite at several amplitudes to separate them");
    }
  }
  if (v.effect == "none")
    v.explanation = "no candidate explains the gap better than noise: G0 fits within the noise";
  else if (v.effect == "ambiguous")
    v.explanation = "the top candidates (" + v.tied[0] + ", " + v.tied[1] +
                    (v.tied.size() > 2 ? ", …" : "") +
                    ") fit the validation data equally well; more informative data would separate them";
  else
    v.explanation = v.effect + " closes " + std::to_string(int(std::round(100 * v.shrink))) +
                    " % of the explainable gap on the validation records";

  report.where = LocateGap(g0, validation, floor.sigma);
  report.where.noise_nrmse = noise_nrmse;
  report.where.noise_floor = floor;
  std::vector<GapRecord> all_records = estimation;
  all_records.insert(all_records.end(), validation.begin(), validation.end());
  report.where.detection_lines = AnalyseDetectionLines(all_records, &g0);
  return report;
}

}  // namespace idrig
