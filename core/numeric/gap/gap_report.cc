// The gap diagnosis' entry point and report (see gap_diagnosis.h): input checks, the continuous
// sim model, the data's scales, G0 and its refit, the candidates fitted in parallel
// (candidate_fit.cc), ranked (ranking.cc), and the verdict. Localisation is gap_where.cc.
#include <unsupported/Eigen/MatrixFunctions>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "core/numeric/gap/gap_internal.h"
#include "core/numeric/signal/level_shifts.h"
#include "core/numeric/signal/outliers.h"
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

// Multiple shooting when G0 integrates or is lightly damped: the slowest mode decays by less
// than e^-5 over the longest record, so an open-loop simulation from a wrong state (or with a
// small input bias) drifts. Segments of max(N/8, 100·(n+1)) samples each get a free state;
// a true integrator (a pole within 1e-6/Ts of 0) also gets an input offset in every candidate.
void ChooseFitScheme(const TransferFunction& g0, const std::vector<GapRecord>& estimation, double ts,
                     FitContext& ctx) {
  const Eigen::VectorXcd p = Poles(g0);
  ctx.integrating = false;
  for (int i = 0; i < p.size(); ++i)
    if (std::abs(p(i)) < 1e-6 / ts) ctx.integrating = true;
  ctx.nuisance = CandidateSpec{};
  ctx.nuisance.segment = ShootingSegment(g0, LongestScored(estimation), ts);
}

// The floor of what a candidate leaves: the noise floor's ARX estimator (gap_noise.h) on its
// residual, y − ŷ as the records' output. On a nonlinear rig the one-step ARX predictor of y
// misses the nonlinearity, and its floor is loose (an upper bound); once the candidate has taken
// the nonlinearity out, what it leaves is white noise where nothing else is missing (the estimate
// is then its MSE) and predictable where a second effect is. 0 where the floor is not an ARX
// estimate (the periods' floor is exact) or the records are too short.
double ResidualFloor(const FitContext& ctx, const CandidateWork& w, const NoiseFloor& floor) {
  if (floor.method != "arx_prediction") return 0.0;
  const Candidate cand(*ctx.g0, w.spec, ctx.scales, ctx.options->substeps);
  // Every sample of every record, also those a validation record does not score (a record split in
  // time is scored from its middle, and its predictor's regressors reach back before that); w.y_val
  // holds only the scored samples.
  std::vector<GapRecord> estimation = *ctx.estimation, validation = *ctx.validation;
  for (std::vector<GapRecord>* set : {&estimation, &validation})
    for (GapRecord& r : *set) r.y -= cand.Predict(w.x, r);
  try {
    const NoiseFloor own = EstimateNoiseFloor(estimation, validation);
    return own.sigma * own.sigma;
  } catch (const std::invalid_argument&) {
    return 0.0;
  }
}

// A reference candidate (none, or the refitted G0) as fitted, for the ranking.
CandidateWork ReferenceWork(const Candidate& cand, const FitOutcome& fit, const Eigen::VectorXd& y_val,
                            const std::vector<GapRecord>& estimation) {
  CandidateWork w;
  CandidateFit& c = w.fit;
  c.effect = cand.EffectOf(fit.x);
  c.plant = cand.Plant(fit.x);
  c.parameters = cand.Size();
  c.estimation_mse = fit.mse;
  c.evaluations = fit.evaluations;
  c.input_offset = cand.InputOffset(fit.x);
  c.input_offset_fitted = cand.NuisanceParams() > 0;
  for (const GapRecord& r : estimation) {
    Nuisance nu;
    cand.Predict(fit.x, r, &nu);
    c.output_offsets.push_back(nu.output_offset);
    if (cand.spec().drift) c.output_drifts.push_back(nu.output_drift);
  }
  w.y_val = y_val;
  w.x = fit.x;
  w.spec = cand.spec();
  return w;
}

// G0's validation residual tested against the input (ResidualFollowsInput), its figures in the notes.
bool InputExplainsResidual(const std::vector<GapRecord>& validation, const Eigen::VectorXd& residual,
                           GapReport& report) {
  std::string note;
  const bool follows = ResidualFollowsInput(validation, residual, &note);
  const bool ran = note.rfind("input-residual test not run", 0) != 0;
  report.notes.push_back(ran ? "G0's validation residual is above the noise floor; " + note : note);
  return follows;
}

}  // namespace

long ShootingSegment(const TransferFunction& g0, long samples, double ts) {
  const Eigen::VectorXcd p = Poles(g0);
  double slowest = INFINITY;
  for (int i = 0; i < p.size(); ++i) slowest = std::min(slowest, -p(i).real());
  if (p.size() == 0 || !(slowest * samples * ts < 5.0)) return 0;
  const long segment = std::max<long>(samples / 8, 100 * (g0.Order() + 1));
  return segment >= samples ? 0 : segment;
}

bool gap_detail::ResidualFollowsInput(const std::vector<GapRecord>& validation, const Eigen::VectorXd& residual,
                                      std::string* note) {
  std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>> segments;
  long offset = 0;
  for (const GapRecord& r : validation) {
    const long n = r.u.size() - r.score_from;
    segments.emplace_back(residual.segment(offset, n), r.u.tail(n));
    offset += n;
  }
  try {
    const InputCorrelationTest test = TestInputCorrelationPrewhitened(segments);
    char line[400];
    std::snprintf(line, sizeof line,
                  "input-residual test (prewhitened by its AR(%d)): N·R² = %.1f against %.1f on lags 0..%d, "
                  "%.1f against %.1f on %d far lags up to %ld (99.9 %% together): %s",
                  test.ar_order, test.statistic, test.threshold, test.lags - 1, test.far_statistic,
                  test.far_threshold, test.far_lags, test.max_lag,
                  test.correlated ? "the residual follows the input, so it is not noise"
                                  : "not explained by the input (coloured noise or a disturbance)");
    *note = line;
    return test.correlated;
  } catch (const std::invalid_argument& e) {
    *note = std::string("input-residual test not run: ") + e.what();
    return false;
  }
}

bool gap_detail::ResidualFollowsInputThroughMaps(const FitContext& ctx, const CandidateWork& w,
                                                 const Eigen::VectorXd& residual, std::string* note) {
  const bool has_map = std::any_of(w.spec.kinds.begin(), w.spec.kinds.end(), [](EffectKind k) {
    return k == EffectKind::kOutputSaturation || k == EffectKind::kSensorNonlinearity;
  });
  if (!has_map || ctx.nuisance.segment > 0) return false;
  const Candidate c(*ctx.g0, w.spec, ctx.scales, ctx.options->substeps);
  if (c.Size() != w.x.size()) return false;
  std::vector<GapRecord> through;
  for (const GapRecord& r : *ctx.validation) {
    std::vector<Effect> maps;
    const Eigen::VectorXd plant_output = c.Simulate(w.x, r, &maps);
    if (maps.empty() || !plant_output.allFinite()) return false;
    GapRecord seen = r;
    for (long k = 0; k < r.u.size(); ++k) {
      double y = plant_output(k), slope = 1.0;
      for (const Effect& m : maps) {
        double s = 1.0;
        y = OutputMap(m, y, &s);
        slope *= s;
      }
      seen.u(k) = slope * r.u(k);
    }
    through.push_back(std::move(seen));
  }
  std::string line;
  const bool follows = ResidualFollowsInput(through, residual, &line);
  *note = "through the output maps' slope at the plant's output, " + line;
  return follows;
}

void gap_detail::AdoptCandidate(const CandidateFit& c, GapVerdict& v) {
  v.effects = c.effects;
  v.effects_std = c.effects_std;
  v.params = c.effects.empty() ? c.effect : c.effects.front();
  v.param_std = c.effects_std.empty() ? c.param_std : c.effects_std.front();
  v.plant = c.plant;
  v.nrmse_after = c.nrmse_after;
  v.nuisance_validation = c.nuisance_validation;
  v.nuisance.input_offset = c.input_offset;
  v.nuisance.input_offset_std = c.input_offset_std;
  v.nuisance.input_offset_fitted = c.input_offset_fitted;
  v.nuisance.output_offset = c.output_offsets;
  v.nuisance.output_drift = c.output_drifts;
}

void gap_detail::ParallelFor(size_t count, int threads_wanted, const std::function<void(size_t)>& body,
                 const std::function<std::string(size_t)>& what, const std::function<double(size_t)>& cost) {
  const int threads = std::max(1, std::min<int>(static_cast<int>(count),
                                                threads_wanted > 0 ? threads_wanted
                                                                   : static_cast<int>(std::thread::hardware_concurrency())));
  std::vector<size_t> order(count);
  std::iota(order.begin(), order.end(), size_t{0});
  if (cost) {
    std::vector<double> c(count);
    for (size_t i = 0; i < count; ++i) c[i] = cost(i);
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return c[a] > c[b]; });
  }
  std::atomic<size_t> next{0};
  std::vector<std::string> errors(count);
  auto run = [&] {
    for (size_t at = next++; at < count; at = next++) {
      const size_t i = order[at];
      try {
        body(i);
      } catch (const std::exception& e) {
        errors[i] = e.what();
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(run);
  run();
  for (auto& t : pool) t.join();
  for (size_t i = 0; i < count; ++i)
    if (!errors[i].empty()) Fail(what(i) + " failed: " + errors[i]);
}

// Measured on `gap_benchmark --benchmark_filter=BM_DiagnosePair/1/10000/1` (an integrating plant,
// one thread): the sensor map alone 3.3 s and beside a backlash 5.9 s, friction 1.1 and 2.0 s, a
// cubic spring 1.2 and 1.1 s, the output clip 0.4 and 1.2 s, a resonance 0.9 s, the others
// 0.2–0.7 s. Only the order depends on these.
double gap_detail::FitCost(EffectKind kind) {
  switch (kind) {
    case EffectKind::kSensorNonlinearity: return 4.0;
    case EffectKind::kCoulombFriction:
    case EffectKind::kCubicStiffness:
    case EffectKind::kBacklash: return 2.0;
    case EffectKind::kOutputSaturation:
    case EffectKind::kUnmodelledResonance: return 1.5;
    case EffectKind::kNone:
    case EffectKind::kParameterMismatch: return 0.0;
    default: return 1.0;
  }
}

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
  GapRecord est = gap_detail::RecordHead(record, half);
  est.score_from = 0;
  GapRecord val = record;
  val.score_from = static_cast<int>(half);
  estimation.push_back(est);
  validation.push_back(val);
}

namespace {

// Bridges the output glitches of every record (core/numeric/signal/outliers.h) and says so.
std::vector<GapRecord> BridgeGlitches(const std::vector<GapRecord>& records, const char* set, GapReport& report) {
  std::vector<GapRecord> out = records;
  for (size_t i = 0; i < out.size(); ++i) {
    GapRecord& r = out[i];
    if (r.u.size() != r.y.size() || !r.y.allFinite()) continue;  // refused by CheckRecords
    const GlitchScan scan = BridgeOutputGlitches(r.y, r.u);
    const std::string name = std::string(set) + " record " + std::to_string(i + 1);
    if (scan.too_many) {
      report.notes.push_back(name + ": " + std::to_string(scan.excursions) + " output samples in " +
                             std::to_string(scan.events) +
                             " runs stand far out of their running median, too many for "
                             "glitches: left as measured");
      continue;
    }
    if (scan.glitches.empty()) continue;
    std::string samples;
    for (const auto& g : scan.glitches) {
      report.glitches.push_back({set, static_cast<int>(i), g.sample, g.value, g.replaced_by});
      if (samples.size() < 120) samples += (samples.empty() ? "" : ", ") + std::to_string(g.sample);
    }
    report.notes.push_back(name + ": " + std::to_string(scan.glitches.size()) +
                           (scan.glitches.size() == 1 ? " output sample" : " output samples") +
                           " far out of the signal (a sensor or acquisition glitch) bridged from "
                           "their neighbours before fitting, at sample " + samples);
  }
  return out;
}

constexpr double kLatticeLevels = 1.5;  // a jump below 1.5 lattice steps is one level crossed

// Marks every record's sensor steps (core/numeric/signal/level_shifts.h) against a model's
// output: each step adds an output level of its own from there on (GapRecord::sensor_steps, a
// nuisance column of every candidate); the simulation runs through it, so a plant's state (a
// friction's stick position, a backlash's side) carries over. A step nearer than `min_part`
// samples to the record's start or end, or to another step, is not marked (said in the notes).
// On an output that sits on a lattice (a quantiser coarser than the noise), a jump of about one
// lattice step is the reading crossing a level as the output moves through it — sharp and
// lasting on a slow output, as a sensor step is — and is not marked either (`--pairs any
// --integrating --seed 972`: four coarse quantisers, each read as two to four sensor steps).
std::vector<GapRecord> MarkSensorSteps(const std::vector<GapRecord>& records, const char* set,
                                       const std::function<Eigen::VectorXd(const GapRecord&)>& model,
                                       const std::string& model_name, long min_part, GapReport& report) {
  std::vector<GapRecord> out = records;
  std::optional<OutputLattice> lattice;  // of all the records, once a step is found
  const auto lattice_step = [&]() {
    if (!lattice) {
      double strength = 0;
      const double q = QuantisationStep(records, &strength);
      lattice = DetectOutputLattice(records, q, 0.0);
    }
    return lattice->lattice ? lattice->step : 0.0;
  };
  for (size_t i = 0; i < out.size(); ++i) {
    GapRecord& r = out[i];
    const long n = r.y.size();
    if (r.u.size() != n || r.score_from != 0 || !(r.sample_time > 0) || !r.y.allFinite() || !r.u.allFinite())
      continue;  // refused or split later (CheckRecords, SplitRecord)
    Eigen::VectorXd y_model;
    try {
      y_model = model(r);
    } catch (const std::exception&) {
      continue;
    }
    const std::string name = std::string(set) + " record " + std::to_string(i + 1);
    for (const LevelShift& step : FindSensorSteps(r.y, y_model)) {
      std::ostringstream msg;
      msg << name << ": the output jumps by " << step.size << " at sample " << step.sample
          << " and stays there, while " << model_name << " does not move (a sensor re-zeroed or knocked)";
      long last = 0;
      for (long s : r.sensor_steps) last = std::max(last, s <= step.sample ? s : 0L);
      const bool near = step.sample - last < min_part || n - step.sample < min_part ||
                        std::any_of(r.sensor_steps.begin(), r.sensor_steps.end(),
                                    [&](long s) { return std::abs(s - step.sample) < min_part; });
      const double q = lattice_step();
      if (q > 0 && std::abs(step.size) < kLatticeLevels * q) {
        msg << "; the output sits on a lattice of step " << q
            << ": one level crossed as the output moves through it, not marked";
      } else if (near) {
        msg << "; too near the record's ends or another step (" << min_part << " samples): not marked";
      } else {
        msg << ": a sensor level of its own from there on (a nuisance parameter of every candidate)";
        r.sensor_steps.push_back(step.sample);
        std::sort(r.sensor_steps.begin(), r.sensor_steps.end());
        report.sensor_steps.push_back({set, static_cast<int>(i), step.sample, step.size});
      }
      report.notes.push_back(msg.str());
    }
  }
  return out;
}

}  // namespace

namespace {

constexpr double kStepSearchAboveFloor = 1.5;  // nrmse_after / noise floor for the second search
constexpr double kStepGainRequired = 0.8;      // the steps' diagnosis must end below this share
constexpr long kShortestSegmentPerOrder = 50;   // a halved shooting segment keeps ≥ 50·(n + 1) samples

// The diagnosis on records whose glitches are bridged already (`report` carries what the
// bridging said). `second_at_floor`, where given, says whether the verdict's second effect was
// searched though its first reached the noise floor (GapOptions::second_effect_at_floor), so
// that it awaits its confirmation on longer segments (DiagnoseGap).
GapReport DiagnoseGapOnce(const TransferFunction& sim_model, std::vector<GapRecord> estimation_in,
                          std::vector<GapRecord> validation_in, const GapOptions& options, GapReport report,
                          bool* second_at_floor = nullptr) {
  if (second_at_floor) *second_at_floor = false;
  if (estimation_in.empty()) Fail("no estimation records");
  const double ts = estimation_in.front().sample_time;
  if (!(ts > 0)) Fail("the records' sample time must be positive");
  const TransferFunction g0 = ContinuousSimModel(sim_model, ts);
  const int order = g0.Order();
  const int min_samples = std::max(20, 10 * (order + 4));
  if (options.find_sensor_steps) {
    const auto g0_output = [&](const GapRecord& r) {
      EffectSimulationOptions sim;
      sim.substeps = 1;
      return SimulateWithEffect(g0, Effect{}, r.u, r.sample_time, sim);
    };
    estimation_in = MarkSensorSteps(estimation_in, "estimation", g0_output, "the sim model's output", min_samples, report);
    validation_in = MarkSensorSteps(validation_in, "validation", g0_output, "the sim model's output", min_samples, report);
  }

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
  scales.duration = duration;
  for (const auto& r : validation) scales.duration = std::max(scales.duration, r.u.size() * ts);
  scales.u_max = std::max(1e-12, std::max(std::abs(*std::max_element(all_u.begin(), all_u.end())),
                                          std::abs(*std::min_element(all_u.begin(), all_u.end()))));
  scales.y_max = std::max(1e-12, std::max(std::abs(*std::max_element(all_y.begin(), all_y.end())),
                                          std::abs(*std::min_element(all_y.begin(), all_y.end()))));
  const double uq[5] = {0.02, 0.15, 0.5, 0.85, 0.98};
  for (int i = 0; i < 5; ++i) scales.u_quantile[i] = Quantile(all_u, uq[i]);
  for (int i = 0; i < 6; ++i) {
    scales.u_low[i] = Quantile(all_u, Scales::kTailShares[i]);
    scales.u_high[i] = Quantile(all_u, 1 - Scales::kTailShares[i]);
  }
  const double yq[4] = {0.005, 0.02, 0.98, 0.995};
  for (int i = 0; i < 4; ++i) scales.y_measured_quantile[i] = scales.y_quantile[i] = Quantile(all_y, yq[i]);
  for (int i = 0; i < 6; ++i) {
    scales.y_measured_low[i] = Quantile(all_y, Scales::kTailShares[i]);
    scales.y_measured_high[i] = Quantile(all_y, 1 - Scales::kTailShares[i]);
  }

  long n_est = 0, n_val = 0;
  for (const auto& r : estimation) n_est += r.u.size() - r.score_from;
  for (const auto& r : validation) n_val += r.u.size() - r.score_from;
  report.estimation_samples = static_cast<int>(n_est);
  report.validation_samples = static_cast<int>(n_val);

  const std::vector<EffectKind> kinds = options.candidates.empty() ? AllEffects() : options.candidates;
  const Eigen::VectorXd y_val = Stack(validation, [](const GapRecord& r) { return r.y; });

  FitContext ctx;
  ctx.g0 = &g0;
  ctx.estimation = &estimation;
  ctx.validation = &validation;
  ctx.options = &options;
  ctx.n_est = n_est;
  ctx.n_val = n_val;
  ctx.y_val = y_val;
  ChooseFitScheme(g0, estimation, ts, ctx);
  if (options.fixed_segment >= 0) {
    ctx.nuisance.segment = options.fixed_segment;
    ctx.integrating = options.fixed_integrating;
  }
  // A sensor drift where it is not an actuator offset in disguise (on an integrator du is a
  // ramp) and not already taken by the shooting segments' own offsets.
  ctx.nuisance.drift = options.fit_drift && ctx.nuisance.segment == 0 && !ctx.integrating;
  GapVerdict& v = report.verdict;
  v.fit_scheme = ctx.nuisance.segment > 0 ? "multiple_shooting" : "single_shooting";
  v.shooting_segment = ctx.nuisance.segment;
  v.integrating = ctx.integrating;
  if (ctx.nuisance.segment > 0)
    report.notes.push_back(
        "G0 integrates or is lightly damped (slowest decay over the record < e^-5): fitted by "
        "multiple shooting, a free state per segment of " + std::to_string(ctx.nuisance.segment) +
        " samples, so that the open-loop simulation cannot drift");
  v.nuisance.initial_state = ctx.nuisance.segment > 0
                                 ? "free per segment of " + std::to_string(ctx.nuisance.segment) + " samples (least squares)"
                                 : "free per record (least squares)";

  // G0 as given (with the nuisance), and G0 refitted (parameter_mismatch): the references.
  const Candidate as_is(g0, [&] {
    CandidateSpec spec = SpecFor(ctx, {EffectKind::kNone});
    spec.fit_plant = false;
    return spec;
  }(), scales, options.substeps);
  const Residuals as_is_residuals{&as_is, &estimation, n_est};
  const FitOutcome as_is_fit =
      Minimise(as_is_residuals, Eigen::VectorXd::Zero(as_is.Size()), options.evaluations_polish * (as_is.Size() + 1));
  const Eigen::VectorXd y0_val =
      Stack(validation, [&](const GapRecord& r) { return as_is.Predict(as_is_fit.x, r); });
  // The same G0 fitted to the estimation records with their output mirrored (y → −y), on an
  // integrating plant (du alone): the actuator offset that drives the plant the way the mirrored
  // readings drift, where an |y| sensor reads a plant that stays below its fold (FitEffect).
  double mirrored_du = 0;
  if (ctx.integrating && as_is.Size() == 1 &&
      std::find(kinds.begin(), kinds.end(), EffectKind::kSensorNonlinearity) != kinds.end()) {
    std::vector<GapRecord> mirrored = estimation;
    for (GapRecord& r : mirrored) r.y = -r.y;
    const Residuals mirrored_residuals{&as_is, &mirrored, n_est};
    mirrored_du = Minimise(mirrored_residuals, Eigen::VectorXd::Zero(1), options.evaluations_polish * 2).x(0);
  }
  const Candidate refit(g0, SpecFor(ctx, {EffectKind::kParameterMismatch}), scales, options.substeps);
  const Residuals refit_residuals{&refit, &estimation, n_est};
  Eigen::VectorXd refit_start = Eigen::VectorXd::Zero(refit.Size());
  if (as_is.Size() > 0) refit_start.tail(as_is.Size()) = as_is_fit.x;  // du
  const FitOutcome refit_fit =
      Minimise(refit_residuals, refit_start, options.evaluations_polish * (refit.Size() + 1));
  const Eigen::VectorXd y_refit_val =
      Stack(validation, [&](const GapRecord& r) { return refit.Predict(refit_fit.x, r); });
  {
    // The output's scales in the model's coordinates: the measured y less the refit's output
    // offset b (a sensor offset, plus G0(0)·du), so that the limits of an output saturation and
    // the scale of a cubic spring or a sensor map start where the plant's output is, not where
    // the sensor's zero puts it.
    std::vector<double> centred;
    for (const auto& r : estimation) {
      Nuisance nuisance;
      refit.Predict(refit_fit.x, r, &nuisance);
      for (long k = 0; k < r.y.size(); ++k) centred.push_back(r.y(k) - nuisance.output_level(k));
    }
    double y_max = 0;
    for (double v : centred) y_max = std::max(y_max, std::abs(v));
    scales.y_max = std::max(1e-12, y_max);
    for (int i = 0; i < 4; ++i) scales.y_quantile[i] = Quantile(centred, yq[i]);
    for (int i = 0; i < 6; ++i) {
      scales.y_low[i] = Quantile(centred, Scales::kTailShares[i]);
      scales.y_high[i] = Quantile(centred, 1 - Scales::kTailShares[i]);
    }
  }
  {
    // Lag that best aligns G0's output with the measured one (a delay's natural start).
    const GapRecord& first = estimation.front();
    const Eigen::VectorXd y0 = as_is.Predict(as_is_fit.x, first);
    const long n = first.y.size();
    const long max_lag = std::min<long>(n / 4, static_cast<long>(10 * scales.slow / ts) + 1);
    const Eigen::VectorXd yc = first.y.array() - first.y.mean(), y0c = y0.array() - y0.mean();
    double best = -INFINITY;
    for (long lag = 0; lag <= max_lag; ++lag) {
      const double c = yc.tail(n - lag).dot(y0c.head(n - lag)) / std::sqrt(double(n - lag));
      if (c > best) best = c, scales.lag_of_best_match = lag * ts;
    }
  }
  ctx.scales = scales;
  ctx.y0_val = y0_val;
  ctx.y_refit_val = y_refit_val;
  ctx.as_is_mse = as_is_fit.mse;
  ctx.mirrored_du = mirrored_du;
  ctx.as_is_size = as_is.Size();
  ctx.refit_fit = refit_fit;
  ctx.refit_size = refit.Size();
  ctx.refit_nuisance_est = refit.NuisanceColumns(refit_fit.x, estimation);
  ctx.refit_nuisance_val = refit.NuisanceColumns(refit_fit.x, validation);
  ctx.q_step = QuantisationStep(estimation, &ctx.q_strength, options.threads);
  ctx.q_phase = DetectOutputLattice(estimation, ctx.q_step, 0.0).offset;  // a sensor offset after the rounding
  ctx.k_effects = std::max<int>(1, static_cast<int>(kinds.size()) - 2);
  auto fit_one = [&](EffectKind kind) {
    CandidateWork w;
    CandidateFit& c = w.fit;
    if (kind == EffectKind::kNone) {
      w = ReferenceWork(as_is, as_is_fit, y0_val, estimation);
      c.effect.kind = kind;
      c.plant = g0;
      c.significant = true;
    } else if (kind == EffectKind::kParameterMismatch) {
      w = ReferenceWork(refit, refit_fit, y_refit_val, estimation);
    } else {
      FitEffect(ctx, kind, w);
    }
    ScoreCandidate(ctx, w);
    return w;
  };
  // The candidates are independent: fit them in parallel (results do not depend on the
  // schedule; each candidate is fitted deterministically).
  std::vector<CandidateWork> work(kinds.size());
  ParallelFor(kinds.size(), options.threads, [&](size_t i) { work[i] = fit_one(kinds[i]); },
              [&](size_t i) { return std::string("fitting ") + EffectName(kinds[i]); },
              [&](size_t i) { return FitCost(kinds[i]); });
  MaskOneSidedDeadZone(ctx, work);
  MaskImplausibleDynamics(ctx.scales, work);

  // Noise floor, estimated without the candidates (gap_noise.h); records too short for it fall
  // back to the smallest estimation residual among the candidates (said in the method).
  NoiseFloor floor;
  try {
    floor = EstimateNoiseFloor(estimation, validation);
  } catch (const std::invalid_argument&) {
    double noise_mse = std::numeric_limits<double>::infinity();
    for (const auto& w : work) noise_mse = std::min(noise_mse, w.fit.estimation_mse);
    floor.method = "best_candidate_residual";
    floor.sigma = std::sqrt(noise_mse);
    floor.samples = n_est;
  }
  // Nothing is left for a second effect (or for more dynamics) when a fit already simulates the
  // validation records within the independent noise floor (its MSE within two standard
  // deviations of a χ²_N sample variance, σ²(1 + 2√(2/N))).
  const bool floor_known = floor.method != "best_candidate_residual";
  const double floor_mse = floor.sigma * floor.sigma * SampleVarianceTolerance(n_val);
  auto within_floor = [&](double mse) { return floor_known && mse <= floor_mse; };
  // Does what G0 leaves on the validation records above the floor follow the input (the
  // prewhitened test, validation.h)? When it does not, the gap is an output disturbance (mains
  // hum, a vibration from elsewhere on the rig, coloured noise the ARX floor reads low), and a
  // candidate that adds a mode must not explain it: a lightly damped mode with a free initial
  // state reproduces a hum through its free response, not through the input (a 23 Hz hum of 3σ
  // on `none` cases was named unmodelled_resonance, then unmodelled_dynamics). The resonance is
  // set aside and the linear order is not checked. The other candidates keep their rules: the
  // test has little power for a slow residual (its lags reach 20 samples, then sparsely), and a
  // parameter mismatch or a gain under a two-valued input on an integrating plant, whose
  // residuals are slow, were called `none` when they were set aside too.
  int g0_slot = -1;
  for (size_t i = 0; i < work.size(); ++i)
    if (work[i].fit.effect.kind == EffectKind::kNone && work[i].fit.effects.size() <= 1) g0_slot = static_cast<int>(i);
  const bool g0_above_floor = floor_known && g0_slot >= 0 && !within_floor(work[g0_slot].fit.validation_mse);
  const bool residual_follows_input = g0_above_floor && InputExplainsResidual(validation, y_val - y0_val, report);
  const bool disturbance_only = g0_above_floor && !residual_follows_input;
  if (floor_known && g0_slot >= 0)
    v.g0_gap = !g0_above_floor ? "within_noise" : residual_follows_input ? "follows_input" : "does_not_follow_input";
  // Only a mode whose free response lasts can stand in for a disturbance: one whose envelope has
  // decayed below 1 % before the end of the longest validation record (ζω·T > ln 100) cannot
  // carry a steady hum or vibration over it, so its gain comes through the input. The test above
  // has little power on a short record (`gap bench --samples 1500 --seed 802 --offsets`, case 4:
  // a 13 rad/s mode, ζ 0.084, ζω·T = 16; N·R² 48.9 against 49.2, the mode set aside and the
  // verdict a delay at 0.072 for a floor of 0.035).
  const double longest_val_s = LongestScored(validation) * ts;
  auto mode_lasts = [&](const Effect& e) {
    return e.params.size() >= 2 && OutlastsRecord(e.params[0] * e.params[1], longest_val_s);
  };
  bool resonance_kept = false;
  if (disturbance_only)
    for (CandidateWork& w : work) {
      const EffectKind kind = w.fit.effect.kind;
      if (w.fit.effects.size() > 1 || kind != EffectKind::kUnmodelledResonance) continue;
      if (!mode_lasts(w.fit.effect)) {
        resonance_kept = true;
        w.fit.note = "kept although G0's validation residual does not follow the input: the fitted mode's free "
                     "response dies out within the record (ζω·T > ln 100), so it cannot stand in for a steady disturbance";
        continue;
      }
      w.masked = true;
      w.fit.note = "set aside: G0's validation residual does not follow the input, and a mode added to the "
                   "plant acts through the input (its free response could reproduce an output disturbance)";
    }
  if (disturbance_only) MaskGainsWithinColouredNoise(ctx, work);
  MaskLinearEffectsAtTheirIdentity(ctx, work);
  MaskWhatTheEstimationRecordsReject(
      ctx, work, floor_known ? floor.sigma * floor.sigma * SampleVarianceTolerance(n_est) : 0.0);
  report.ranking = RankCandidates(work, options);
  const double y_val_spread = (y_val.array() - y_val.mean()).matrix().norm() / std::sqrt(double(n_val));

  const CandidateFit& top = report.ranking.front();
  for (const CandidateWork& w : work)
    if (w.fit.effect.kind == top.effect.kind && w.fit.effects.size() <= 1) report.validation_prediction = w.y_val;
  v.effect = EffectName(top.effect.kind);
  v.confidence = top.score;
  AdoptCandidate(top, v);
  v.params = top.effect;
  v.nrmse_before = Nrmse(y_val, y0_val)(0);
  const double noise_nrmse = floor.sigma / std::max(y_val_spread, 1e-300);
  if (report.ranking.size() > 1 && report.ranking[1].eligible &&
      report.ranking[1].bic - top.bic < options.ambiguity_bic) {
    v.effect = "ambiguous";
    v.tied = {EffectName(top.effect.kind), EffectName(report.ranking[1].effect.kind)};
  }
  // A two-valued input (PRBS, random binary) passes a dead zone, backlash or a symmetric
  // saturation as a mere gain: when the gap is a pure gain change, those cannot be told from a
  // parameter mismatch with this data.
  if (v.effect == "parameter_mismatch" && BinaryInput(estimation) && BinaryInput(validation)) {
    Candidate gain(g0, SpecFor(ctx, {EffectKind::kParameterMismatch}), scales, options.substeps);
    gain.SetGainOnly();
    Residuals gain_residuals{&gain, &estimation, n_est};
    Eigen::VectorXd gain_start = Eigen::VectorXd::Zero(gain.Size());
    if (as_is.Size() > 0) gain_start.tail(as_is.Size()) = as_is_fit.x;
    const FitOutcome gain_fit = Minimise(gain_residuals, gain_start, 200);
    const double lr = n_est * std::log(gain_fit.mse / refit_fit.mse);
    const int dof = std::max(1, refit.Size() - gain.Size());
    std::string evidence = "LR " + std::to_string(lr);
    bool pure_gain = lr < ChiSquareQuantile(1 - options.significance, dof);
    if (!pure_gain) {
      // The LR counts every estimation sample as independent: under coloured noise the full
      // refit's other coefficients follow the noise's slow wander and pass it. The dynamics
      // changed only if the refit also simulates the validation records significantly better
      // than the gain alone (the same Diebold–Mariano test with the automatic Newey–West lag
      // that the order check's adoption uses).
      const Eigen::VectorXd y_gain_val =
          Stack(validation, [&](const GapRecord& r) { return gain.Predict(gain_fit.x, r); });
      const double z = ValidationGainZ(y_val, y_gain_val, y_refit_val, 0.0, true);
      pure_gain = z < NormalUpperQuantile(options.significance);
      evidence += std::string(" above the threshold, ") + (pure_gain ? "but" : "and") +
                  " the full refit's validation gain over it z = " + std::to_string(z);
    }
    if (pure_gain) {
      v.effect = "ambiguous";
      v.tied = {"parameter_mismatch", "dead_zone", "backlash", "input_saturation"};
      v.confidence = 1.0 / v.tied.size();  // nothing in the data prefers one of them
      report.notes.push_back(
          "the input takes two values only, and the gap is a pure gain change (gain-only refit "
          "not worse: " + evidence + "): input dead zone, backlash and symmetric "
          "saturation act as a gain on such a signal (an asymmetric saturation as a gain plus an offset, which the output offset absorbs) and cannot be told from a parameter "
          "mismatch; excite at several amplitudes to separate them");
    } else {
      report.notes.push_back("the input takes two values only, and the refit changes more than the gain (" +
                             evidence + "): a parameter mismatch, not a gain that an input map could be");
    }
  }
  // `none` on top says G0 fits within the noise. That holds only when what G0 leaves on the
  // validation records is noise: within the floor, or not explained by past inputs (coloured
  // noise, which the ARX floor reads low, is not). A residual above the floor and correlated with
  // the input (the prewhitened test, validation.h) is a gap that no candidate explains: the
  // linear order is checked, and if nothing explains it either the verdict is `unexplained`.
  // (top is then G0 as given: its residual is the one tested above.)
  const bool gap_unexplained = v.effect == "none" && residual_follows_input;
  if (disturbance_only)
    report.notes.push_back(
        "the gap G0 leaves on the validation records is above the noise floor but does not follow the input: "
        "an output disturbance (hum, vibration, drift) or coloured noise, not a change of the plant; " +
        std::string(resonance_kept ? "a higher linear order was not tried on it, and an added resonance only as a "
                                     "mode that dies out within the record"
                                   : "an added resonance and a higher linear order were not tried on it"));
  // The linear part itself, and the diagnosis again on the fixed linear part (linear_order.cc).
  const LinearOrderCheck linear =
      options.check_linear_order && !disturbance_only && v.effect != "ambiguous" &&
              (v.effect != "none" || gap_unexplained)
          ? CheckLinearOrder(ctx, top, report)
          : LinearOrderCheck{};
  // When the higher-order part beats every single candidate, the pair search still runs first:
  // two static effects on G0 can beat it (friction with a saturation on an integrating plant,
  // where the part of order n0 + 2 beat friction alone and was adopted before any pair was
  // tried). The adoption is decided after the pair search.
  bool unmodelled = false;
  // A second effect, by forward selection (effect_pairs.cc), from the best eligible effect —
  // also when parameter_mismatch tops the ranking: two effects together can leave a linear
  // refit as the best single explanation. Two effects that each explain part of the gap can
  // rank the wrong one first (backlash ahead of friction when friction comes with a
  // saturation), so while the best pair so far still leaves the validation records above the
  // independent noise floor, the search goes on from the next eligible effect (up to three
  // firsts); the pair with the lowest validation BIC is kept.
  // Two single effects tied (within ambiguity_bic) while the validation records stay above the
  // floor: each explains part of what two effects do together, and their pair, if it passes its
  // rules against both, settles the tie (`--pairs any --excitation multisine --seed 970` case 41:
  // backlash with a cubic spring, the two singles 0.07 BIC apart at five times the floor).
  const bool tie = v.effect == "ambiguous" && v.tied.size() == 2;
  double verdict_val_mse = top.validation_mse;
  if (!unmodelled && (v.effect != "ambiguous" || tie) && top.effect.kind != EffectKind::kNone &&
      options.second_effect) {
    PairSearch best;
    int searched = 0;
    double first_single_bic = 0;
    // Kass and Raftery's "very strong" evidence: a BIC difference above 10.
    constexpr double kRivalBic = 10.0;
    constexpr double kFarAboveFloor = 1.5;
    std::vector<EffectKind> searched_kinds;
    std::vector<CandidateWork> tied_pairs;  // under a tie: the pair kept from each first
    bool at_floor_only = false;  // searched from the first effect alone (multiple shooting, at the floor)
    for (const CandidateWork& w : work) {
      if (!w.fit.eligible || w.fit.effects.empty()) continue;
      // Within the floor, unless what the first effect leaves still follows the input (the
      // prewhitened test G0's residual had): the floor is an upper bound, and a one-step ARX
      // predictor leaves it loose on a nonlinear rig sampled coarsely (σ̂/σ 1.6–2.2 at Ts 0.05 s:
      // a dead zone alone at twice the noise variance hid its cubic spring under it).
      // Within the floor on the estimation records as well (pooled with the validation records:
      // every record localises the gap; the estimation MSE, fitted there, reads low if anything):
      // at 20 dB an actuator lag left a y², y³ sensor on validation at 1.04 times the floor, within
      // its tolerance of 1.045, and on the estimation records at 1.064 (`--pairs any --snr 20
      // --seed 6101` case 35; pooled 1.053 against 1.032).
      if (searched == 0 && within_floor(w.fit.validation_mse)) {
        const double pooled_mse =
            (n_est * w.fit.estimation_mse + n_val * w.fit.validation_mse) / std::max<long>(1, n_est + n_val);
        const double pooled_limit = floor.sigma * floor.sigma * SampleVarianceTolerance(n_est + n_val);
        std::string input_note;
        const std::string first = std::string("second effect after ") + EffectName(w.fit.effects.front().kind);
        const auto follows_input = [&first](const std::string& test) {
          return first + ": searched though its validation MSE is within the noise floor, since what it leaves "
                         "follows the input (" + test + ")";
        };
        if (!(pooled_mse <= pooled_limit)) {
          char line[320];
          std::snprintf(line, sizeof line,
                        "%s: searched though its validation MSE %.4g is within the noise floor %.4g (%s), since "
                        "on the estimation and validation records together it leaves %.4g, above the floor's "
                        "tolerance %.4g",
                        first.c_str(), w.fit.validation_mse, floor.sigma * floor.sigma, floor.method.c_str(),
                        pooled_mse, pooled_limit);
          report.notes.push_back(line);
        } else if (ResidualFollowsInput(validation, ctx.y_val - w.y_val, &input_note)) {
          report.notes.push_back(follows_input(input_note));
        } else if (const double own = ResidualFloor(ctx, w, floor);
                   own > 0 && !(w.fit.validation_mse <= own * SampleVarianceTolerance(n_val))) {
          char line[320];
          std::snprintf(line, sizeof line,
                        "%s: searched though its validation MSE %.4g is within the noise floor %.4g (%s), since "
                        "what it leaves is predictable: the same estimator on its residual reads %.4g",
                        first.c_str(), w.fit.validation_mse, floor.sigma * floor.sigma, floor.method.c_str(), own);
          report.notes.push_back(line);
        } else if (ResidualFollowsInputThroughMaps(ctx, w, ctx.y_val - w.y_val, &input_note)) {
          // Behind a fold or a clip what a missing linear effect leaves is not linear in the input
          // (`gap bench --cases 52 --seed 7602 --offsets --combos 0.5 --pairs any --plants two-mass
          // --snr 20` case 35: a lag before an |y| sensor, N·R² 36.6 against 49.2 in the linear test,
          // 62.0 through the fold's slope).
          report.notes.push_back(follows_input(input_note));
        } else if (options.second_effect_at_floor && ctx.nuisance.segment > 0 &&
                   (options.fixed_segment >= 0 || 2 * ctx.nuisance.segment < LongestScored(estimation))) {
          char line[400];
          std::snprintf(line, sizeof line,
                        "%s: searched though its validation MSE %.4g (%.4g on the estimation and validation records "
                        "together) is within the noise floor %.4g (%s), since the shooting segments' free states "
                        "take up part of what a second effect does; from this first effect only, and a pair found so "
                        "must be found again on segments twice as long",
                        first.c_str(), w.fit.validation_mse, pooled_mse, floor.sigma * floor.sigma,
                        floor.method.c_str());
          report.notes.push_back(line);
          at_floor_only = true;
        } else {
          char line[320];
          std::snprintf(line, sizeof line,
                        "%s: not searched, its validation MSE %.4g (%.4g on the estimation and validation records "
                        "together) is within the noise floor %.4g (%s)",
                        first.c_str(), w.fit.validation_mse, pooled_mse, floor.sigma * floor.sigma,
                        floor.method.c_str());
          report.notes.push_back(line);
          break;
        }
      }
      // A pair at the floor ends the search, except for a near rival of the first effect (its
      // single BIC within kRivalBic of the first's: no strong evidence between the two), which
      // can explain the same part of the gap with fewer parameters: two samples of delay beside
      // an input limit on a first-order plant, where a damped mode (ζ 0.57) fitted alone 6 BIC
      // ahead of the delay and its pair reached the floor first (`--pairs any --seed 978 --ts
      // 0.05` case 2, `--seed 973 --excitation noise` case 2); the lowest validation BIC decides.
      const bool rival = searched == 1 && w.fit.bic - first_single_bic < kRivalBic;
      // Three firsts; two more while the best so far leaves the validation records far above the
      // floor (kFarAboveFloor times its variance): the effect a pair needs first can rank low
      // alone (`--pairs any --integrating --seed 980` case 28: an input limit beside a backlash of
      // r 0.3, the backlash alone fifth and the limit not eligible, the third first's pair at 2.3
      // times the floor; backlash first, the limit is its second at the floor).
      const double best_mse = best.kept ? best.pair.fit.validation_mse : top.validation_mse;
      const bool far = floor_known && best_mse > kFarAboveFloor * floor.sigma * floor.sigma;
      if (searched > 0 && (!floor_known || at_floor_only || searched == 5 || (searched == 3 && !far) ||
                           (best.kept && within_floor(best.pair.fit.validation_mse) && !rival)))
        break;
      if (searched == 0) first_single_bic = w.fit.bic;
      PairSearch trial = SearchSecondEffect(ctx, w, top.bic, kinds);
      report.notes.push_back(trial.note);
      ++searched;
      searched_kinds.push_back(w.fit.effects.front().kind);
      if (trial.kept && tie) tied_pairs.push_back(trial.pair);
      if (trial.kept && (!best.kept || trial.pair.fit.bic < best.pair.fit.bic)) best = std::move(trial);
    }
    // The best pair is also reached from its other effect when that was not a first and the
    // pair still leaves the validation records above the floor: a first effect fitted alone
    // can sit far from its value in the pair (an input saturation's limits bent to mimic the
    // friction it lacks), and the pair refit starts from that fit; the second effect fitted
    // alone, first here, gives the other start (friction with a saturation, zeros plant).
    if (best.kept && floor_known && !within_floor(best.pair.fit.validation_mse)) {
      const EffectKind other = best.pair.fit.effects[1].kind;
      if (std::find(searched_kinds.begin(), searched_kinds.end(), other) == searched_kinds.end())
        for (const CandidateWork& w : work) {
          if (!w.fit.eligible || w.fit.effects.empty() || w.fit.effects.front().kind != other) continue;
          PairSearch trial = SearchSecondEffect(ctx, w, top.bic, kinds);
          report.notes.push_back(trial.note + " (the best pair's other effect as the first)");
          ++searched;
          if (trial.kept && trial.pair.fit.bic < best.pair.fit.bic) best = std::move(trial);
          break;
        }
    }
    // The best pair's first effect a delay, a lag or a resonance: its kin (another of the three)
    // can stand in for it alone, up to a bend of the plant, and rank ahead of it on validation by
    // what the second effect leaves (a delay of two samples beside an output clip on a lightly
    // damped plant: the lag alone 22 BIC ahead, its pair reached the floor first and ended the
    // search; `gap bench --cases 52 --seed 7601 --offsets --combos 0.3 --pairs any --damping
    // 0.02,0.3` case 26). The kin that was not a first, where it is eligible alone, is fitted
    // with the same second effect; the lower validation BIC decides, unless the validation
    // records cannot tell the two pairs apart and the estimation records can.
    if (best.kept && IsLinearEffect(best.pair.fit.effects[0].kind)) {
      const EffectKind second = best.pair.fit.effects[1].kind;
      for (const CandidateWork& w : work) {
        if (!w.fit.eligible || w.fit.effects.size() != 1) continue;
        const EffectKind kin = w.fit.effects.front().kind;
        if (!IsLinearEffect(kin) || kin == second ||
            std::find(searched_kinds.begin(), searched_kinds.end(), kin) != searched_kinds.end())
          continue;
        PairSearch trial = SearchSecondEffect(ctx, w, top.bic, {second});
        ++searched;
        searched_kinds.push_back(kin);
        if (!trial.kept) continue;
        const bool lower = trial.pair.fit.bic < best.pair.fit.bic;
        const CandidateWork& ahead = lower ? trial.pair : best.pair;
        const CandidateWork& behind = lower ? best.pair : trial.pair;
        const bool swap = behind.fit.parameters <= ahead.fit.parameters &&
                          behind.fit.estimation_mse < ahead.fit.estimation_mse &&
                          CompareOnBothRecords(ctx, ahead, behind).estimation_decides;
        const bool take = lower != swap;
        report.notes.push_back(trial.note + " (the kin of the best pair's first effect as the first; " +
                               (take ? "it replaces " : "it does not replace ") +
                               EffectName(best.pair.fit.effects[0].kind) + " with " + EffectName(second) +
                               (swap ? ": the validation records cannot tell the two pairs apart, the estimation "
                                       "records can)"
                                     : ", on validation BIC)"));
        if (take) best = std::move(trial);
      }
    }
    CandidateWork single;
    std::string prune_note;
    bool main_second = false;
    // A tie is settled only by the pair of the two tied effects: a pair that holds one of them
    // leaves the other's pair untried (`--seed 951` case 16: a lag and a resonance tied beside a
    // clip; the resonance's pair is no answer to which of the two it is).
    const auto holds_both = [&](const CandidateFit& c) {
      return c.effects.size() == 2 &&
             ((EffectName(c.effects[0].kind) == v.tied[0] && EffectName(c.effects[1].kind) == v.tied[1]) ||
              (EffectName(c.effects[0].kind) == v.tied[1] && EffectName(c.effects[1].kind) == v.tied[0]));
    };
    // A tie between two effects that each keep the same second effect (a lag and a delay, each
    // beside the quantiser both need): the two pairs differ only in the tied effect and settle
    // the tie where the records tell them apart — the validation records significantly, or, where
    // those cannot, the estimation records (CompareOnBothRecords, with the automatic Newey–West
    // lag: a quantiser's residual is a train of whole-step flips, whose BIC overstates the
    // evidence). Otherwise the tie stands.
    bool settled_by_common = false;
    double common_z = 0;  // the z that settled it
    const std::string first = best.kept ? EffectName(best.pair.fit.effects[0].kind) : "";
    if (tie && best.kept && !holds_both(best.pair.fit) && (first == v.tied[0] || first == v.tied[1])) {
      const std::string other_name = first == v.tied[0] ? v.tied[1] : v.tied[0];
      for (const CandidateWork& p : tied_pairs) {
        if (EffectName(p.fit.effects[0].kind) != other_name || p.fit.effects[1].kind != best.pair.fit.effects[1].kind)
          continue;
        const EstimationAgainstValidation t = CompareOnBothRecords(ctx, best.pair, p);
        const bool estimation = p.fit.parameters <= best.pair.fit.parameters &&
                                p.fit.estimation_mse < best.pair.fit.estimation_mse && t.estimation_decides;
        char line[400];
        std::snprintf(line, sizeof line,
                      "%s and %s each keep %s as the second effect; of the two pairs, %s (validation BIC %.1f "
                      "against %.1f; %s's gain on validation z = %.2f, %s's on the estimation records z = %.2f, "
                      "threshold %.2f)",
                      first.c_str(), other_name.c_str(), EffectName(p.fit.effects[1].kind),
                      estimation ? ("the estimation records take " + other_name + "'s").c_str()
                      : t.z_val > t.threshold ? ("the validation records take " + first + "'s").c_str()
                                              : "neither record tells them apart",
                      best.pair.fit.bic, p.fit.bic, first.c_str(), t.z_val, other_name.c_str(), t.z_est, t.threshold);
        report.notes.push_back(line);
        if (estimation) best.pair = p;
        settled_by_common = estimation || t.z_val > t.threshold;
        common_z = estimation ? t.z_est : t.z_val;
        break;
      }
    }
    const bool settles = !tie || (best.kept && (holds_both(best.pair.fit) || settled_by_common));
    const bool pruned = best.kept && settles && PruneToSingle(ctx, best.pair, single, prune_note, &main_second, work);
    if (best.kept && !settles) {
      report.notes.push_back("the tie between " + v.tied[0] + " and " + v.tied[1] + " stands: the best pair, " +
                             EffectName(best.pair.fit.effects[0].kind) + " with " +
                             EffectName(best.pair.fit.effects[1].kind) + ", does not hold both");
    } else if (pruned && tie) {
      report.notes.push_back(prune_note + "; the tie between " + v.tied[0] + " and " + v.tied[1] + " stands");
    } else if (pruned) {
      report.notes.push_back(prune_note);
      const CandidateFit& c = single.fit;
      verdict_val_mse = c.validation_mse;
      report.validation_prediction = single.y_val;
      v.effect = EffectName(c.effect.kind);
      AdoptCandidate(c, v);
      // Its BIC weight among the eligible single candidates (its own kind's first fit replaced).
      double total = 1.0;
      for (const CandidateFit& r : report.ranking)
        if (r.eligible && r.effect.kind != c.effect.kind) total += std::exp(-0.5 * (r.bic - c.bic));
      v.confidence = 1.0 / total;
    } else if (best.kept) {
      if (!prune_note.empty()) report.notes.push_back(prune_note);
      CandidateFit c = best.pair.fit;
      if (main_second) {  // the main effect first (verdict.effect)
        std::swap(c.effects[0], c.effects[1]);
        if (c.effects_std.size() == 2) std::swap(c.effects_std[0], c.effects_std[1]);
        c.effect = c.effects.front();
        c.param_std = c.effects_std.empty() ? std::vector<double>{} : c.effects_std.front();
      }
      verdict_val_mse = c.validation_mse;
      report.validation_prediction = best.pair.y_val;
      if (second_at_floor) *second_at_floor = at_floor_only;
      if (tie) {
        report.notes.push_back("the tie between " + v.tied[0] + " and " + v.tied[1] + " is settled by the pair " +
                               EffectName(c.effects[0].kind) + " with " + EffectName(c.effects[1].kind));
        v.tied.clear();
        double total = 1.0;  // the pair's BIC weight against the eligible singles
        for (const CandidateFit& r : report.ranking)
          if (r.eligible) total += std::exp(-0.5 * (r.bic - c.bic));
        v.confidence = 1.0 / total;
        // Settled between two pairs by a z test: no surer than that test (Φ(z)).
        if (settled_by_common) v.confidence = std::min(v.confidence, 0.5 * std::erfc(-common_z / std::sqrt(2.0)));
      }
      v.effect = EffectName(c.effects.front().kind);
      AdoptCandidate(c, v);
      if (searched > 1)
        report.notes.push_back(std::string("pair kept: ") + EffectName(c.effects[0].kind) + " with " +
                               EffectName(c.effects[1].kind) + " (lowest validation BIC over " +
                               std::to_string(searched) + " first effects)");
    }
  }
  // A static effect on G0 was better than the higher-order linear part alone, and no second
  // static effect explains the rest (no pair, or a lag/resonance/delay standing in for missing
  // dynamics, first or second): does the higher-order part with the static effect(s) found on it
  // beat that?
  const bool linear_stand_in = std::any_of(v.effects.begin(), v.effects.end(),
                                           [](const Effect& e) { return IsLinearEffect(e.kind); });
  const bool static_pair = v.effects.size() >= 2 && !linear_stand_in;
  if (linear.wins)  // a pair of static effects that came after it must be beaten
    unmodelled = AdoptHigherOrder(ctx, linear, top, report,
                                  static_pair ? HigherOrderMode::kAgainstPair : HigherOrderMode::kAdopt);
  else if (linear.beats_linear && v.effect != "ambiguous" && !within_floor(verdict_val_mse) && !static_pair) {
    // What the verdict leaves must follow the input for more dynamics to explain it: a hum on a
    // friction case (seed 31, case 47) was taken by the order-4 part's free response.
    std::string note;
    if (ResidualFollowsInput(validation, ctx.y_val - report.validation_prediction, &note))
      unmodelled = AdoptHigherOrder(ctx, linear, top, report, HigherOrderMode::kAgainstVerdict, true);
    else
      report.notes.push_back("linear order check: not against " + v.effect + ": what it leaves on the validation "
                             "records does not follow the input (" + note + ")");
  }
  std::vector<GapRecord> all_records = estimation;
  all_records.insert(all_records.end(), validation.begin(), validation.end());
  const OutputLattice lattice = DetectOutputLattice(all_records, ctx.q_step, floor.sigma);
  NameLatticeQuantisation(lattice, noise_nrmse, report);
  // An effect that only the estimation records reach (`gap bench --offsets --snr 20 --seed 4020`,
  // case 62: an output clip that the estimation record's trough reaches and the validation
  // record's does not; G0 leaves the estimation records at 3.5 times the noise variance, the
  // clip brings them to the floor at LR 4332, and on validation G0 is within the noise, so the
  // validation BIC put `none` on top and the explanation said G0 fits within the noise). Where
  // G0 fits the validation records within the noise but leaves a gap on the estimation records
  // (N·MSE/σ² above N + 3√(2N), the test of where.gap_significant, σ the independent floor)
  // that follows the input, a single effect that passed the likelihood-ratio test, brings the
  // estimation records within the floor and does no worse than G0 on validation is named, and
  // the notes say that the validation records do not confirm it (shrink stays 0: there is no
  // gap on them to close).
  if (v.effect == "none" && v.g0_gap == "within_noise" && floor_known) {
    const double s2 = floor.sigma * floor.sigma;
    const CandidateWork* as_given = nullptr;
    for (const CandidateWork& w : work)
      if (w.fit.effect.kind == EffectKind::kNone && w.fit.effects.size() <= 1) as_given = &w;
    const double n = static_cast<double>(n_est);
    if (as_given && AboveNoiseVariance(as_given->fit.estimation_mse / s2, n)) {
      const CandidateWork* best = nullptr;
      auto estimation_bic = [&](const CandidateFit& c) { return n * std::log(c.estimation_mse) + c.parameters * std::log(n); };
      for (const CandidateWork& w : work) {
        const CandidateFit& c = w.fit;
        if (c.effect.kind == EffectKind::kNone || c.effect.kind == EffectKind::kParameterMismatch ||
            c.effects.size() > 1 || w.masked || !c.significant ||
            !(c.estimation_mse <= s2 * SampleVarianceTolerance(n_est)) ||
            !(c.validation_mse <= as_given->fit.validation_mse * SampleVarianceTolerance(n_val)))
          continue;
        if (!best || estimation_bic(c) < estimation_bic(best->fit)) best = &w;
      }
      std::string input_note;
      auto gap_follows_input = [&] {  // G0 simulated on the estimation records only when it is needed
        const Eigen::VectorXd y_est = Stack(estimation, [](const GapRecord& r) { return r.y; });
        const Eigen::VectorXd y0_est =
            Stack(estimation, [&](const GapRecord& r) { return as_is.Predict(as_is_fit.x, r); });
        return ResidualFollowsInput(estimation, y_est - y0_est, &input_note);
      };
      if (best && gap_follows_input()) {
        const CandidateFit& c = best->fit;
        v.effect = EffectName(c.effect.kind);
        v.confidence = 1.0;
        AdoptCandidate(c, v);
        v.estimation_only = true;
        report.validation_prediction = best->y_val;
        char line[600];
        std::snprintf(line, sizeof line,
                      "%s found on the estimation records only: G0 leaves them at %.3g times the noise variance "
                      "(the gap follows the input: %s), %s brings them to %.3g times it (LR %.1f, threshold %.1f); "
                      "on the validation records G0 is within the noise (validation MSE %.4g, with %s %.4g), so "
                      "they do not reach where it acts and do not confirm it — record validation data over the "
                      "estimation records' range",
                      EffectName(c.effect.kind), as_given->fit.estimation_mse / s2, input_note.c_str(),
                      EffectName(c.effect.kind), c.estimation_mse / s2, c.likelihood_ratio, c.lr_threshold,
                      as_given->fit.validation_mse, EffectName(c.effect.kind), c.validation_mse);
        report.notes.push_back(line);
      }
    }
  }
  ApplyNoiseFloor(noise_nrmse, v);  // after the second effect: nrmse_after is final
  if (v.effect == "none" && gap_unexplained) {
    v.effect = "unexplained";
    v.confidence = 0.0;
    char line[300];
    std::snprintf(line, sizeof line,
                  "the gap is beyond the noise (validation NRMSE %.4g, floor %.4g) and follows the input, but "
                  "no effect of the library and no linear part of order %d explains it: a missing input, an "
                  "effect outside the library, or a sim model of another structure",
                  v.nrmse_after, noise_nrmse, g0.Order() + 2);
    v.explanation = line;
  } else if (v.effect == "none" && v.g0_gap == "does_not_follow_input") {
    char line[300];
    std::snprintf(line, sizeof line,
                  "no effect of the plant: what G0 leaves on the validation records (NRMSE %.4g, floor %.4g) "
                  "does not follow the input — an output disturbance or coloured noise, which no candidate "
                  "explains better than noise",
                  v.nrmse_before, noise_nrmse);
    v.explanation = line;
  } else if (v.effect == "none")
    v.explanation = "no candidate explains the gap better than noise: G0 fits within the noise";
  else if (v.estimation_only)
    v.explanation = v.effect + " explains the gap G0 leaves on the estimation records; the validation records do "
                    "not reach where it acts (G0 fits them within the noise), so it is not confirmed on them";
  else if (v.effect == "unmodelled_dynamics")
    v.explanation = "the linear part lacks dynamics: a linear model of order " +
                    std::to_string(v.linear_order) + " beats every linear explanation (validation NRMSE " +
                    std::to_string(v.linear_nrmse_after) + ")" +
                    (v.effects.empty() ? std::string("; no static effect remains after it")
                                       : "; after it, " + std::string(EffectName(v.effects[0].kind)) +
                                             " brings the validation NRMSE to " + std::to_string(v.nrmse_after));
  else if (v.effect == "ambiguous")
    v.explanation = "the top candidates (" + v.tied[0] + ", " + v.tied[1] +
                    (v.tied.size() > 2 ? ", …" : "") +
                    ") fit the validation data equally well; more informative data would separate them";
  else {
    std::string named = v.effect;
    if (v.effects.size() > 1) named += " with " + std::string(EffectName(v.effects[1].kind));
    v.explanation = named + " closes " + std::to_string(int(std::round(100 * v.shrink))) +
                    " % of the explainable gap on the validation records";
  }

  // The reported model's delay line holds a free level before each record (PreRecordResponse,
  // candidate_fit.cc) where its delay is a whole sample or more.
  double delay = v.plant.delay_s;
  for (const Effect& e : v.effects)
    if (e.kind == EffectKind::kTimeDelay && !e.params.empty()) delay += e.params[0];
  if (HasDelayLine(delay, ts))
    v.nuisance.initial_state += "; the model's delay line also holds a free input level at the start of each record";
  if (std::any_of(v.effects.begin(), v.effects.end(), [](const Effect& e) { return e.kind == EffectKind::kBacklash; }))
    v.nuisance.initial_state += "; the backlash's play starts where it was left before each record (the best of a "
                                "grid across its band around the first command, Candidate::PlayStates)";

  // An actuator offset that the records do not pin down is reported as fitted, and said to be
  // so: its 1σ beyond the span of the input, where another parameter (a dead zone's edges, the
  // output offset through a near-linear plant) takes up what it does (DaISy exchanger, cubic
  // spring with a dead zone: du −0.06 ± 99 on an input that spans 0.6).
  if (v.nuisance.input_offset_fitted && v.nuisance.input_offset_std > 0) {
    double lo = INFINITY, hi = -INFINITY;
    for (const GapRecord& r : estimation)
      if (r.u.size() > 0) lo = std::min(lo, r.u.minCoeff()), hi = std::max(hi, r.u.maxCoeff());
    if (hi > lo && !(v.nuisance.input_offset_std <= hi - lo)) {
      char line[400];
      std::snprintf(line, sizeof line,
                    "the actuator offset is not determined by these records: du = %.4g ± %.4g, its 1σ more than "
                    "the input's span on the estimation records (%.4g); another parameter of the model takes up "
                    "what it does, and verdict.nuisance.input_offset is no operating point to rely on",
                    v.nuisance.input_offset, v.nuisance.input_offset_std, hi - lo);
      report.notes.push_back(line);
    }
  }
  report.where = LocateGap(g0, validation, floor.sigma);
  report.where.noise_nrmse = noise_nrmse;
  report.where.noise_floor = floor;
  report.where.lattice = lattice;
  report.where.detection_lines = AnalyseDetectionLines(all_records, &g0);
  return report;
}

}  // namespace

// A sensor step is looked for against G0 first (DiagnoseGapOnce); one that a large gap hides
// stands out of what the diagnosed model leaves: then it is marked and the records are
// diagnosed again, once.
GapReport DiagnoseGap(const TransferFunction& sim_model, const std::vector<GapRecord>& estimation_raw,
                      const std::vector<GapRecord>& validation_raw, const GapOptions& options) {
  GapReport bridged;  // the glitches bridged, once for both diagnoses
  const std::vector<GapRecord> estimation =
      options.bridge_glitches ? BridgeGlitches(estimation_raw, "estimation", bridged) : estimation_raw;
  const std::vector<GapRecord> validation =
      options.bridge_glitches ? BridgeGlitches(validation_raw, "validation", bridged) : validation_raw;
  // A second effect searched though the first effect reached the floor (multiple shooting:
  // the segments' free states take up part of what a second effect does) must be found again by
  // the diagnosis on segments twice as long. A load disturbance's walk within a segment can pass
  // for an effect (`gap bench --cases 26 --seed 2005 --integrating --process-noise 0.5 --offsets`,
  // case 7: a cubic spring beside a backlash, LR 21.1, on segments of 250 and 500 samples, not on
  // 1000); an effect of the rig stays (`--cases 40 --seed 5002 --combos 1 --pairs any
  // --integrating --offsets`, case 36: a cubic spring beside a dead zone on 500 and 1000, LR 53.6
  // on 500; case 28: an input limit beside a backlash). Otherwise the diagnosis is run again
  // without that search, and the first effect stands alone.
  const auto diagnose_once = [&](const std::vector<GapRecord>& est, const std::vector<GapRecord>& val,
                                 const GapOptions& opts, const GapReport& seed) {
    bool at_floor = false;
    GapReport report = DiagnoseGapOnce(sim_model, est, val, opts, seed, &at_floor);
    if (!at_floor || opts.fixed_segment >= 0 || report.verdict.effects.size() < 2) return report;
    const GapVerdict& v = report.verdict;
    GapOptions longer = opts;
    longer.fixed_segment = 2 * v.shooting_segment;
    longer.fixed_integrating = v.integrating;
    const GapReport check = DiagnoseGapOnce(sim_model, est, val, longer, seed);
    const auto kinds = [](const GapVerdict& verdict) {
      std::vector<EffectKind> k;
      for (const Effect& e : verdict.effects) k.push_back(e.kind);
      std::sort(k.begin(), k.end());
      return k;
    };
    const auto names = [](const GapVerdict& verdict) {  // "a with b"; the verdict's word where it names none
      std::string s;
      for (const Effect& e : verdict.effects) s += std::string(s.empty() ? "" : " with ") + EffectName(e.kind);
      return s.empty() ? verdict.effect : s;
    };
    const std::string pair = names(v);
    const std::string segments = "segments of " + std::to_string(longer.fixed_segment) + " samples";
    if (kinds(check.verdict) == kinds(v)) {
      report.notes.push_back("the pair " + pair + ", searched at the floor, is found again on " + segments);
      return report;
    }
    GapOptions without = opts;
    without.second_effect_at_floor = false;
    GapReport seeded = seed;
    seeded.notes.push_back("the pair " + pair + ", searched though " + EffectName(v.effects[0].kind) +
                           " reached the floor, is not found again on " + segments + " (they name " + names(check.verdict) +
                           "), so it is dropped: a walk within the segments can pass for an effect");
    return DiagnoseGapOnce(sim_model, est, val, without, seeded);
  };
  GapReport first = diagnose_once(estimation, validation, options, bridged);
  const double ts = estimation.front().sample_time;
  const int order = ContinuousSimModel(sim_model, ts).Order();
  // A load disturbance on an integrating or lightly damped rig (process noise, a varying load)
  // integrates into a walk that the free state of each shooting segment takes only at the
  // segment's start; what is left within a segment is slow, and a sensor map's y² and y³ or the
  // refit's gain follow it in most segments (`gap bench --cases 20 --seed 2002 --only none
  // --integrating --process-noise 0.5 --offsets`: a sensor map or a gain named in 8 of 20 `none`
  // cases, each closing about 2 % of the validation NRMSE, its validation gain z 3–6.5 with the
  // automatic lag; signature 0.08–0.25). Where G0's own gap is within the noise or does not
  // follow the input, and the diagnosis names one effect that matches little of the gap
  // (signature under min_signature: admitted by its validation gain alone, the route that
  // correlated noise can pass), the records are diagnosed again with segments half as long, where
  // the walk within a segment is smaller. An effect of the rig persists there (perhaps as a
  // weaker or kindred candidate); a walk does not. So the second diagnosis replaces the first only
  // when it finds nothing: a 3-sample delay within the noise became parameter_mismatch on the
  // shorter segments (`--cases 26 --seed 44 --integrating --offsets`, case 15) and keeps its name.
  // An effect that matches the gap is not checked: the shorter segments' free states also take
  // a slow gap of the rig's own (a gain error on an integrator, signature 0.37, `--seed 83
  // --integrating --noise-pole 0.7`, case 14; a sensor map within the noise beside a delay,
  // signature 0.21, `--seed 980 --combos 1 --pairs any --integrating --excitation levels`, case 8:
  // both came out `none` on 250-sample segments).
  GapOptions used = options;
  {
    const GapVerdict& v = first.verdict;
    const long halved = v.shooting_segment / 2;
    if (options.fixed_segment < 0 && v.fit_scheme == "multiple_shooting" &&
        halved >= kShortestSegmentPerOrder * (order + 1) &&
        (v.g0_gap == "within_noise" || v.g0_gap == "does_not_follow_input") && v.effect != "none" &&
        v.effect != "unexplained" && v.effect != "unmodelled_dynamics" && v.effects.size() <= 1 &&
        !first.ranking.empty() && first.ranking.front().signature < options.min_signature) {
      GapOptions shorter = options;
      shorter.fixed_segment = halved;
      shorter.second_effect_at_floor = false;
      shorter.fixed_integrating = v.integrating;
      const std::string why = "G0's validation gap " +
                              std::string(v.g0_gap == "within_noise" ? "is within the noise floor"
                                                                     : "does not follow the input") +
                              ": a load disturbance's walk within a shooting segment could pass for an effect, so the "
                              "records were diagnosed again with segments of " + std::to_string(halved) +
                              " samples";
      GapReport second = DiagnoseGapOnce(sim_model, estimation, validation, shorter, bridged);
      // Nothing, or a tie that holds the refit's gain but not the first's effect: under a
      // two-valued input an input map is a gain, and a gap the shorter segments leave to a gain
      // is no effect of the first's kind (`gap bench --cases 26 --seed 2005 --integrating
      // --process-noise 0.5 --offsets --only input_saturation,dead_zone`: 9 of the 19 cases under a
      // two-valued input named a sensor map, a spring, friction, a clip or a quantiser fitted to
      // the walk, `ambiguous` on 250-sample segments).
      const std::vector<std::string>& tied = second.verdict.tied;
      const bool gain_tie = second.verdict.effect == "ambiguous" &&
                            std::find(tied.begin(), tied.end(), "parameter_mismatch") != tied.end() &&
                            std::find(tied.begin(), tied.end(), v.effect) == tied.end();
      if (second.verdict.effect == "none" || gain_tie) {
        std::string tie;
        for (const std::string& t : tied) tie += (tie.empty() ? "" : ", ") + t;
        const auto at = second.notes.begin() + static_cast<long>(std::min(bridged.notes.size(), second.notes.size()));
        second.notes.insert(at, why + " (with " + std::to_string(v.shooting_segment) + " the diagnosis named " +
                                    v.effect + "; with " + std::to_string(halved) + " it names " +
                                    (gain_tie ? "only a tie with a gain change: " + tie : std::string("nothing")) +
                                    ", and that stands)");
        first = std::move(second);
        used = shorter;
      } else {
        first.notes.push_back(why + ": they name " + second.verdict.effect + ", so the effect does not rest on the " +
                              "longer segments, and the diagnosis with " + std::to_string(v.shooting_segment) +
                              " stands");
      }
    }
  }
  const GapVerdict& v = first.verdict;
  // Only where the diagnosed model leaves the validation records well above the noise floor: a
  // step left in the records would; a fit at the floor has no step to find (and its residual's
  // spread is so small that a sharp model mismatch, a backlash taking up its play, could pass).
  if (!options.find_sensor_steps || v.effect == "none" || v.effect == "unexplained" || v.plant.den.size() == 0 ||
      !(v.nrmse_after > kStepSearchAboveFloor * v.noise_nrmse))
    return first;
  const long min_samples = std::max(20, 10 * (order + 4));
  const double du = v.nuisance.input_offset_fitted ? v.nuisance.input_offset : 0.0;
  const auto diagnosed = [&](const GapRecord& r) {
    EffectSimulationOptions sim;
    sim.substeps = options.substeps;
    return SimulateWithEffects(v.plant, InRigOrder(v.effects), Eigen::VectorXd(r.u.array() + du), r.sample_time, sim);
  };
  GapReport marks;
  const std::string name = "the diagnosed model's output (" + v.effect + ")";
  const std::vector<GapRecord> estimation_marked =
      MarkSensorSteps(estimation, "estimation", diagnosed, name, min_samples, marks);
  const std::vector<GapRecord> validation_marked =
      MarkSensorSteps(validation, "validation", diagnosed, name, min_samples, marks);
  if (marks.sensor_steps.empty()) return first;
  // The notes: the bridging's, then these marks and why the records were diagnosed again, then
  // the second diagnosis's own.
  GapReport seeded = bridged;
  seeded.notes.insert(seeded.notes.end(), marks.notes.begin(), marks.notes.end());
  seeded.notes.push_back("diagnosed again with those sensor steps (the first diagnosis, without them, said " +
                         v.effect + ")");
  seeded.sensor_steps = marks.sensor_steps;
  GapReport second = diagnose_once(estimation_marked, validation_marked, used, seeded);
  // Kept only when the steps explain a good part of what was left: the validation NRMSE falls
  // by a fifth or more (a step is a level change the records carry for hundreds of samples).
  if (!(second.verdict.nrmse_after < kStepGainRequired * v.nrmse_after)) {
    std::ostringstream msg;
    msg << "sensor steps found against the diagnosed model (" << marks.sensor_steps.size()
        << ") were not kept: with them the validation NRMSE is " << second.verdict.nrmse_after << " against "
        << v.nrmse_after;
    first.notes.push_back(msg.str());
    return first;
  }
  return second;
}

}  // namespace idrig
