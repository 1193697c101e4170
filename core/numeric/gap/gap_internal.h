#pragma once
// Shared declarations of the gap diagnosis' parts (internal to core/numeric/gap):
// candidate_fit.cc (one candidate's model and its output-error fit), ranking.cc (likelihood-ratio
// tests, validation BIC, signature, eligibility and weights), gap_report.cc (data checks, the
// verdict and DiagnoseGap itself). Not a public interface.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/numeric/gap/gap_diagnosis.h"

namespace idrig::gap_detail {

[[noreturn]] void Fail(const std::string& message);

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

double Quantile(std::vector<double> v, double p);

struct Scales {
  double ts = 1, slow = 1, u_max = 1, y_max = 1;
  double duration = 1;  // [s] the longest record (estimation or validation): a bound on delays
  double lag_of_best_match = 0;  // [s] shift of G0's output that best matches y (cross-correlation)
  double u_quantile[5] = {0, 0, 0, 0, 0};  // 2, 15, 50, 85, 98 %
  double y_quantile[4] = {0, 0, 0, 0};     // 0.5, 2, 98, 99.5 %
  // Tails for the grid starts of limits: quantiles kTailShares of u and of y (y less the refit's
  // output offset), low side and high side (1 − share).
  static constexpr double kTailShares[6] = {0.001, 0.01, 0.03, 0.07, 0.15, 0.3};
  double u_low[6] = {}, u_high[6] = {}, y_low[6] = {}, y_high[6] = {};
  // The same for the measured y as it is: an output clip's limits are in those coordinates
  // (OffsetAndStateThroughMaps; a clip never shares a candidate with a sensor map).
  double y_measured_quantile[4] = {0, 0, 0, 0};
  double y_measured_low[6] = {}, y_measured_high[6] = {};
};

// What a candidate contains: 0–2 effects (kNone / kParameterMismatch carry no parameters), each
// with its fixed sub-variant (|y| for the sensor, the step for quantisation), whether G0's
// coefficients move, and the nuisance parameters every candidate has.
struct CandidateSpec {
  std::vector<EffectKind> kinds;
  std::vector<std::vector<double>> fixed;  // per kind (may be shorter: empty)
  bool fit_plant = true;
  bool input_offset = false;  // an actuator offset du (fitted by LM): u → u + du
  bool free_state = true;     // output offset and free initial state by variable projection
  long segment = 0;           // samples per shooting segment (own state each); 0: whole record
  // A sensor drift per record (segment), a ramp beside the output offset, by variable projection:
  // set where it is not an input offset in disguise (ChooseFitScheme).
  bool drift = false;
};

struct Nuisance {
  double input_offset = 0, output_offset = 0;  // du, and b of the first segment
  double output_drift = 0;                     // d of the first segment [y units/s] (spec.drift)
  double initial_state_rms = 0;                // RMS of the first segment's x0 (realisation units)
  // The sensor's level at every sample of the record — b + d·(t − t_mid) plus the levels its
  // sensor steps add (the first segment's coefficients) — for putting measured outputs into the
  // plant's coordinates.
  Eigen::VectorXd output_level;
};

// candidate_fit.cc: the plant's delay-free sampled realisation (zero-order hold; order 0: no
// states), its free response (row k = C A^k; fewer than n rows where it has decayed to zero: the
// missing rows are zeros) and the shooting segments of a record's scored samples, as (start,
// length): one, or every `segment` samples (the remainder spread over them).
StateSpace SampledUndelayed(const TransferFunction& plant, double ts);
Eigen::MatrixXd FreeResponse(const StateSpace& d, long n);
std::vector<std::pair<long, long>> Segments(const GapRecord& record, long segment);
// Least squares of r on [1, F] (F = the free response's first rows, zero below them): [b; x0].
// With `extra` (the sensor's own columns, as long as r: a drift's ramp, a step's level): on
// [1, F, extra], [b; x0; c]. Equilibrated normal equations, a minimum-norm solution where the
// columns are nearly dependent; `rank`: the columns' numerical rank.
Eigen::VectorXd OffsetAndStateFit(const Eigen::VectorXd& r, const Eigen::MatrixXd& free_rows, long* rank = nullptr,
                                  const Eigen::MatrixXd* extra = nullptr);

// One candidate: x = [θ (plant log multipliers) | du | φ_1 | φ_2].
class Candidate {
 public:
  Candidate(const TransferFunction& base, const CandidateSpec& spec, const Scales& scales,
            int substeps);

  static int NumEffectParams(EffectKind kind, const std::vector<double>& fixed);

  int PlantParams() const {
    return static_cast<int>(free_den_.size() + free_num_.size()) + (gain_only_ ? 1 : 0);
  }
  int NuisanceParams() const { return spec_.input_offset ? 1 : 0; }
  // Only the plant's gain moves (one multiplier on num): a gap that is a pure gain change.
  void SetGainOnly() {
    free_den_.clear();
    free_num_.clear();
    gain_only_ = true;
    block_start_.assign(block_start_.size(), PlantParams() + NuisanceParams());
  }
  int EffectParams() const { return effect_params_; }
  int Blocks() const { return static_cast<int>(spec_.kinds.size()); }
  int BlockStart(size_t i) const { return block_start_[i]; }
  int BlockSize(size_t i) const { return block_size_[i]; }
  int Size() const { return PlantParams() + NuisanceParams() + EffectParams(); }
  const CandidateSpec& spec() const { return spec_; }

  TransferFunction Plant(const Eigen::VectorXd& x) const;
  double InputOffset(const Eigen::VectorXd& x) const;
  // φ → physical parameters, in EffectParameterNames order: block i, the first, all real ones.
  Effect EffectAt(const Eigen::VectorXd& x, size_t i) const;
  Effect EffectOf(const Eigen::VectorXd& x) const;
  std::vector<Effect> Effects(const Eigen::VectorXd& x) const;
  // Inverse of EffectAt for block i, for starting points given in physical units.
  Eigen::VectorXd Phi(size_t i, const std::vector<double>& p) const;
  // The plant with its effects and input offset, from rest (no output nuisance). With
  // `output_maps`, the output saturation and sensor map are left out and returned there.
  // `play_state`: the backlash's output before the record (EffectSimulationOptions).
  Eigen::VectorXd Simulate(const Eigen::VectorXd& x, const GapRecord& record,
                           std::vector<Effect>* output_maps = nullptr, double play_state = 0.0) const;
  // Simulate + the output offset and free initial state(s) fitted by least squares; with a
  // backlash, also where its play was left before the record (PlayStates: the best of a grid).
  Eigen::VectorXd Predict(const Eigen::VectorXd& x, const GapRecord& record,
                          Nuisance* nuisance = nullptr) const;
  // How many nuisance columns Predict fits on these records: per record and segment the rank of
  // [1, F] (output offset and free initial state). They are fitted on validation records too,
  // so a candidate with more states (a lag, a resonance, a higher order), above all under
  // multiple shooting, gets a lower validation MSE for free; the scores count them.
  long NuisanceColumns(const Eigen::VectorXd& x, const std::vector<GapRecord>& records) const;
  // The plant with the linear effects (lag, resonance, delay) folded in: what the free
  // response of the nuisance comes from.
  TransferFunction LinearPart(const Eigen::VectorXd& x) const;
  // With a backlash: the play's outputs before the record that Predict chooses from, across the
  // band [v0 − r, v0 + r] around the play's first input v0 (its state after the first sample is
  // in that band whatever it was before); empty without a backlash. `taken_up`: a sample by
  // which every start has been taken up the same way (the play's input has moved 2r from v0;
  // the record's length if it never does).
  std::vector<double> PlayStates(const Eigen::VectorXd& x, const GapRecord& record,
                                 long* taken_up = nullptr) const;

 private:
  // What a prediction's nuisance fit needs of the linear part at x on segments of up to `longest`
  // samples: the free response F, the first segment's state columns (F and the delay line's
  // level) and, behind a |y| sensor, the settled direction. The same for every play state
  // (Predict computes it once for them all).
  struct FreeRows {
    long longest = -1;
    Eigen::MatrixXd free, first;
    Eigen::VectorXd settled;
  };
  FreeRows Rows(const Eigen::VectorXd& x, double sample_time, long longest, bool absolute_sensor) const;
  Eigen::VectorXd PredictFrom(const Eigen::VectorXd& x, const GapRecord& record, Nuisance* nuisance,
                              double play_state, FreeRows* rows = nullptr) const;
  TransferFunction base_;
  CandidateSpec spec_;
  Scales scales_;
  int substeps_;
  std::vector<int> free_den_, free_num_;
  bool gain_only_ = false;
  std::vector<int> block_start_, block_size_;
  int effect_params_ = 0;
};

// Residuals y − ŷ over the scored samples of every record, as one vector.
struct Residuals {
  const Candidate* candidate;
  const std::vector<GapRecord>* records;
  long count = 0;
  void operator()(const Eigen::VectorXd& x, Eigen::VectorXd& r) const;
};

struct LmFunctor {
  using Scalar = double;
  enum { InputsAtCompileTime = Eigen::Dynamic, ValuesAtCompileTime = Eigen::Dynamic };
  using InputType = Eigen::VectorXd;
  using ValueType = Eigen::VectorXd;
  using JacobianType = Eigen::MatrixXd;
  Residuals residuals;
  int n_inputs = 0;
  int* calls = nullptr;
  int inputs() const { return n_inputs; }
  int values() const { return static_cast<int>(residuals.count); }
  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& f) const {
    ++*calls;
    residuals(x, f);
    return 0;
  }
};

double Mse(const Residuals& residuals, const Eigen::VectorXd& x);

struct FitOutcome {
  Eigen::VectorXd x;
  double mse = kNan;
  int evaluations = 0;
  bool converged = false;
};

FitOutcome Minimise(const Residuals& residuals, Eigen::VectorXd x, int max_evaluations);

// Starting points (physical units) for each effect, from the data's scales.
std::vector<std::vector<double>> Starts(EffectKind kind, const Scales& s);

// Candidate quantisation step from the samples' lattice; *strength = its mean resultant length.
// The grid of steps is scored on up to `threads` threads (the same result on any number).
double QuantisationStep(const std::vector<GapRecord>& records, double* strength, int threads = 1);
// In place: y → E[q·round((y + n)/q)], n ~ N(0, s²) (the quantisation candidate's predictor).
void SmoothedStaircase(Eigen::VectorXd& y, double q, double s);

// Every sample within 2 % of the range from the minimum or the maximum.
bool BinaryInput(const std::vector<GapRecord>& records);
// 1 + two standard deviations of a χ²_n sample variance, σ²(1 + 2√(2/n))/σ²: how much larger an
// MSE of n samples may come out than the variance it estimates and still be that variance.
inline double SampleVarianceTolerance(long n) { return 1 + 2 * std::sqrt(2.0 / std::max<long>(1, n)); }

// Whether a delay of `delay_s` fills a line of a whole sample or more at sample time ts (its
// whole part, as the simulator takes it). Such a line holds a free level before the record
// (PreRecordResponse).
inline bool HasDelayLine(double delay_s, double ts) { return std::floor(delay_s / ts + 1e-12) >= 1; }

// Whether the input explains a validation residual (concatenated over the records' scored
// samples, as Stack makes it): the prewhitened test of validation.h, AR(10), lags 0..20 and
// geometric beyond, per record, at 99.9 %; `note` gets its figures. Records too short for it
// say so and count as not explained.
bool ResidualFollowsInput(const std::vector<GapRecord>& validation, const Eigen::VectorXd& residual,
                          std::string* note);

double Correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b);
// Validation BIC with the nuisance fitted on the validation records counted: N_val ln V̂ +
// k ln N_est, V̂ = mse·N_val/(N_val − nuisance_val) the unbiased residual variance.
double ValidationBic(long n_val, long n_est, double mse, int parameters, long nuisance_val);
// How significantly y_c simulates y better than y_ref (Diebold–Mariano): d_k = (y − y_ref)² −
// (y − y_c)², z = (mean(d) − bias)/se with the Newey–West (Bartlett, lag 4(N/100)^(2/9))
// standard error; 0 when d is identically zero. `bias`: the gain y_c gets for free from the
// extra nuisance columns it fits on these records (their count times σ²/N). `automatic_lag`:
// the lag is at least Andrews' (1991) AR(1) plug-in for the Bartlett kernel,
// 1.1447 (α N)^(1/3) with α = 4ρ²/((1 − ρ)²(1 + ρ)²) and ρ the lag-1 autocorrelation of d —
// long enough for noise of a long correlation time, which the fixed lag under-covers.
double ValidationGainZ(const Eigen::VectorXd& y, const Eigen::VectorXd& y_ref, const Eigen::VectorXd& y_c,
                       double bias = 0.0, bool automatic_lag = false);
// The `bias` for ValidationGainZ of a fit `c` that fits `extra` more nuisance columns on the
// validation records than its reference: extra · σ̂²/N with σ̂² = mse·N_val/(N_val − nuisance_val).
double NuisanceGainBias(long extra, double validation_mse, long n_val, long nuisance_val);
// One-sided normal quantile at level `alpha` (z with P(Z > z) = alpha).
double NormalUpperQuantile(double alpha);
// Whether a mode decaying at `decay_rate` [1/s] (−Re(s), ζω for a resonance) still has its
// envelope above 1 % at the end of `horizon_s`: its free response lasts over the record.
inline bool OutlastsRecord(double decay_rate, double horizon_s) {
  return !(decay_rate * horizon_s > std::log(100.0));
}

// Samples scored in the longest of the records (after its warm-up).
inline long LongestScored(const std::vector<GapRecord>& records) {
  long longest = 0;
  for (const auto& r : records) longest = std::max<long>(longest, r.u.size() - r.score_from);
  return longest;
}

// The first `length` samples of `record` (its sensor steps within them; score_from kept).
GapRecord RecordHead(const GapRecord& record, long length);

// Simulation over the scored samples of every record, concatenated.
Eigen::VectorXd Stack(const std::vector<GapRecord>& records,
                      const std::function<Eigen::VectorXd(const GapRecord&)>& f);

// A fitted candidate with its validation prediction (concatenated scored samples).
struct CandidateWork {
  CandidateFit fit;
  Eigen::VectorXd y_val;
  Eigen::VectorXd x;             // fitted parameter vector
  CandidateSpec spec;            // what was fitted
  bool masked = false;           // not eligible: the same map as a better-named candidate (note says)
  bool gain_significant = false; // validation_gain_z above the normal quantile at `significance`
};

// Everything the candidates share: the data, the scales, G0 and its refit.
struct FitContext {
  const TransferFunction* g0 = nullptr;
  const std::vector<GapRecord>* estimation = nullptr;
  const std::vector<GapRecord>* validation = nullptr;
  const GapOptions* options = nullptr;
  Scales scales;
  long n_est = 0, n_val = 0;
  Eigen::VectorXd y_val, y0_val, y_refit_val;  // measured, G0, refitted G0 on validation
  double as_is_mse = 0;                         // G0 (with nuisance) on estimation
  double mirrored_du = 0;                       // G0's du (x's coordinate) on the estimation records with y → −y
  FitOutcome refit_fit;                         // refitted G0 (parameter_mismatch)
  CandidateSpec nuisance;                       // the nuisance setting every candidate shares
  bool integrating = false;                     // G0 integrates: du in every candidate
  int refit_size = 0;
  long refit_nuisance_est = 0, refit_nuisance_val = 0;  // the refit's nuisance columns (Candidate::NuisanceColumns)
  int as_is_size = 0;                           // fitted parameters of `none` (du when integrating)
  double q_step = 0, q_strength = 0, q_phase = 0;  // the output lattice: q_phase + k·q_step
  int k_effects = 1;                            // effects tested (Bonferroni)
};

// Mean squared simulation error of `y_hat` on the validation records' scored samples.
inline double ValidationMse(const FitContext& ctx, const Eigen::VectorXd& y_hat) {
  return (ctx.y_val - y_hat).squaredNorm() / ctx.n_val;
}

// The spec of a candidate with these effects and the context's nuisance setting.
CandidateSpec SpecFor(const FitContext& ctx, std::vector<EffectKind> kinds,
                      std::vector<std::vector<double>> fixed = {});

// Fits a candidate: every prefix (θ, du and the earlier blocks' φ, as a fitted x; shorter
// prefixes are padded with zeros) times every start of the last block (physical units). The
// best is polished. Fills effect(s), plant, parameters, estimation_mse, the 1σ of every effect
// block and of du, the output offsets, evaluations, the validation prediction, x and spec.
void FitSpec(const FitContext& ctx, const CandidateSpec& spec,
             const std::vector<Eigen::VectorXd>& prefixes,
             const std::vector<std::vector<double>>& starts, CandidateWork& w);
// The same from explicit starting points x0 (full parameter vectors).
void FitSpecFrom(const FitContext& ctx, const CandidateSpec& spec, const std::vector<Eigen::VectorXd>& points,
                 CandidateWork& w);

// Fits one effect (not none, not parameter_mismatch), its variants, from its starts.
void FitEffect(const FitContext& ctx, EffectKind kind, CandidateWork& w);

// Linear-in-parameters starts of `kind` given a base prediction: the restoring-force idea —
// what the base model leaves, e = y − ŷ_base, regressed on the base plant driven by the effect's
// basis (y³ for a cubic spring, sign(dŷ/dt) for friction; ŷ², ŷ³ for a sensor map).
std::vector<std::vector<double>> LinearStarts(const FitContext& ctx, EffectKind kind,
                                              const Candidate& base, const Eigen::VectorXd& x);

// ranking.cc: the likelihood-ratio test, validation MSE/NRMSE/BIC and signature of one fitted
// candidate; then eligibility, ordering and BIC weights over all of them (best first).
void ScoreCandidate(const FitContext& ctx, CandidateWork& w);
// A single candidate's validation gain over its reference (ValidationGainZ): parameter_mismatch
// over G0 as given, an effect over the refit, less the free gain of its extra nuisance columns.
// Needs w.fit's validation_mse and nuisance_validation (ScoreCandidate sets them).
double GainOverReferenceZ(const FitContext& ctx, const CandidateWork& w, bool automatic_lag);
// Fills w.fit.nuisance_estimation / nuisance_validation (Candidate::NuisanceColumns of w's fit).
void CountNuisance(const FitContext& ctx, CandidateWork& w);
// A lag or delay fitted to (almost) nothing, under kIdentityShareOfTs of the sample time, is no
// effect: its better fit over the refit is the plant's, from another start (`--seed 84
// --integrating --noise-pole 0.9`, case 0, `none`: a lag of T = 2.8e-14 s at signature 0.29
// was named). Such a single candidate is masked, with a note.
constexpr double kIdentityShareOfTs = 0.01;
void MaskLinearEffectsAtTheirIdentity(const FitContext& ctx, std::vector<CandidateWork>& work);
// ResidualFollowsInput on what candidate `w` leaves, with the input seen through its output
// maps (a clip, a sensor map): u_k times the maps' slope at the plant's output
// (Candidate::Simulate without the maps). Behind a map m a missing linear effect ΔG leaves m'(y)·(ΔG u) to first
// order — linear in m'(y)·u, not in u (behind |y| its sign flips with the plant's output). False
// without output maps, and under multiple shooting (the plant's output from rest is not the
// segments' there).
bool ResidualFollowsInputThroughMaps(const FitContext& ctx, const CandidateWork& w, const Eigen::VectorXd& residual,
                                     std::string* note);

// Two fits `a` (ranked ahead on validation) and `b` on both kinds of record, by the
// Diebold–Mariano z with the automatic Newey–West lag (ValidationGainZ): `z_est`, b's gain over a
// on the estimation records less the free gain of b's extra parameters and nuisance columns;
// `z_val`, a's gain over b on validation less a's extra nuisance columns. `estimation_decides`
// when z_est passes the one-sided threshold at `significance` and z_val does not: the
// validation records cannot tell the two apart, the estimation records can, for b (ranking.cc).
struct EstimationAgainstValidation {
  double z_est = 0, z_val = 0, threshold = 0;
  bool estimation_decides = false;
};
EstimationAgainstValidation CompareOnBothRecords(const FitContext& ctx, const CandidateWork& a, const CandidateWork& b);
// The validation BIC ranks the candidates; where the validation records cannot tell the best two
// eligible single candidates apart and the estimation records can, the estimation records
// decide. The best (not none) is masked, with a note, when the runner-up (not none) fits the
// estimation records within the noise floor (`floor_mse`: the independent floor's variance with
// its sample tolerance on those records; 0 turns the rule off) and significantly better than
// the best (ValidationGainZ on the estimation residuals with the automatic Newey–West lag, less
// the free gain of its extra parameters and nuisance columns), and the best's own validation
// gain over the runner-up is not significant. `gap bench --cases 26
// --seed 7406 --integrating --offsets`, case 23: an output clip under a binary input, which
// the validation record barely reaches, at the noise on both records (estimation MSE 0.00297
// for a noise variance of 0.00303), lost by 0.7 % of validation MSE to an actuator lag of
// T = 7.2 s that left 3.3 times the noise on the estimation record (ranking.cc).
void MaskWhatTheEstimationRecordsReject(const FitContext& ctx, std::vector<CandidateWork>& work, double floor_mse);
// The rule an effect passes, as a single candidate or as the second of a pair: significant on the
// estimation records, and on validation its change matches the gap (signature ≥ min_signature)
// or it gains significantly.
bool PassesEffectRule(const GapOptions& options, bool significant, double signature, bool gain_significant);
// An effect (not none, not parameter_mismatch) may be the verdict: PassesEffectRule, not masked.
bool EffectEligible(const GapOptions& options, const CandidateWork& w);
// Any single candidate may rank as the verdict: none always, parameter_mismatch when it beats G0
// significantly and is not masked, an effect when EffectEligible.
bool CandidateEligible(const GapOptions& options, const CandidateWork& w);
// Sorts `work` best first (eligible, then validation BIC) and returns the ranking.
std::vector<CandidateFit> RankCandidates(std::vector<CandidateWork>& work, const GapOptions& options);
// Masks a dead zone that is an input limit in disguise (ranking.cc), before RankCandidates;
// `slot`: where the two stand among the candidates' effects (1 for the second of a pair).
void MaskOneSidedDeadZone(const FitContext& ctx, std::vector<CandidateWork>& work, size_t slot = 0);
// Masks a candidate (single or pair) with a resonance fitted with ζ at its bound 1/√2 or within
// two standard errors of it (no peak: a lag in disguise) or above the Nyquist frequency π/ts (no
// sampled record shows it), or with an actuator lag longer than the longest record (an
// integrator over the record, not a lag); ranking.cc.
void MaskImplausibleDynamics(const Scales& scales, std::vector<CandidateWork>& work);
// Where G0's validation residual is above the floor but does not follow the input (an output
// disturbance or coloured noise, gap_report.cc), masks every single candidate — parameter_mismatch
// over G0 as given, an effect over the refit — that matches little of the gap (signature under
// min_signature) and whose validation gain is not significant with the automatic Newey–West lag
// (ValidationGainZ), i.e. once the residual's correlation is counted;
// the likelihood ratio, the validation BIC and the fixed-lag gain count the samples as
// independent (ranking.cc).
void MaskGainsWithinColouredNoise(const FitContext& ctx, std::vector<CandidateWork>& work);

// The criterion that picks one of an effect's variants (FitEffect, the pair search): the
// validation BIC where there are several, the estimation BIC otherwise.
double VariantCriterion(const FitContext& ctx, const CandidateWork& trial, size_t variants);

// effect_pairs.cc: forward selection of a second effect after `first` (an eligible single
// effect), each other effect added to it and refitted together; a pair is kept when it passes
// the significance, signature and validation-BIC rules against `first` and beats `top_bic` (the
// best single candidate's validation BIC) by the ambiguity margin; the best kept pair is
// returned, with a note listing every pair tried.
struct PairSearch {
  bool kept = false;
  CandidateWork pair;  // when kept: effects = {first's, the second}
  std::string note, lean_note;
};
// Backward check after the forward selection: each effect of the kept pair alone (not
// quantisation, which is placed from the lattice), refitted from the pair's fit (θ, du and its
// own φ), scored like a single candidate. When an eligible one simulates the validation records
// within the ambiguity margin of the pair (validation BIC), the other effect adds nothing the
// data show — the pair search had found a better basin for it, not a second effect — and
// `single` holds it (returns true). `note` says what was compared.
// The main effect of the pair is the one that does better alone (the other costs less when
// removed). When the pair was reached from its lesser effect, the lesser one must pass the
// rules of a second effect (significant LR, signature, validation BIC below by the ambiguity
// margin) against the main one alone as refitted from the pair, or as `singles` (the ranking's
// single fits) has it where that fits the estimation records better; if it does not, the pair
// is dropped for the main effect alone (a route through the lesser effect must not let it past
// the rules). Otherwise `main_second` is set: report the pair with the main effect first.
// A pair reached from its other effect with the quantiser second: that effect must pass as a
// second after the quantiser's single fit in `singles` (none: the pair stands).
bool PruneToSingle(const FitContext& ctx, const CandidateWork& pair, CandidateWork& single, std::string& note,
                   bool* main_second, const std::vector<CandidateWork>& singles);
// Grid starts of the piecewise effects (limits, dead zone, backlash, friction), whose cost has
// no gradient where no sample reaches the break: a coarse grid over the tails of u or y (both
// limits, or one), or over widths; physical units. Empty for the other effects.
std::vector<std::vector<double>> GridStarts(EffectKind kind, const Scales& s);
// Of every prefix times every start of the last block of `spec`, the `keep` starting points
// with the lowest estimation MSE (one simulation each, no fit), no two with the same MSE.
std::vector<Eigen::VectorXd> BestStartPoints(const FitContext& ctx, const CandidateSpec& spec,
                                             const std::vector<Eigen::VectorXd>& prefixes,
                                             const std::vector<std::vector<double>>& starts, size_t keep);

PairSearch SearchSecondEffect(const FitContext& ctx, const CandidateWork& first, double top_bic,
                              const std::vector<EffectKind>& kinds);

// linear_order.cc: a linear model of order n0 + 2 (passing the LR and signature tests against
// the refit) against the best single candidate `top` (wins) and against the linear candidates of
// the ranking (beats_linear).
struct LinearOrderCheck {
  bool wins = false, beats_linear = false;
  double bic = 0;               // its validation BIC
  double linear_delta_bic = 0;  // its validation BIC less the best linear candidate's
  TransferFunction plant;
  int order = 0;
  double nrmse = 0;             // its validation NRMSE
  long nuisance_validation = 0; // nuisance columns it fits on the validation records
  Eigen::VectorXd y_val;        // its simulation of the validation records
};
LinearOrderCheck CheckLinearOrder(const FitContext& ctx, const CandidateFit& top, GapReport& report);
// How AdoptHigherOrder decides: kAdopt — the part beat every single candidate and nothing came
// after it; kAgainstVerdict — it beat only the linear explanations, so with what the diagnosis
// finds on it, it must beat the verdict so far (`top`, or the pair kept after it);
// kAgainstPair — it beat every single candidate, but a pair of static effects on G0 came after:
// it must beat that pair, with what the diagnosis finds on it or alone.
enum class HigherOrderMode { kAdopt, kAgainstVerdict, kAgainstPair };
// The diagnosis again on check.plant; the verdict becomes unmodelled_dynamics with the static
// effect(s) found there (returns true) when `mode` allows it (above). `verdict_follows_input`:
// the input–residual test on what the verdict so far leaves on validation, where the caller has
// run it already (else it is run here when needed).
bool AdoptHigherOrder(const FitContext& ctx, const LinearOrderCheck& check, const CandidateFit& top,
                      GapReport& report, HigherOrderMode mode, std::optional<bool> verdict_follows_input = {});

// The verdict takes the candidate's effects, their 1σ, plant, validation NRMSE and nuisance.
void AdoptCandidate(const CandidateFit& c, GapVerdict& v);

// body(i) for i < count on up to `threads` threads (0: hardware); an exception is rethrown as
// std::invalid_argument naming what(i). With `cost` the items start in order of decreasing
// cost(i) (longest first: the costliest fit does not start last and hold the others' threads
// idle); the results never depend on the order.
void ParallelFor(size_t count, int threads, const std::function<void(size_t)>& body,
                 const std::function<std::string(size_t)>& what,
                 const std::function<double(size_t)>& cost = nullptr);

// The relative cost of fitting an effect (as one of a candidate's effects), for ParallelFor's
// order: the sensor map fits two variants, each through a Gauss–Newton nuisance fit per segment;
// friction and a cubic spring run sub-steps; a backlash predicts each record from several play
// states; the output clip's nuisance goes through the clip.
double FitCost(EffectKind kind);

}  // namespace idrig::gap_detail
