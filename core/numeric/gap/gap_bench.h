#pragma once
// Synthetic blind cases for the gap diagnosis: a random plant G0 (the "sim model"), one or two
// withheld effects with random parameters added to it (the "real rig"), optionally random
// actuator and sensor offsets (an operating point), output noise at a chosen SNR, and
// estimation and validation records from independent excitation realisations of one of three
// kinds (multisine at three amplitude levels with steps; PRBS; random binary), or on request
// band-limited Gaussian noise, a random staircase or a logarithmic chirp; optionally
// integrating plants only. The generator
// simulates the rig more finely than the diagnosis does (feedback effects with 16 sub-steps),
// and the diagnosis never sees the case's truth. The bench's plan (which case has which
// effects) and its scores are here too, so that every front end scores alike.
#include <cstdint>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/numeric/gap/effects.h"
#include "core/numeric/gap/gap_diagnosis.h"

namespace idrig {

struct GapCaseOptions {
  double snr_db = 30.0;        // output SNR (signal RMS / noise RMS in dB)
  int samples = 4000;          // per record
  double sample_time = 0.01;   // [s]
  // "levels", "prbs", "rbs"; or, only when asked for, "noise" (band-limited Gaussian), "steps"
  // (a random staircase) or "chirp" (one logarithmic sweep); empty: one of the first three
  // drawn at random per case.
  std::string excitation;
  // Random operating point: an actuator offset (added to the command before every input-side
  // effect) of up to ±30 % of the command's peak, and a sensor offset (added to the reading)
  // of 10–100 % of the output's range, either sign; the records start with the rig settled at
  // the operating point (a warm-up at zero command is simulated and dropped).
  bool offsets = false;
  // Integrating plants only (K/(s(Ts + 1)): position from force, a level from a flow). The
  // records then drift with any actuator offset, as on such a rig run open loop.
  bool integrating = false;
  // Damping ratio ζ of the second- and third-order plants' mode, drawn uniformly in
  // [zeta_min, zeta_max] (ζ < 0.1: lightly damped, the records ring; the draw consumes the same
  // random numbers whatever the range, so a seed's other draws do not move).
  double zeta_min = 0.15, zeta_max = 0.8;
  // Output noise coloured by a first-order pole a in [0, 1) (0: white), of the same variance.
  double noise_pole = 0;
  // Plant family: empty (first order, mass–spring–damper, or the two in series), "zeros" (the
  // third-order series plant with a zero: a lead, or non-minimum phase — a drum level, a
  // flexible arm's tip), or "two-mass" (force on one mass, position of the other through a
  // spring: a fourth-order plant with a resonance, with or without an antiresonance).
  std::string plants;
  // Sensor or acquisition glitches per record (a run of 1–3 samples each: a spike 2–20 output
  // spans off, a dropout to zero, or a reading stuck one span beyond the range), added last.
  int glitches = 0;
  // A slow sensor drift: a ramp from 0 to `drift` noise sigmas over the estimation record and to
  // −`drift` over the validation record, in the analogue reading (before the ADC, after the noise).
  double drift = 0;
  // Process noise: the share F in [0, 1) of the noise variance that enters at the plant's input
  // as a load disturbance (white, held over each sample, after the input maps and before a
  // friction or spring; the plant colours it, an integrator makes it a random walk — and the
  // linear effects folded into the plant, a lag or a delay, act on it too), scaled so that its
  // part of the output has variance F·σ² on the rig's linear part over a record; the rest,
  // (1 − F)·σ², is output noise as before. 0: output noise only (the same numbers as before).
  double process_noise = 0;
};

// Adds `count` glitches (as GapCaseOptions::glitches) to y.
void AddGlitches(Eigen::VectorXd& y, int count, std::mt19937_64& rng);

struct GapCase {
  EffectKind truth = EffectKind::kNone;   // the first (or only) withheld effect
  std::vector<EffectKind> truths;         // every withheld effect: one, or a co-occurring pair
  Effect effect;               // the first withheld effect (parameter_mismatch: none; see real)
  std::vector<Effect> effects; // every withheld effect, in the order of `truths`
  TransferFunction sim;        // what the user's simulation says
  TransferFunction real;       // the rig's linear part
  std::string excitation;      // "levels", "prbs" or "rbs"
  double noise_sigma = 0;
  double input_offset = 0;     // actuator offset [units of u]
  double output_offset = 0;    // sensor offset [units of y], added after the ADC
  GapRecord estimation, validation;
  // How far each withheld effect (in the order of `truths`) shows above the noise on the
  // record that shows it more: ‖Δy⊥‖²/σ², Δy the record's output less the same record drawn again
  // without this effect (the other kept; parameter_mismatch: with G0's linear part instead of
  // the rig's) with the same load, noise and drift (so Δy is noise-free but for a quantiser's
  // rounding, and an effect acts on the walk a load drives), ⊥ after the least-squares fit of
  // an offset and a gain of the output without it (what a refitted G0 and the output offset
  // absorb at once; for parameter_mismatch the offset only). The noncentrality of a test that
  // knew the effect and everything else: an upper bound on what any diagnosis can see (a refit
  // of the plant's dynamics or a free state per shooting segment absorbs more). `none`: +inf.
  std::vector<double> visibility;
  // The same with what the diagnosis's own fit absorbs also taken out (GapCase::visibility is an
  // upper bound that it does not reach on an integrating rig): beside the offset and the gain,
  // the refit of the rig's linear part (the output's sensitivities to its coefficients) but for
  // parameter_mismatch, of the other withheld effect's parameters (a quantiser's aside), an
  // actuator offset, and where G0 is fitted by multiple shooting (ShootingSegment) an offset and
  // a free state per segment. Beside a quantiser, Δy is taken without it and over σ² + q²/12 (the
  // noise dithers the quantiser: the rounding flips of one noise draw are no evidence a test can
  // place). A linearised estimate of the noncentrality of the diagnosis's own likelihood-ratio
  // test, still an upper bound (the effect's own parameters are the truth's).
  std::vector<double> visibility_refit;
};

// The visibility (GapCase::visibility) under which a withheld effect is within the noise: the
// 1 % level of χ²(1) Bonferroni-corrected over the 11 effects (none and parameter_mismatch
// aside), the likelihood-ratio threshold a one-parameter effect must pass in the diagnosis. Below it even a test that knew the effect
// would miss it about half the time or more.
double BenchVisibilityThreshold();

// Throws std::invalid_argument naming a damping range that is not 0 < LO <= HI or a noise
// pole outside [0, 1) (MakeGapCase checks them; a front end may check them up front).
void ValidateGapCaseOptions(const GapCaseOptions& options);
GapCase MakeGapCase(EffectKind truth, std::mt19937_64& rng, const GapCaseOptions& options = {});
// One or two withheld effects (two: each drawn as for a single case, acting together on the rig;
// parameter_mismatch may not be one of a pair). Throws std::invalid_argument otherwise.
GapCase MakeGapCase(const std::vector<EffectKind>& truths, std::mt19937_64& rng,
                    const GapCaseOptions& options = {});

// Pairs of effects that occur together on rigs (the bench's two-effect cases, in turn):
// friction + actuator saturation (servo axes), dead zone + cubic spring (valve overlap on a
// stiffening suspension), backlash + quantisation (gear train read by an encoder), time delay +
// sensor nonlinearity (transport delay read by a nonlinear probe), actuator lag + saturation
// (a limited, slow amplifier), friction + backlash (geared drives), dead zone + actuator lag
// (a hydraulic valve with overlap and spool dynamics).
const std::vector<std::pair<EffectKind, EffectKind>>& CoOccurringEffectPairs();

// The rig's output for input u: the linear part with the effects, output noise, and for
// quantisation the noise before the rounding (a noisy signal digitised by an ADC). Several
// effects act in stage order: actuator offset, input maps (saturation, dead zone, backlash),
// the linear effects folded into the plant, one feedback effect (friction or cubic stiffness),
// output maps (saturation, sensor), noise, ADC (quantisation), sensor offset. With noise_pole
// a ≠ 0 the noise is coloured, first-order autoregressive e(k) = a e(k−1) + √(1 − a²) σ w(k)
// (the same variance σ², the same random numbers as white noise). `sensor_drift` (per sample;
// empty: none) is added to the analogue reading with the noise, before the ADC. `load` (per
// sample; empty: none) is added to the plant's input after the input maps (a load disturbance).
Eigen::VectorXd SimulateRig(const TransferFunction& plant, const Effect& effect,
                            const Eigen::VectorXd& u, double sample_time, double noise_sigma,
                            std::mt19937_64& rng);
Eigen::VectorXd SimulateRig(const TransferFunction& plant, const std::vector<Effect>& effects,
                            const Eigen::VectorXd& u, double sample_time, double noise_sigma,
                            std::mt19937_64& rng, double input_offset = 0,
                            double output_offset = 0, double noise_pole = 0,
                            const Eigen::VectorXd& sensor_drift = Eigen::VectorXd(),
                            const Eigen::VectorXd& load = Eigen::VectorXd());

// Every unordered pair of the effects (none and parameter_mismatch aside) that the rig can
// simulate together — all but friction with a cubic spring (one feedback effect at most): 54
// pairs, for a bench that does not assume which effects meet on a rig.
const std::vector<std::pair<EffectKind, EffectKind>>& AnyEffectPairs();

// The bench's plan: case `index` has a pair (CoOccurringEffectPairs in turn, or AnyEffectPairs
// with `any_pairs`) for a share `combo_share` of the cases, spread evenly, and otherwise a
// single effect (the vocabulary in turn). combo_share = 0 gives the vocabulary in turn
// (index mod 13).
std::vector<EffectKind> BenchCaseTruth(int index, double combo_share, bool any_pairs = false);
// The excitations a case may ask for (GapCaseOptions::excitation): the three drawn by default
// first, then those drawn only on request.
const std::vector<std::string>& BenchExcitations();
// The seed of case `index` of a bench run with seed `seed` (each case its own generator, so a
// result does not depend on the thread schedule, and any case can be drawn again alone).
inline uint64_t BenchCaseSeed(uint64_t seed, int index) { return seed * 1000003ULL + static_cast<uint64_t>(index); }

// What a diagnosis said about one case, and its scores.
struct GapBenchOutcome {
  std::vector<EffectKind> truth;        // one or two
  std::string verdict;                  // verdict.effect (may be "ambiguous")
  std::vector<std::string> effects;     // verdict.effects' names (one or two)
  std::string excitation;
  std::vector<double> visibility;       // GapCase::visibility (empty: not known, counted as visible)
  std::vector<double> visibility_refit{};  // GapCase::visibility_refit (empty: not known, counted as visible)
  double shrink = 0, confidence = 0, seconds = 0;
};

struct GapBenchScore {
  int cases = 0;
  int single_cases = 0, single_correct = 0;  // top-1: verdict.effect == the withheld effect
  int single_extra = 0;        // right top-1 but a second (spurious) effect named as well
  int none_cases = 0, false_alarms = 0;      // none withheld, something else named
  int combo_cases = 0, combo_both = 0;       // both withheld effects in verdict.effects
  int combo_either = 0;                      // verdict.effect is one of the two
  double top1_accuracy = 0;    // single_correct / single_cases
  double false_alarm_rate = 0; // false_alarms / none_cases
  double combo_both_rate = 0, combo_top1_rate = 0;
  double median_shrink_correct = 0;  // over single cases with the right verdict (not none); NaN: none such
  // The same scores without the cases no data can decide: a two-valued input (prbs, rbs) with
  // an input saturation, dead zone or backlash withheld — any static map of a two-valued signal
  // is affine, i.e. a gain and an offset, which the refitted G0 and the output offset absorb
  // (the honest verdict there is `ambiguous`).
  int decidable_single_cases = 0, decidable_single_correct = 0;
  int decidable_combo_cases = 0, decidable_combo_both = 0;
  double top1_decidable = 0, combo_both_decidable = 0;
  // The decidable cases whose withheld effects each show above the noise (visibility at least
  // BenchVisibilityThreshold()): an effect below it is missed by any method, a `none` there is
  // the honest verdict. `none` cases always count.
  int detectable_single_cases = 0, detectable_single_correct = 0;
  int detectable_combo_cases = 0, detectable_combo_both = 0;
  double top1_detectable = 0, combo_both_detectable = 0;
  // The detectable cases whose withheld effects each also show above the noise after the refit
  // (visibility_refit at least BenchVisibilityThreshold()).
  int refit_single_cases = 0, refit_single_correct = 0;
  int refit_combo_cases = 0, refit_combo_both = 0;
  double top1_refit = 0, combo_both_refit = 0;
  double mean_seconds = 0;
  // rows: the truth ("a" or "a+b"); columns: the named effects ("x" or "x+y") with counts.
  std::map<std::string, std::map<std::string, int>> confusion;
  std::map<std::string, std::pair<int, int>> by_excitation;  // single cases: right, total
  std::map<std::string, std::pair<int, int>> by_pair;        // pair cases: both named, total
};

GapBenchScore ScoreGapBench(const std::vector<GapBenchOutcome>& outcomes);

}  // namespace idrig
