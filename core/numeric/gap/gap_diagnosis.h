#pragma once
// Sim-to-real gap diagnosis: where a linear simulation model G0 departs from measured records,
// which unmodelled effect of the library (effects.h) causes it, and how far the gap shrinks on
// held-out validation records once that effect is added.
//
// Which (attribution): every effect is fitted by output-error simulation on the estimation
// records, with G0's coefficients free to move inside G0's structure (log multipliers on the
// non-zero coefficients of num and the monic den), by Levenberg–Marquardt (Eigen's MINPACK
// port) from a few starting points per effect. Candidates are ranked on the validation records
// by BIC, J = N_val·ln V_val + k·ln N_est (k fitted parameters), turned into weights
// w ∝ exp(−J/2). An effect may win only when (a) its likelihood ratio against the refitted G0
// on the estimation data, N ln(V_refit/V_effect), exceeds the χ²_k quantile at the
// Bonferroni-corrected level, and (b) the change it makes to the simulation correlates with the
// measured gap (signature check). `none` wins when the refitted G0 does not significantly beat
// G0 itself. `ambiguous` when the top two BIC values differ by less than `ambiguity_bic`.
//
// Where (localisation, gap_where.cc): gap against the noise floor, model-error spectrum by band
// with input–residual coherence, residual by input amplitude, by state (velocity sign, near
// reversals, output level) and by time.
//
// Sizes: records are SISO, u and y of equal length, one sample time for all records.
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "core/numeric/gap/effects.h"
#include "core/numeric/gap/gap_noise.h"
#include "core/numeric/io_record.h"
#include "core/numeric/model/lti_model.h"

namespace idrig {

struct GapRecord {
  Eigen::VectorXd u, y;
  double sample_time = 0.0;
  // Samples before `score_from` drive the simulation (warm-up) but are not scored: used when
  // a validation record is the second half of a record whose first half is for estimation.
  int score_from = 0;
  // Samples where the sensor's level changes (a sensor step, found by DiagnoseGap): each adds an
  // output level of its own from there on, fitted as a nuisance parameter beside the offset.
  std::vector<long> sensor_steps;
};

struct GapOptions {
  double significance = 0.01;    // family-wise level of the likelihood-ratio tests
  double ambiguity_bic = 2.0;    // top two closer than this in BIC → "ambiguous"
  // The effect's change must correlate with the measured gap (signature ≥ min_signature: it
  // explains a visible share of what the refit leaves), or, where the gap is small against the
  // noise and no effect can explain such a share, its validation gain must be significant
  // (validation_gain_z above the normal quantile at `significance`: a confirmation, on records
  // it was not fitted to, of an LR test already passed at the Bonferroni-corrected level).
  double min_signature = 0.2;
  int substeps = 4;              // sub-steps for friction and cubic stiffness
  int evaluations_per_start = 10;   // LM budget per start, ×(parameters + 1)
  int evaluations_polish = 80;      // LM budget for the best start, ×(parameters + 1)
  std::vector<EffectKind> candidates;  // empty: every effect of the library
  int threads = 0;               // candidates fitted in parallel; 0: one per hardware thread
  bool second_effect = true;     // forward selection of a second effect after the first
  // Under multiple shooting, a second effect searched from the first even where the first reaches
  // the noise floor (each segment's free state takes up part of what a second effect does); a
  // pair found so is kept only when the diagnosis on segments twice as long names it too.
  bool second_effect_at_floor = true;
  bool check_linear_order = true;  // test a higher-order linear part (unmodelled_dynamics)
  // The fit scheme, when it must not be chosen from G0: samples per shooting segment (0: single
  // shooting) and whether G0 integrates. The diagnosis on a higher-order linear part keeps the
  // scheme of the diagnosis that found it, so that their NRMSEs and BICs compare.
  long fixed_segment = -1;       // -1: chosen from G0 (ChooseFitScheme)
  // Output glitches (core/numeric/signal/outliers.h) bridged before fitting; false: the records
  // are fitted as measured.
  bool bridge_glitches = true;
  bool fixed_integrating = false;
  // A slow sensor drift (a ramp per record beside its offset) among the nuisance parameters, where
  // G0 is fitted by single shooting and does not integrate (ChooseFitScheme).
  bool fit_drift = true;
  // Sensor steps (core/numeric/signal/level_shifts.h) found against G0 and against the diagnosed
  // model, each an output level of its own from there on (GapRecord::sensor_steps); false: none.
  bool find_sensor_steps = true;
};

struct BandGap {
  double f_lo_hz = 0, f_hi_hz = 0;
  double gap_power = 0;          // residual power in the band (per Hz, mean)
  double coherence = 0;          // mean |γ_ue|² over the band
  double coherence_threshold = 0;  // 99.9 % level for no correlation, Beta(1, L−1)
  double relative_error = 0;     // median |Ê(jω)/G0(jω)|, Ê = S_ue/S_uu the model-error FRF
  bool significant = false;
  double nrmse_before = 0, nrmse_after = 0;  // of the band-passed validation output
};

struct BinnedGap {
  std::string label;             // e.g. "|u| in [0.1, 0.4)"
  int samples = 0;
  double mean = 0, rms = 0;      // of the residual y − ŷ0 in the bin
  double relative_rms = 0;       // rms / RMS(ŷ0) in the bin: the gap relative to the signal
};

struct GapFactor {
  std::string name;              // "amplitude", "velocity_sign", "reversal", "output_level", "time"
  std::vector<BinnedGap> bins;
  double eta_squared = 0;        // share of residual variance explained by the bin means
  double rms_ratio = 0;          // largest bin RMS / smallest bin RMS
  double relative_ratio = 0;     // largest bin relative_rms / smallest
};

struct GapWhere {
  double nrmse_before = 0;       // G0 on all records, simulation NRMSE
  double noise_nrmse = 0;        // noise floor as NRMSE (noise_floor.sigma / spread of y_val)
  NoiseFloor noise_floor;        // how the floor was estimated (without the candidates)
  DetectionLines detection_lines;  // even/odd lines of a periodic odd multisine (if any)
  OutputLattice lattice;         // the lattice the output samples sit on (quantisation)
  double gap_to_noise = 0;       // RMS(y − ŷ0) / σ̂
  bool gap_significant = false;
  bool residual_white = false, residual_independent = false;  // tests on y − ŷ0
  std::vector<BandGap> bands;
  std::vector<GapFactor> factors;
  std::string summary;
};

struct CandidateFit {
  Effect effect;                 // fitted effect parameters
  TransferFunction plant;        // G0 after its coefficients were allowed to move
  int parameters = 0;            // fitted parameters (plant + effect)
  // Output offsets and free initial states fitted by projection (per record and segment), on
  // the estimation and on the validation records; counted in the LR's degrees of freedom
  // (beyond the refit's) and in the validation BIC (see ValidationBic).
  long nuisance_estimation = 0, nuisance_validation = 0;
  double estimation_mse = 0;
  double validation_mse = 0;
  double nrmse_after = 0;        // validation simulation NRMSE
  double bic = 0;                // validation BIC
  double score = 0;              // BIC weight (sums to 1 over the ranking)
  double likelihood_ratio = 0;   // against the refitted G0 (against G0 for parameter_mismatch)
  double lr_threshold = 0;
  bool significant = false;
  double signature = 0;          // corr(ŷ_c − ŷ_0, y − ŷ_0) on validation data
  // The validation gain as a z statistic: mean(e_ref² − e_c²)/its standard error (Newey–West),
  // e_ref the refitted G0's validation residual. Stands in for the signature share when the gap
  // is small against the noise (see GapOptions::min_signature).
  double validation_gain_z = 0;
  bool eligible = false;         // may be the verdict
  std::vector<double> param_std; // 1σ of effect parameters (linearised), NaN when unknown
  std::vector<Effect> effects;   // every effect of the candidate (one, or two after selection)
  std::vector<std::vector<double>> effects_std;  // their 1σ
  double input_offset = 0, input_offset_std = 0;  // fitted actuator offset du (u units)
  bool input_offset_fitted = false;
  std::vector<double> output_offsets;             // per estimation record (first segment)
  std::vector<double> output_drifts;              // the same, [y units/s], when a drift is fitted
  int evaluations = 0;
  std::string note;
};

// Nuisance parameters every candidate carries (never named as an effect): an actuator offset
// du (u → u + du; fitted where it is not an output offset in disguise), an output offset per
// record (per segment) and a free initial state per record (per segment), the latter two by
// variable projection.
struct GapNuisance {
  double input_offset = 0, input_offset_std = 0;
  bool input_offset_fitted = false;
  std::vector<double> output_offset;  // per estimation record
  // A sensor drift per estimation record [y units/s] about its middle (empty: not fitted — an
  // integrating or lightly damped G0, where an actuator offset or the segments' own offsets take
  // a ramp, or GapOptions::fit_drift off).
  std::vector<double> output_drift;
  std::string initial_state;          // how the initial state was treated
};

struct GapVerdict {
  // An effect name, "ambiguous", or "unmodelled_dynamics" (the linear part lacks dynamics: a
  // higher-order linear model beats every single effect — or every linear one, and with the
  // static effect a second diagnosis on it finds, every single effect; `effects` then holds what
  // that second diagnosis finds, if any), or "unexplained" (`none` would have topped the
  // ranking, but G0's validation residual is above the noise floor and follows the input: a gap
  // that no effect and no higher-order linear part explains; `effects` empty).
  std::string effect;
  std::vector<std::string> tied; // the two candidates when ambiguous
  double confidence = 0;         // BIC weight of the verdict among all candidates
  double nrmse_before = 0, nrmse_after = 0;  // validation records
  double shrink = 0;             // (before − after)/(before − noise floor): ≤ 1 unless below_noise_floor
  double noise_nrmse = 0;        // the independent noise floor as an NRMSE (where.noise_floor)
  double remaining_gap_to_noise = 0;  // nrmse_after − noise_nrmse: what is left beyond the noise
  bool below_noise_floor = false;     // nrmse_after < noise_nrmse (shrink may then exceed 1)
  // The effect explains a gap that only the estimation records show; G0 fits the validation
  // records within the noise, so they do not confirm it (a note gives the figures).
  bool estimation_only = false;
  Effect params;
  std::vector<double> param_std;
  TransferFunction plant;        // the adjusted linear part
  long nuisance_validation = 0;  // nuisance columns the verdict's model fits on validation
  std::vector<Effect> effects;   // one or two effects (the first is `params`); empty for none
  std::vector<std::vector<double>> effects_std;
  GapNuisance nuisance;
  int linear_order = 0;          // unmodelled_dynamics: the order of the linear part that fits
  double linear_nrmse_after = 0; // unmodelled_dynamics: validation NRMSE with that linear part
  std::string fit_scheme;        // "single_shooting" or "multiple_shooting"
  long shooting_segment = 0;     // samples per segment when multiple shooting
  bool integrating = false;      // G0 integrates: every candidate fits an actuator offset
  // What G0 leaves on the validation records: "within_noise" (within the noise floor),
  // "follows_input" (above it and explained by past inputs: the prewhitened test),
  // "does_not_follow_input" (above it, not explained: a disturbance or coloured noise); empty
  // when the floor could not be estimated without the candidates.
  std::string g0_gap;
  std::string explanation;
};

// An output sample bridged as a glitch before fitting (core/numeric/signal/outliers.h).
struct GapGlitch {
  std::string records;   // "estimation" or "validation"
  int record = 0;        // index among them
  long sample = 0;
  double value = 0, replaced_by = 0;
};

// A sensor step found in a record (core/numeric/signal/level_shifts.h), marked in it.
struct GapSensorStep {
  std::string records;   // "estimation" or "validation"
  int record = 0;        // index among them (as given)
  long sample = 0;       // the first sample at the new level
  double size = 0;       // the new level less the old
};

struct GapReport {
  GapVerdict verdict;
  std::vector<GapGlitch> glitches;    // output glitches bridged before fitting
  std::vector<GapSensorStep> sensor_steps;  // marked before fitting
  std::vector<CandidateFit> ranking;  // best first
  GapWhere where;
  std::vector<std::string> notes;     // what was assumed (e.g. "split in time at 50 %")
  int estimation_samples = 0, validation_samples = 0;
  // The verdict's simulation of the validation records (their scored samples, stacked): the
  // fitted candidate, pair or higher-order part the verdict names (a quantiser named from the
  // lattice alone, with nothing fitted, leaves it at what was fitted before).
  Eigen::VectorXd validation_prediction;
};

// Throws std::invalid_argument for: no records, NaN, mismatched lengths, a constant input,
// differing sample times, records too short for the model's order, a discrete sim model whose
// sample time differs from the data's.
GapReport DiagnoseGap(const TransferFunction& sim_model, const std::vector<GapRecord>& estimation,
                      const std::vector<GapRecord>& validation, const GapOptions& options = {});

// Splits one record in time: the first half for estimation; the whole record for validation
// with scoring from the midpoint (the first half only warms the simulation up).
void SplitRecord(const GapRecord& record, std::vector<GapRecord>& estimation,
                 std::vector<GapRecord>& validation);

// Localisation only (also used by DiagnoseGap). `noise_sigma` ≤ 0: unknown, the residual's RMS
// is used (so the gap is never called significant).
GapWhere LocateGap(const TransferFunction& sim_model, const std::vector<GapRecord>& records,
                   double noise_sigma);

// Samples per shooting segment of the diagnosis of G0 on records of `samples` at `ts` (0: single
// shooting): multiple shooting when G0's slowest mode decays by less than e^-5 over the record
// (an integrator, a lightly damped mode), segments of max(N/8, 100·(n+1)) samples.
long ShootingSegment(const TransferFunction& g0, long samples, double ts);

// The front ends' conversions: a SISO sim model (tf, or ss with one input and one output) as a
// transfer function, and a SISO record (t,u,y). Throw std::invalid_argument for MIMO.
TransferFunction SimModelTransferFunction(const LtiModel& model);
GapRecord ToGapRecord(const IoRecord& record);

}  // namespace idrig
