// The gap diagnosis on rigs as they are: actuator and sensor offsets (nuisance parameters, never
// an effect), an integrating plant (multiple shooting), two effects at once, and records that
// are bad in the ways real records are (mostly clipped, drifting, at two operating points).
// Truths are by construction (the rig is simulated with the effect library, 16 sub-steps).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/numeric/gap/gap_bench.h"
#include "core/numeric/gap/gap_diagnosis.h"

namespace idrig {
namespace {

GapCase LevelsCase(EffectKind truth, uint64_t seed, int samples = 2500) {
  for (uint64_t s = seed;; ++s) {
    std::mt19937_64 rng(s);
    GapCaseOptions options;
    options.samples = samples;
    options.excitation = "levels";
    GapCase c = MakeGapCase(truth, rng, options);
    if (c.excitation == "levels") return c;
  }
}

double Rms(const Eigen::VectorXd& v) { return std::sqrt(v.squaredNorm() / v.size()); }

// The recorded input misses the actuator's offset (the plant saw u + du), the recorded output
// carries the sensor's (y + dy).
void AddOffsets(GapCase& c, double du, double dy) {
  for (GapRecord* r : {&c.estimation, &c.validation}) {
    r->u.array() -= du;
    r->y.array() += dy;
  }
}

struct OffsetCase {
  EffectKind truth;
  uint64_t seed;
};

class OffsetTest : public ::testing::TestWithParam<OffsetCase> {};

TEST_P(OffsetTest, OffsetsAreNuisanceNotAnEffect) {
  GapCase c = LevelsCase(GetParam().truth, GetParam().seed);
  const double du = 0.3 * Rms(c.estimation.u), dy = 0.5 * Rms(c.estimation.y);
  AddOffsets(c, du, dy);
  const GapReport report = DiagnoseGap(c.sim, {c.estimation}, {c.validation});
  const GapVerdict& v = report.verdict;
  std::printf("truth %-20s verdict %-20s du %.4f (fitted %.4f, %s) dy %.4f (fitted %.4f) NRMSE %.4f -> %.4f\n",
              EffectName(c.truth), v.effect.c_str(), du, v.nuisance.input_offset,
              v.nuisance.input_offset_fitted ? "fitted" : "not a parameter", dy,
              v.nuisance.output_offset.empty() ? NAN : v.nuisance.output_offset[0], v.nrmse_before,
              v.nrmse_after);
  EXPECT_EQ(v.effect, EffectName(c.truth));
  // One effect withheld, one named: no second effect made of the offsets.
  if (c.truth != EffectKind::kNone) {
    EXPECT_EQ(v.effects.size(), 1u);
  }
  ASSERT_EQ(v.nuisance.output_offset.size(), 1u);
  if (c.truth == EffectKind::kNone) {
    // Offsets only: the nuisance absorbs them (du ≡ dy/G0(0) before a linear stable plant).
    const double dc_gain = c.sim.num(c.sim.num.size() - 1) / c.sim.den(c.sim.den.size() - 1);
    EXPECT_NEAR(v.nuisance.output_offset[0], dy + dc_gain * du, 0.1 * std::abs(dy) + 5 * c.noise_sigma);
  }
  if (c.truth == EffectKind::kDeadZone) {
    // Through the dead zone the actuator offset is identifiable on its own.
    ASSERT_TRUE(v.nuisance.input_offset_fitted);
    EXPECT_NEAR(v.nuisance.input_offset, du, 0.15 * du);
    EXPECT_NEAR(v.params.params[0], c.effect.params[0], 0.1 * c.effect.params[0]);
  }
}

INSTANTIATE_TEST_SUITE_P(Rigs, OffsetTest,
                         ::testing::Values(OffsetCase{EffectKind::kNone, 301},
                                           OffsetCase{EffectKind::kDeadZone, 302},
                                           OffsetCase{EffectKind::kCubicStiffness, 303},
                                           OffsetCase{EffectKind::kOutputSaturation, 304},
                                           OffsetCase{EffectKind::kCoulombFriction, 305}),
                         [](const auto& info) { return std::string(EffectName(info.param.truth)); });

TEST(GapIntegratingTest, FrictionOnAPositionFromForcePlantIsFrictionNotAFlexibleWrongEffect) {
  // Position from force: m ẍ + c ẋ = F − F_c sign(ẋ), x measured; m = 1, c = 0.5.
  TransferFunction plant;
  plant.num = Eigen::VectorXd::Constant(1, 1.0);
  plant.den = Eigen::Vector3d(1.0, 0.5, 0.0);
  GapCase shape = LevelsCase(EffectKind::kNone, 311, 3000);
  const double ts = shape.estimation.sample_time * 2;  // 0.02 s: 60 s per record
  std::mt19937_64 rng(312);
  const double u_rms = Rms(shape.estimation.u);
  const Effect friction{EffectKind::kCoulombFriction, {0.25 * u_rms}};
  GapRecord est, val;
  for (auto [r, u] : {std::pair{&est, &shape.estimation.u}, std::pair{&val, &shape.validation.u}}) {
    r->sample_time = ts;
    r->u = *u;
    const Eigen::VectorXd clean = SimulateRig(plant, friction, r->u, ts, 0.0, rng);
    std::normal_distribution<double> noise(0.0, 0.01 * Rms(clean.array() - clean.mean()));
    r->y = clean;
    for (long k = 0; k < r->y.size(); ++k) r->y(k) += noise(rng);
  }
  const GapReport report = DiagnoseGap(plant, {est}, {val});
  const GapVerdict& v = report.verdict;
  std::printf("integrating plant: verdict %s (F_c %.4f, true %.4f), fit %s segment %ld, NRMSE %.4f -> %.4f\n",
              v.effect.c_str(), v.params.params.empty() ? NAN : v.params.params[0], friction.params[0],
              v.fit_scheme.c_str(), v.shooting_segment, v.nrmse_before, v.nrmse_after);
  EXPECT_EQ(v.fit_scheme, "multiple_shooting");
  EXPECT_EQ(v.effect, "coulomb_friction");
  ASSERT_FALSE(v.params.params.empty());
  EXPECT_NEAR(v.params.params[0], friction.params[0], 0.2 * friction.params[0]);
}

TEST(GapOffsetTest, AOneSidedLimitIsNamedASaturationNotADeadZoneWithALargeOffset) {
  // Only the upper limit is reached (the lower one lies far below the data). Over the data that
  // is one kink, which a dead zone with an actuator offset as large as its flat part fits as
  // well with one parameter fewer; a limit is the name for a response that stops away from
  // zero command (ranking.cc, MaskOneSidedDeadZone).
  GapCase c = LevelsCase(EffectKind::kInputSaturation, 306);
  const double u_max = c.estimation.u.cwiseAbs().maxCoeff();
  const Effect limit{EffectKind::kInputSaturation, {-10 * u_max, 0.45 * u_max}};
  std::mt19937_64 rng(307);
  for (GapRecord* r : {&c.estimation, &c.validation}) {
    r->y = SimulateWithEffect(c.real, limit, r->u, r->sample_time);
    const double sigma = Rms(r->y.array() - r->y.mean()) * std::pow(10.0, -30.0 / 20);
    std::normal_distribution<double> noise(0.0, sigma);
    for (long k = 0; k < r->y.size(); ++k) r->y(k) += noise(rng);
  }
  AddOffsets(c, 0.2 * Rms(c.estimation.u), 0.5 * Rms(c.estimation.y));
  const GapReport report = DiagnoseGap(c.sim, {c.estimation}, {c.validation});
  for (const CandidateFit& f : report.ranking)
    if (f.effect.kind == EffectKind::kDeadZone || f.effect.kind == EffectKind::kInputSaturation)
      std::printf("%s: eligible %d, estimation MSE %.4g, validation MSE %.4g, du %.4f %s\n", EffectName(f.effect.kind),
                  f.eligible, f.estimation_mse, f.validation_mse, f.input_offset, f.note.c_str());
  EXPECT_EQ(report.verdict.effect, "input_saturation");
  ASSERT_FALSE(report.verdict.effects.empty());
  const Effect& named = report.verdict.effects.front();
  ASSERT_EQ(named.kind, EffectKind::kInputSaturation);
  // The limit in command units (u_hi − du: an actuator offset and the limits trade against the
  // output offset) is where the records show it.
  EXPECT_NEAR(named.params[1] - report.verdict.nuisance.input_offset, 0.45 * u_max - 0.2 * Rms(c.estimation.u),
              0.05 * u_max);
}

struct PairCase {
  EffectKind first, second;
  uint64_t seed;
};

class TwoEffectTest : public ::testing::TestWithParam<PairCase> {};

// Effect parameters scaled to the record: limits at 70 % of max|u|, widths at 25 % of RMS(u),
// the cubic term at 30 % of max|u| at max|y|.
Effect Scaled(EffectKind kind, const GapRecord& r, const Eigen::VectorXd& y_lin) {
  const double u_max = r.u.cwiseAbs().maxCoeff(), u_rms = Rms(r.u), y_max = y_lin.cwiseAbs().maxCoeff();
  switch (kind) {
    case EffectKind::kInputSaturation: return {kind, {-0.7 * u_max, 0.7 * u_max}};
    case EffectKind::kDeadZone:
    case EffectKind::kBacklash:
    case EffectKind::kCoulombFriction: return {kind, {0.25 * u_rms}};
    case EffectKind::kCubicStiffness: return {kind, {0.3 * u_max / std::pow(y_max, 3)}};
    case EffectKind::kOutputQuantization: return {kind, {0.05 * y_max}};
    default: return {kind, {}};
  }
}

TEST_P(TwoEffectTest, BothEffectsAreNamed) {
  const PairCase p = GetParam();
  GapCase c = LevelsCase(EffectKind::kCoulombFriction, p.seed);  // a second-order plant
  std::mt19937_64 rng(p.seed + 1);
  const Eigen::VectorXd y_lin = SimulateWithEffect(c.real, Effect{}, c.estimation.u, c.estimation.sample_time);
  const std::vector<Effect> effects = {Scaled(p.first, c.estimation, y_lin), Scaled(p.second, c.estimation, y_lin)};
  EffectSimulationOptions fine;
  fine.substeps = 16;
  for (GapRecord* r : {&c.estimation, &c.validation}) {
    r->y = SimulateWithEffects(c.real, effects, r->u, r->sample_time, fine);
    const double sigma = Rms(r->y.array() - r->y.mean()) * std::pow(10.0, -30.0 / 20);
    std::normal_distribution<double> noise(0.0, sigma);
    for (long k = 0; k < r->y.size(); ++k) r->y(k) += noise(rng);
  }
  const GapReport report = DiagnoseGap(c.sim, {c.estimation}, {c.validation});
  const GapVerdict& v = report.verdict;
  std::printf("truth %s + %s: verdict %s, effects", EffectName(p.first), EffectName(p.second), v.effect.c_str());
  for (const auto& e : v.effects) std::printf(" %s", EffectName(e.kind));
  std::printf(", NRMSE %.4f -> %.4f\n", v.nrmse_before, v.nrmse_after);
  if (std::getenv("GAP_DEBUG")) {
    for (const auto& r : report.ranking)
      std::printf("  %-22s nrmse %.4f est_mse %.3g bic %.1f LR %.1f/%.1f sig %.2f elig %d\n",
                  EffectName(r.effect.kind), r.nrmse_after, r.estimation_mse, r.bic, r.likelihood_ratio,
                  r.lr_threshold, r.signature, r.eligible);
    for (const auto& n : report.notes) std::printf("  note: %s\n", n.c_str());
  }
  ASSERT_EQ(v.effects.size(), 2u);
  const bool both = (v.effects[0].kind == p.first && v.effects[1].kind == p.second) ||
                    (v.effects[0].kind == p.second && v.effects[1].kind == p.first);
  EXPECT_TRUE(both);
  EXPECT_EQ(v.effect, EffectName(v.effects[0].kind));  // verdict.effect stays the first
  ASSERT_EQ(v.effects_std.size(), 2u);
  for (const auto& sd : v.effects_std)
    for (double s : sd) EXPECT_FALSE(s < 0);
}

INSTANTIATE_TEST_SUITE_P(
    Pairs, TwoEffectTest,
    ::testing::Values(PairCase{EffectKind::kCoulombFriction, EffectKind::kInputSaturation, 321},
                      PairCase{EffectKind::kDeadZone, EffectKind::kCubicStiffness, 322}),
    [](const auto& info) {
      return std::string(EffectName(info.param.first)) + "_with_" + EffectName(info.param.second);
    });

// Case `index` of `idrig gap bench --seed SEED` with these options (as the bench draws it).
GapCase SeededBenchCase(uint64_t seed, int index, const std::vector<EffectKind>& truth,
                        const GapCaseOptions& options) {
  std::mt19937_64 rng(BenchCaseSeed(seed, index));
  return MakeGapCase(truth, rng, options);
}

// Case `index` of `idrig gap bench --seed SEED --offsets` with the rest of the options given:
// an integrating plant, an excitation, a plant family ("" for the default).
GapCase OffsetBenchCase(uint64_t seed, int index, const std::vector<EffectKind>& truth, bool integrating = false,
                        const std::string& excitation = "", const std::string& plants = "", int samples = 0,
                        double sample_time = 0) {
  GapCaseOptions options;
  if (samples > 0) options.samples = samples;
  if (sample_time > 0) options.sample_time = sample_time;
  options.offsets = true;
  options.integrating = integrating;
  options.excitation = excitation;
  options.plants = plants;
  return SeededBenchCase(seed, index, truth, options);
}

// The bench's integrating plants (K/(s(Ts + 1)), a drifting record from the actuator offset), as
// `idrig gap bench --integrating --offsets --seed 44` draws them: case `index`.
GapCase IntegratingBenchCase(EffectKind truth, int index) { return OffsetBenchCase(44, index, {truth}, true); }

// `idrig gap bench --seed SEED --integrating --process-noise 0.5 --offsets`, case `index`.
GapCase ProcessNoiseBenchCase(uint64_t seed, int index, EffectKind truth) {
  GapCaseOptions options;
  options.offsets = true;
  options.integrating = true;
  options.process_noise = 0.5;
  return SeededBenchCase(seed, index, {truth}, options);
}

// The diagnosis as the bench runs it (one thread; the result does not depend on it).
GapReport DiagnoseOnOneThread(const GapCase& c, bool fit_drift = true) {
  GapOptions options;
  options.threads = 1;
  options.fit_drift = fit_drift;
  return DiagnoseGap(c.sim, {c.estimation}, {c.validation}, options);
}

// The last of the report's notes that contains `text` (empty when none does).
std::string LastNoteWith(const GapReport& report, const std::string& text) {
  std::string found;
  for (const auto& n : report.notes)
    if (n.find(text) != std::string::npos) found = n;
  return found;
}

const CandidateFit& Ranked(const GapReport& report, EffectKind kind) {
  const auto it = std::find_if(report.ranking.begin(), report.ranking.end(),
                               [&](const CandidateFit& f) { return f.effect.kind == kind && f.effects.size() <= 1; });
  if (it == report.ranking.end()) throw std::runtime_error(std::string("not ranked: ") + EffectName(kind));
  return *it;
}

TEST(GapIntegratingTest, AWeakResonanceUnderADriftIsNamedByItsSignificantValidationGain) {
  // The output is mostly the drift, so at 30 dB of it the resonance explains about 2 % of what
  // G0 leaves: a correlation of 0.14 with the gap, under the 0.2 share, but a validation gain of
  // 3σ (Diebold–Mariano, after the free gain of its extra states). Before, the verdict was none.
  const GapCase c = IntegratingBenchCase(EffectKind::kUnmodelledResonance, 17);
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  const CandidateFit& resonance = Ranked(report, EffectKind::kUnmodelledResonance);
  std::printf("weak resonance on an integrator: verdict %s, signature %.3f, gain z %.2f, NRMSE %.4f -> %.4f\n",
              v.effect.c_str(), resonance.signature, resonance.validation_gain_z, v.nrmse_before, v.nrmse_after);
  EXPECT_EQ(v.effect, "unmodelled_resonance");
  EXPECT_LT(resonance.signature, GapOptions{}.min_signature);  // the gain route, not the share, made it eligible
  EXPECT_GT(resonance.validation_gain_z, 2.33);
  EXPECT_TRUE(resonance.eligible);
  ASSERT_EQ(v.params.params.size(), 2u);
  EXPECT_NEAR(v.params.params[0], c.effect.params[0], 0.2 * c.effect.params[0]);  // ω
}

TEST(GapIntegratingTest, ExtraStatesFittedOnValidationDoNotBuyAResonanceForADelay) {
  // Multiple shooting fits a free state per segment on the validation records too: a resonance
  // has two states more than the delay that is there, 16 columns over 8 segments, worth 16 σ²
  // of validation RSS for nothing. Uncounted, they made the resonance beat the true delay by 17
  // BIC units; counted, the two tie (the data cannot tell this delay from a fast resonance).
  const GapCase c = IntegratingBenchCase(EffectKind::kTimeDelay, 2);
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  const CandidateFit& delay = Ranked(report, EffectKind::kTimeDelay);
  const CandidateFit& resonance = Ranked(report, EffectKind::kUnmodelledResonance);
  std::printf("delay on an integrator: verdict %s, nuisance columns delay %ld resonance %ld, fit %s\n",
              v.effect.c_str(), delay.nuisance_validation, resonance.nuisance_validation, v.fit_scheme.c_str());
  ASSERT_EQ(v.fit_scheme, "multiple_shooting");
  const long segments = report.validation_samples / v.shooting_segment;
  // Two states more per segment; the delay has one column the resonance lacks, the level its
  // line holds before the (one) validation record.
  EXPECT_EQ(resonance.nuisance_validation - delay.nuisance_validation, 2 * segments - 1);
  const bool delay_named = v.effect == "time_delay" ||
                           std::find(v.tied.begin(), v.tied.end(), "time_delay") != v.tied.end();
  EXPECT_TRUE(delay_named) << v.effect;
}

TEST(GapIntegratingTest, FrictionOnADriftingIntegratorDoesNotExhaustMemory) {
  // The delay candidate's fit wandered to its parameter bound (10^13 samples of delay line, an
  // OOM kill of the bench). Delays are now bounded by the record and the simulator refuses
  // more than 10^8 samples.
  const GapCase c = IntegratingBenchCase(EffectKind::kCoulombFriction, 8);
  GapReport report;
  ASSERT_NO_THROW(report = DiagnoseOnOneThread(c));
  std::printf("friction on a drifting integrator: verdict %s\n", report.verdict.effect.c_str());
  EXPECT_EQ(report.verdict.effect, "coulomb_friction");
}

TEST(GapIntegratingTest, AnOutputClipActsOnEachSegmentsOwnState) {
  // A PRBS drives an integrator into both output limits for a third of the record. Under
  // multiple shooting the segment's free state is the plant's, so the clip acts on it: with the
  // state added after the clip (before), no saturation fitted down to the noise and the verdict
  // was unmodelled_dynamics.
  const GapCase c = IntegratingBenchCase(EffectKind::kOutputSaturation, 23);
  ASSERT_EQ(c.excitation, "prbs");
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  const CandidateFit& clip = Ranked(report, EffectKind::kOutputSaturation);
  const double noise_var = c.noise_sigma * c.noise_sigma;
  std::printf("output clip on an integrator: verdict %s (%zu effects), estimation MSE %.5f (noise %.5f), NRMSE %.4f -> %.4f\n",
              v.effect.c_str(), v.effects.size(), clip.estimation_mse, noise_var, v.nrmse_before, v.nrmse_after);
  ASSERT_EQ(v.fit_scheme, "multiple_shooting");
  EXPECT_EQ(v.effect, "output_saturation");
  // At the generator's noise: 1.00 times it with the limits in the measured coordinates; 1.23
  // with the offset after the clip (its frame set per segment); 2.1 before the state went in.
  EXPECT_LT(clip.estimation_mse, 1.1 * noise_var);
}

TEST(GapIntegratingTest, AnOutputClipThatARampWalksIntoIsFittedInTheMeasuredCoordinates) {
  // `idrig gap bench --seed 95 --integrating --excitation multisine --offsets`, case 10: the
  // actuator offset ramps the output from the lower limit to the upper one, where the last
  // 28 % of the record sits. With the offset after the clip, free per segment, it and the
  // integrator's level were one direction, the limits' starts clipped nothing, the clip's fit
  // stayed at the refit (estimation MSE 1.8 times the noise) and the verdict was
  // sensor_nonlinearity.
  const GapCase c = OffsetBenchCase(95, 10, {EffectKind::kOutputSaturation}, true, "multisine");
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  const CandidateFit& clip = Ranked(report, EffectKind::kOutputSaturation);
  const double noise_var = c.noise_sigma * c.noise_sigma;
  std::printf("ramp into an output clip: verdict %s, estimation MSE %.5f (noise %.5f), limits %.3f %.3f (true %.3f %.3f + sensor offset %.3f)\n",
              v.effect.c_str(), clip.estimation_mse, noise_var, clip.effect.params[0], clip.effect.params[1],
              c.effect.params[0], c.effect.params[1], c.output_offset);
  EXPECT_EQ(v.effect, "output_saturation");
  EXPECT_LT(clip.estimation_mse, 1.1 * noise_var);
  // The upper limit, which the record sits on, in the measured coordinates: the true limit
  // plus the sensor offset, to a few noise σ.
  EXPECT_NEAR(clip.effect.params[1], c.effect.params[1] + c.output_offset, 3 * c.noise_sigma);
}

TEST(GapIntegratingTest, AnAbsoluteValueSensorKeepsItsFoldUnderMultipleShooting) {
  // The |y| sensor folds the output: a segment's state started where the maps were the
  // identity lands in the mirror basin, so the state from rest is tried too (with that start
  // alone, this case came out unmodelled_resonance + actuator_lag).
  const GapCase c = IntegratingBenchCase(EffectKind::kSensorNonlinearity, 11);
  ASSERT_NE(c.effect.params.at(3), 0.0);  // the |y| variant
  const GapReport report = DiagnoseOnOneThread(c);
  std::printf("|y| sensor on an integrator: verdict %s\n", report.verdict.effect.c_str());
  EXPECT_EQ(report.verdict.effect, "sensor_nonlinearity");
  EXPECT_EQ(report.verdict.effects.size(), 1u);
}


// An |y| sensor on an integrator that an actuator offset drives below zero for both records:
// the sensor reads −y throughout (a refit keeps G0's sign and cannot), and the diagnosis must find
// |y| at the noise floor with the actuator offset that drives the plant down.
void ExpectTheMirroredPlant(const GapCase& c, const char* what) {
  ASSERT_NE(c.effect.params.at(3), 0.0);  // the |y| variant
  // The readings |y| + b sit above the sensor offset and rise while the actuator offset drives
  // the integrator down.
  ASSERT_LT(c.input_offset, 0.0);
  ASSERT_GT(c.estimation.y.minCoeff(), c.output_offset);
  ASSERT_GT(c.estimation.y.tail(100).mean(), c.estimation.y.head(100).mean() + 1.0);
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  std::printf("%s: verdict %s (%zu effects), NRMSE %.4f -> %.4f (noise %.4f), du %.4f (true %.4f)\n", what,
              v.effect.c_str(), v.effects.size(), v.nrmse_before, v.nrmse_after, v.noise_nrmse,
              v.nuisance.input_offset, c.input_offset);
  ASSERT_EQ(v.effect, "sensor_nonlinearity");
  EXPECT_EQ(v.effects.size(), 1u);
  ASSERT_EQ(v.params.params.size(), 4u);
  EXPECT_EQ(v.params.params[3], 1.0);  // |y|, not the polynomial
  EXPECT_LT(v.nrmse_after, 1.05 * v.noise_nrmse);
  EXPECT_NEAR(v.nuisance.input_offset, c.input_offset, 0.05 * std::abs(c.input_offset));
}

TEST(GapIntegratingTest, AnAbsoluteValueSensorOnAPlantThatStaysBelowTheFoldIsTheMirroredPlant) {
  // `idrig gap bench --cases 39 --seed 7303 --integrating --offsets --excitation steps`, case 37.
  // Every shooting segment keeps to one side of the fold, where b and the level are one
  // direction; the segments grazing the fold counted as folding, and the record's b was tried at
  // their median and best own b (up to 3.7, above the readings of the others), where no level
  // fits: the |y| fit left 2.08, 30 times the noise, and the verdict was unmodelled_resonance +
  // time_delay. The lowest own b is now tried too.
  ExpectTheMirroredPlant(OffsetBenchCase(7303, 37, {EffectKind::kSensorNonlinearity}, true, "steps"),
                         "|y| sensor below its fold, steps");
}

TEST(GapIntegratingTest, AnAbsoluteValueSensorBelowTheFoldStartsFromTheMirroredDrift) {
  // `idrig gap bench --cases 260 --seed 7310 --integrating --offsets --only sensor_nonlinearity`,
  // case 219: an actuator offset of −0.78 drives the integrator from −3 to −55. From the refit's
  // du and from none the |y| fit ran to du = −2.69, its bound, and stayed where the refit was
  // (0.367 for a noise variance of 0.215); the verdict was unmodelled_resonance + time_delay. The
  // du that fits G0 to −y is now a start of the |y| fit.
  ExpectTheMirroredPlant(OffsetBenchCase(7310, 219, {EffectKind::kSensorNonlinearity}, true),
                         "|y| sensor below its fold, drift from the mirrored records");
}

TEST(GapIntegratingTest, AnEffectThatReachesAQuantiserMustPassAsASecondEffectAfterIt) {
  // `idrig gap bench --cases 39 --seed 7307 --integrating --offsets --excitation noise`, case 25:
  // a quantiser of step 0.17 at a noise σ of 0.02. From the quantiser no second effect passes; a
  // cubic spring alone is eligible against G0, and from it the quantiser passes as its second
  // (LR about 1270): the pair cubic spring + quantiser was named. The backward check now asks the
  // spring to pass as a second after the quantiser alone, as the search from the quantiser did.
  const GapCase c = OffsetBenchCase(7307, 25, {EffectKind::kOutputQuantization}, true, "noise");
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  const std::string dropped = LastNoteWith(report, "does not pass as a second effect after output_quantization alone");
  std::printf("quantiser reached from a cubic spring: verdict %s (%zu effects); %s\n", v.effect.c_str(),
              v.effects.size(), dropped.c_str());
  EXPECT_TRUE(Ranked(report, EffectKind::kCubicStiffness).eligible);  // the route through the spring exists
  EXPECT_EQ(v.effect, "output_quantization");
  EXPECT_EQ(v.effects.size(), 1u);
  EXPECT_NE(dropped.find("cubic_stiffness"), std::string::npos);
}

TEST(GapIntegratingTest, WhereTheValidationRecordsCannotTellTwoFitsApartTheEstimationRecordsDecide) {
  // `idrig gap bench --cases 26 --seed 7406 --integrating --offsets`, case 23: an output clip
  // under a binary input that the validation record barely reaches. The clip fits both records
  // at the noise; an actuator lag of T = 7.2 s left 3.3 times the noise on the estimation record
  // and won on validation by 0.7 % of MSE (28 BIC), so it was named.
  const GapCase c = OffsetBenchCase(7406, 23, {EffectKind::kOutputSaturation}, true);
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  const CandidateFit& lag = Ranked(report, EffectKind::kActuatorLag);
  std::printf("validation tie, estimation decides: verdict %s; actuator_lag: %s\n", v.effect.c_str(), lag.note.c_str());
  EXPECT_EQ(v.effect, "output_saturation");
  EXPECT_FALSE(lag.eligible);
  EXPECT_NE(lag.note.find("the estimation records can"), std::string::npos);
}

TEST(GapIntegratingTest, TheBenchsVisibilityAfterTheRefitAgreesWithTheDiagnosisOnAnIntegratingRig) {
  // `idrig gap bench --cases 26 --seed 7406 --integrating --offsets`, case 14: a parameter
  // mismatch (velocity gain 1.48 for 1.47, time constant 0.174 s for 0.155 s) under a staircase.
  // GapCase::visibility read 225, far above the threshold, and the case counted as detectable;
  // yet the free state of each shooting segment and the actuator offset take up the steady lag
  // the mismatch leaves, and the diagnosis (an independent fit) finds it within the noise. The
  // bench's visibility after the refit says so as well.
  const GapCase c = OffsetBenchCase(7406, 14, {EffectKind::kParameterMismatch}, true);
  ASSERT_EQ(c.visibility_refit.size(), 1u);
  const GapReport report = DiagnoseOnOneThread(c);
  const CandidateFit& mismatch = Ranked(report, EffectKind::kParameterMismatch);
  std::printf("parameter mismatch on an integrator: visibility %.1f, after the refit %.1f; the diagnosis's LR %.1f "
              "(threshold %.1f), verdict %s\n",
              c.visibility[0], c.visibility_refit[0], mismatch.likelihood_ratio, mismatch.lr_threshold,
              report.verdict.effect.c_str());
  EXPECT_GT(c.visibility[0], 10 * BenchVisibilityThreshold());
  EXPECT_LT(c.visibility_refit[0], BenchVisibilityThreshold());
  EXPECT_LT(mismatch.likelihood_ratio, mismatch.lr_threshold);
  EXPECT_EQ(report.verdict.effect, "none");
}

TEST(GapIntegratingTest, BesideACoarseQuantiserTheBenchsVisibilityAfterTheRefitCountsNoRoundingFlips) {
  // `idrig gap bench --cases 40 --seed 5002 --combos 1 --pairs any --integrating --offsets`, case
  // 26: a resonance (15.3 rad/s, ζ 0.13) beside a quantiser of step 0.69 at a noise σ of 0.12.
  // With the same noise draw the resonance moved samples across rounding thresholds, whole steps
  // each, and GapCase::visibility read about 2100; against the dithered quantiser's noise
  // (σ² + q²/12) the refit leaves it within the noise, and the diagnosis finds no resonance.
  const std::vector<EffectKind> truth = BenchCaseTruth(26, 1.0, true);
  ASSERT_EQ(truth, (std::vector<EffectKind>{EffectKind::kUnmodelledResonance, EffectKind::kOutputQuantization}));
  const GapCase c = OffsetBenchCase(5002, 26, truth, true);
  ASSERT_EQ(c.visibility_refit.size(), 2u);
  const GapReport report = DiagnoseOnOneThread(c);
  std::printf("resonance beside a quantiser: visibility %.1f, after the refit %.2f; verdict %s (%zu effects)\n",
              c.visibility[0], c.visibility_refit[0], report.verdict.effect.c_str(), report.verdict.effects.size());
  EXPECT_GT(c.visibility[0], 10 * BenchVisibilityThreshold());
  EXPECT_LT(c.visibility_refit[0], BenchVisibilityThreshold());
  EXPECT_GT(c.visibility_refit[1], BenchVisibilityThreshold()) << "the quantiser itself shows";
  EXPECT_EQ(report.verdict.effect, "output_quantization");
  for (const auto& e : report.verdict.effects) EXPECT_NE(e.kind, EffectKind::kUnmodelledResonance);
}

TEST(GapIntegratingTest, ABacklashIsFittedFromWhereItsPlayWasBeforeTheRecord) {
  // `idrig gap bench --cases 54 --seed 980 --combos 1 --pairs any --integrating --offsets
  // --excitation levels`, case 4, with the backlash alone: the bench's rig warmed up at zero
  // command, which left the play at du + r, 0.20 from where a play started at rest would sit after
  // the first sample. On an integrator that difference drove the first level's ramp until the
  // first reversal: r fitted 0.04 for 0.16, the record's start above the floor, and the verdict
  // was a higher linear order. Where the play was is now a nuisance per record.
  const GapCase c = OffsetBenchCase(980, 4, {EffectKind::kBacklash}, true, "levels");
  const double r = c.effect.params.at(0);
  ASSERT_GT(std::abs(c.input_offset), r);  // the warm-up took up the play on one side
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  std::printf("backlash on an integrator, play left before the record: verdict %s (%zu), r %.4f (truth %.4f), "
              "NRMSE %.4f, floor %.4f\n",
              v.effect.c_str(), v.effects.size(), v.effects.empty() ? NAN : v.effects[0].params[0], r,
              v.nrmse_after, v.noise_nrmse);
  EXPECT_EQ(v.effect, "backlash");
  ASSERT_EQ(v.effects.size(), 1u);
  EXPECT_NEAR(v.effects[0].params[0], r, 0.15 * r);
  EXPECT_LT(v.nrmse_after, 1.02 * v.noise_nrmse);
}

TEST(GapIntegratingTest, AnAbsoluteValueSensorFoldsWhereTheSegmentsLevelPutsIt) {
  // `idrig gap bench --cases 14 --seed 46 --offsets --integrating --combos 1 --excitation
  // levels`, case 3: a |y| sensor and a 0.071 s delay on an integrating plant, a sensor offset of
  // 0.74. Both segment starts (from rest; the state the identity map would need) left the
  // pre-map signal on one side of zero for the whole segment, the fold unused: the sensor map
  // fitted 0.147 for a floor of 0.031 — even with the true delay in G0 — and the verdict was
  // unmodelled_resonance + actuator_lag. The third start puts the integrator's level where the
  // fold falls inside the segment.
  const GapCase c = OffsetBenchCase(46, 3, BenchCaseTruth(3, 1.0), true, "levels");
  ASSERT_EQ(c.effects.size(), 2u);
  ASSERT_EQ(c.effects[1].kind, EffectKind::kSensorNonlinearity);
  ASSERT_NE(c.effects[1].params.at(3), 0.0);  // the |y| variant
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  std::vector<std::string> named;
  for (const Effect& e : v.effects) named.push_back(EffectName(e.kind));
  std::sort(named.begin(), named.end());
  std::printf("|y| sensor + delay on an integrator: verdict %s (%zu effects), NRMSE %.4f, floor %.4f\n",
              v.effect.c_str(), v.effects.size(), v.nrmse_after, v.noise_nrmse);
  EXPECT_EQ(named, (std::vector<std::string>{"sensor_nonlinearity", "time_delay"}));
  EXPECT_LT(v.nrmse_after, 1.05 * v.noise_nrmse);
  for (const Effect& e : v.effects) {
    if (e.kind == EffectKind::kTimeDelay) {
      EXPECT_NEAR(e.params[0], c.effects[0].params[0], 0.05 * c.effects[0].params[0]);
    }
  }
}

struct ColouredCase {
  EffectKind truth;
  int index;
};

class GapColouredNoiseTest : public ::testing::TestWithParam<ColouredCase> {};

TEST_P(GapColouredNoiseTest, AHigherOrderPartThatFollowsTheNoisesWanderIsNotMissingDynamics) {
  // `idrig gap bench --cases 26 --seed 71 --offsets --noise-pole 0.9`: output noise of
  // correlation time (1 + 0.9)/(1 − 0.9) = 19 samples. The effect alone simulates the
  // validation record at the noise level; a fourth-order part with the effect on it was better
  // by 4 % (friction, case 8) and 10 % (cubic spring, case 22) in MSE, 143 and 328 BIC units
  // counting 4000 independent samples, about 8 and 17 on the 210 independent ones, and the
  // verdict was unmodelled_dynamics. The Diebold–Mariano z of that gain (Newey–West) is below
  // its 1 % quantile now. For the cubic spring the fixed lag (9) under-covered the noise's
  // correlation (z 2.52); the automatic lag gives 1.88. Since stop 27 the order check is not run
  // against the verdict at all when what G0 or the verdict leaves does not follow the input
  // (coloured noise does not): either reason keeps the effect.
  GapCaseOptions options;
  options.offsets = true;
  options.noise_pole = 0.9;
  const GapCase c = SeededBenchCase(71, GetParam().index, {GetParam().truth}, options);
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  std::string gain;
  for (const auto& n : report.notes)
    if (n.find("validation gain over the verdict so far") != std::string::npos ||
        n.find("does not follow the input") != std::string::npos)
      gain = n;
  std::printf("%s under coloured noise: verdict %s; %s\n", EffectName(c.truth), v.effect.c_str(), gain.c_str());
  EXPECT_EQ(v.effect, EffectName(c.truth));
  EXPECT_TRUE(gain.find("not significant") != std::string::npos ||
              gain.find("does not follow the input") != std::string::npos)
      << gain;
  EXPECT_EQ(report.validation_prediction.size(), report.validation_samples);
}

INSTANTIATE_TEST_SUITE_P(Seed71, GapColouredNoiseTest,
                         ::testing::Values(ColouredCase{EffectKind::kCoulombFriction, 8},
                                           ColouredCase{EffectKind::kCubicStiffness, 22}),
                         [](const auto& info) { return std::string(EffectName(info.param.truth)); });

TEST(GapColouredNoiseTest, AGainChangeUnderATwoValuedInputIsAmbiguousThoughTheLrPasses) {
  // `idrig gap bench --cases 26 --seed 71 --offsets --noise-pole 0.9`, case 5: an input
  // saturation under a random binary input — on two values a mere gain (and an offset), so it
  // cannot be told from a dead zone, backlash or a gain mismatch. The gain-only refit's LR
  // against the full refit (32, above the threshold: the full refit's other coefficients follow
  // the noise's 19-sample wander) had made it parameter_mismatch; the full refit's validation
  // gain over the gain alone (z −0.3) shows no change of the dynamics, so it is `ambiguous`.
  GapCaseOptions options;
  options.offsets = true;
  options.noise_pole = 0.9;
  const GapCase c = SeededBenchCase(71, 5, {EffectKind::kInputSaturation}, options);
  ASSERT_TRUE(c.excitation == "rbs" || c.excitation == "prbs") << c.excitation;
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  const std::string note = LastNoteWith(report, "the input takes two values only");
  std::printf("input saturation under %s, coloured noise: verdict %s; %s\n", c.excitation.c_str(),
              v.effect.c_str(), note.c_str());
  EXPECT_EQ(v.effect, "ambiguous");
  EXPECT_NE(std::find(v.tied.begin(), v.tied.end(), "input_saturation"), v.tied.end());
  EXPECT_NE(note.find("above the threshold, but the full refit's validation gain"), std::string::npos) << note;
}

TEST(GapColouredNoiseTest, AMismatchOfTheDynamicsUnderATwoValuedInputStaysAParameterMismatch) {
  // The other side of the test above: every coefficient 10–30 % off (`idrig gap bench --cases 26
  // --seed 1021 --offsets --only parameter_mismatch --excitation rbs --noise-pole 0.9`, case 1).
  // The full refit simulates the validation record far better than the gain alone (z 15), so
  // the two-valued input does not make it ambiguous.
  GapCaseOptions options;
  options.offsets = true;
  options.noise_pole = 0.9;
  options.excitation = "rbs";
  const GapCase c = SeededBenchCase(1021, 1, {EffectKind::kParameterMismatch}, options);
  const GapReport report = DiagnoseOnOneThread(c);
  const std::string note = LastNoteWith(report, "the input takes two values only");
  std::printf("parameter mismatch under rbs, coloured noise: verdict %s; %s\n", report.verdict.effect.c_str(),
              note.c_str());
  EXPECT_EQ(report.verdict.effect, "parameter_mismatch");
  EXPECT_NE(note.find("and the full refit's validation gain"), std::string::npos) << note;
}

// Process noise: a load disturbance that the plant colours (`idrig gap bench --cases 30 --seed
// 2001 --offsets --only none --process-noise F`). G0 is the rig; what it leaves is the noise,
// correlated over the plant's time constant. At F = 0.5 case 221 (levels) was named
// parameter_mismatch (LR 3.3 times its threshold, 3 % of the gap closed), at F = 0.9 case 377
// (PRBS) output_saturation: the LR, the validation BIC and the fixed-lag validation gain count
// every sample as independent. A fit that matches little of the gap (signature under 0.2) must
// gain on validation with the automatic lag too.
struct ProcessNoiseCase {
  int index;
  double share;
  const char* was;
};
class GapProcessNoiseTest : public ::testing::TestWithParam<ProcessNoiseCase> {};

TEST_P(GapProcessNoiseTest, ALoadDisturbanceThePlantColoursIsNotAnEffect) {
  GapCaseOptions options;
  options.offsets = true;
  options.process_noise = GetParam().share;
  const GapCase c = SeededBenchCase(2001, GetParam().index, {EffectKind::kNone}, options);
  const GapReport report = DiagnoseOnOneThread(c);
  const std::string was_note = Ranked(report, EffectFromName(GetParam().was)).note;
  std::printf("none under process noise (%s): verdict %s; %s: %s\n", c.excitation.c_str(),
              report.verdict.effect.c_str(), GetParam().was, was_note.c_str());
  EXPECT_EQ(report.verdict.effect, "none");
  EXPECT_NE(LastNoteWith(report, "does not follow the input"), "");
  EXPECT_NE(was_note.find("not significant once the residual's correlation is counted"), std::string::npos) << was_note;
  // The explanation does not say that G0 fits within the noise: its gap is above the floor.
  EXPECT_EQ(report.verdict.g0_gap, "does_not_follow_input");
  EXPECT_NE(report.verdict.explanation.find("does not follow the input"), std::string::npos)
      << report.verdict.explanation;
}

INSTANTIATE_TEST_SUITE_P(Seed2001, GapProcessNoiseTest,
                         ::testing::Values(ProcessNoiseCase{221, 0.5, "parameter_mismatch"},
                                           ProcessNoiseCase{377, 0.9, "output_saturation"}),
                         [](const auto& info) { return "case" + std::to_string(info.param.index); });

TEST(GapProcessNoiseTest, AFrictionThatReproducesASlowGapIsKeptThoughItsGainIsAsSlow) {
  // The other side: `idrig gap bench --cases 26 --seed 44 --offsets --integrating`, case 21. G0's
  // residual on the integrating rig is a slow wander that the linear input test does not tie to
  // the input (a friction's sign(v) is not linear in u), and the friction's validation gain with
  // the automatic lag is z 2.08, under the threshold, because it is as slow as what it removes —
  // but the friction reproduces the gap (signature 0.998; validation NRMSE 1.69 for G0, 0.41 for
  // the refit, 0.027 with the friction) and is not a fit to the noise.
  std::mt19937_64 rng(BenchCaseSeed(44, 21));
  GapCaseOptions options;
  options.offsets = true;
  options.integrating = true;
  const GapCase c = MakeGapCase(BenchCaseTruth(21, 0).front(), rng, options);
  ASSERT_EQ(c.truth, EffectKind::kCoulombFriction);
  const GapReport report = DiagnoseOnOneThread(c);
  const CandidateFit& friction = Ranked(report, EffectKind::kCoulombFriction);
  std::printf("friction on an integrating rig: verdict %s, signature %.3f, NRMSE %.3g -> %.3g; %s\n",
              report.verdict.effect.c_str(), friction.signature, report.verdict.nrmse_before,
              friction.nrmse_after, LastNoteWith(report, "does not follow the input").c_str());
  EXPECT_EQ(report.verdict.effect, "coulomb_friction");
  EXPECT_GE(friction.signature, 0.2);
  EXPECT_EQ(friction.note.find("set aside"), std::string::npos) << friction.note;
  // Its gap does not follow the input, but the friction matches the gap: the check on shorter
  // segments for a load disturbance's walk (GapIntegratingProcessNoiseTest) is not run.
  EXPECT_EQ(report.verdict.g0_gap, "does_not_follow_input");
  EXPECT_EQ(report.verdict.shooting_segment, 500);
  EXPECT_EQ(LastNoteWith(report, "diagnosed again with segments of"), "");
}

// Case `index` of `idrig gap bench --seed SEED --offsets --integrating --noise-pole POLE`.
GapCase IntegratingColouredNoiseCase(uint64_t seed, int index, double noise_pole) {
  GapCaseOptions options;
  options.offsets = true;
  options.integrating = true;
  options.noise_pole = noise_pole;
  return SeededBenchCase(seed, index, {BenchCaseTruth(index, 0).front()}, options);
}

TEST(GapColouredNoiseTest, ALagFittedToNothingIsNotNamed) {
  // `idrig gap bench --cases 26 --seed 84 --offsets --integrating --noise-pole 0.9`, case 0: no
  // effect, coloured output noise on an integrating rig. The actuator_lag candidate fitted
  // T = 2.8e-14 s (no lag at all) with a plant better than the refit's own fit, and at signature
  // 0.29 over the refit it was named. A lag under a hundredth of the sample time is the refit
  // from another start: it is set aside, and nothing is named.
  const GapCase c = IntegratingColouredNoiseCase(84, 0, 0.9);
  ASSERT_EQ(c.truth, EffectKind::kNone);
  const GapReport report = DiagnoseOnOneThread(c);
  const CandidateFit& lag = Ranked(report, EffectKind::kActuatorLag);
  std::printf("none, coloured noise, integrating rig: verdict %s; lag T = %.3g s: %s\n",
              report.verdict.effect.c_str(), lag.effect.params.empty() ? -1.0 : lag.effect.params[0],
              lag.note.c_str());
  EXPECT_EQ(report.verdict.effect, "none");
  ASSERT_FALSE(lag.effect.params.empty());
  if (lag.effect.params[0] < 0.01 * c.estimation.sample_time) {
    EXPECT_FALSE(lag.eligible);
    EXPECT_NE(lag.note.find("fitted to no lag at all"), std::string::npos) << lag.note;
  }
}

TEST(GapOffsetTest, AClipThatOnlyTheEstimationRecordReachesIsNamedAsNotConfirmed) {
  // `idrig gap bench --cases 130 --seed 4020 --snr 20 --offsets`, case 62: an output clip whose
  // lower limit the estimation record's trough reaches (G0 leaves it at about 3.3 times the noise
  // variance) and the validation record's does not (G0 within the noise there). The verdict had
  // been `none`, "G0 fits within the noise". The clip is named, as found on the estimation
  // records only, with the limits where the bench put them (in the measured coordinates: the
  // rig's limits plus its sensor offset).
  GapCaseOptions options;
  options.offsets = true;
  options.snr_db = 20;
  const GapCase c = SeededBenchCase(4020, 62, BenchCaseTruth(62, 0), options);
  ASSERT_EQ(c.truth, EffectKind::kOutputSaturation);
  const GapReport report = DiagnoseOnOneThread(c);
  std::printf("clip on the estimation record only: verdict %s, estimation_only %d, g0_gap %s\n",
              report.verdict.effect.c_str(), int(report.verdict.estimation_only), report.verdict.g0_gap.c_str());
  EXPECT_EQ(report.verdict.g0_gap, "within_noise");
  EXPECT_EQ(report.verdict.effect, "output_saturation");
  EXPECT_TRUE(report.verdict.estimation_only);
  EXPECT_EQ(report.verdict.shrink, 0.0);  // no gap on the validation records to close
  EXPECT_NE(LastNoteWith(report, "found on the estimation records only"), "");
  ASSERT_EQ(report.verdict.params.params.size(), 2u);
  const double lo = c.effects[0].params[0] + c.output_offset, hi = c.effects[0].params[1] + c.output_offset;
  const double span = hi - lo;
  EXPECT_NEAR(report.verdict.params.params[0], lo, 0.02 * span);  // the limit the estimation record reaches
}

TEST(GapProcessNoiseTest, AGainErrorThatMatchesTheGapIsNotCheckedOnShorterSegments) {
  // `idrig gap bench --cases 26 --seed 83 --offsets --integrating --noise-pole 0.7`, case 14: a
  // parameter mismatch on an integrating rig under a PRBS, coloured output noise. Its gap (ramps
  // of the wrong slope) does not follow the input by the prewhitened test, which has little power
  // for a slow residual; the refit matches it (signature 0.37) and takes the validation NRMSE
  // from 0.034 to 0.032. On segments of 250 samples the free states take the ramps themselves and
  // nothing is named, so the check for a walk, were it run on such a fit, would have lost it.
  const GapCase c = IntegratingColouredNoiseCase(83, 14, 0.7);
  ASSERT_EQ(c.truth, EffectKind::kParameterMismatch);
  const GapReport report = DiagnoseOnOneThread(c);
  const CandidateFit& refit = Ranked(report, EffectKind::kParameterMismatch);
  std::printf("gain error on an integrating rig: verdict %s, G0's gap %s, signature %.3f, segment %ld\n",
              report.verdict.effect.c_str(), report.verdict.g0_gap.c_str(), refit.signature,
              report.verdict.shooting_segment);
  EXPECT_EQ(report.verdict.effect, "parameter_mismatch");
  EXPECT_EQ(report.verdict.g0_gap, "does_not_follow_input");
  EXPECT_GE(refit.signature, 0.2);
  EXPECT_EQ(report.verdict.shooting_segment, 500);
  EXPECT_EQ(LastNoteWith(report, "diagnosed again with segments of"), "");
}

// An integrating rig under process noise (`idrig gap bench --cases 20 --seed 2002 --only none
// --integrating --process-noise 0.5 --offsets`): the load integrates into a walk, which the free
// state of each 500-sample shooting segment takes only at the segment's start. Case 78 (levels)
// was named sensor_nonlinearity (LR 53 against 14, validation gain z 6.5 with the automatic lag,
// at 7 of the 8 validation segments), case 195 (random binary) the same with G0 already within
// the noise floor. G0's gap there does not follow the input or is within the floor, and the sensor
// map matches little of it (signature 0.17, 0.16): the records are diagnosed again with segments of
// 250 samples, where the walk within a segment is smaller, and nothing is named there, so that
// diagnosis stands. Cases 117 (levels) and 234 (PRBS) were named sensor_nonlinearity even so
// (LR 244 and 176): with its offset free per segment, a y², y³ map let each segment sit on its own
// stretch of the map, a gain per segment that took up the walk. Since stop 42 the segments of a
// record share the sensor's offset behind such a map: 117 and 195 are `none` at 500 samples, 78 and
// 234 after the diagnosis with 250 (at 500, 78 names a gain, 234 still the sensor map).
class GapIntegratingProcessNoiseTest : public ::testing::TestWithParam<int> {};

TEST_P(GapIntegratingProcessNoiseTest, AWalkWithinTheShootingSegmentsIsNotAnEffect) {
  const GapCase c = ProcessNoiseBenchCase(2002, GetParam(), EffectKind::kNone);
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  const std::string again = LastNoteWith(report, "diagnosed again with segments of");
  std::printf("none on an integrating rig under process noise (%s): verdict %s, segment %ld, G0's gap %s; %s\n",
              c.excitation.c_str(), v.effect.c_str(), v.shooting_segment, v.g0_gap.c_str(), again.c_str());
  EXPECT_EQ(v.effect, "none");
  EXPECT_EQ(v.fit_scheme, "multiple_shooting");
  if (v.shooting_segment != 500) {  // diagnosed again with shorter segments: what it said stands
    EXPECT_EQ(v.shooting_segment, 250);
    EXPECT_NE(again.find("it names nothing, and that stands"), std::string::npos) << again;
  }
}

INSTANTIATE_TEST_SUITE_P(Seed2002, GapIntegratingProcessNoiseTest, ::testing::Values(78, 117, 195, 234),
                         [](const auto& info) { return "case" + std::to_string(info.param); });

// An input saturation under a random binary input on an integrating rig under process noise
// (`idrig gap bench --cases 26 --seed 2005 --integrating --process-noise 0.5 --offsets`, case 5).
// On a two-valued input the saturation is a gain (GapCase::visibility_refit about 1e-11: the
// refit takes it up entirely), so the honest verdict is `ambiguous` among the gain-like
// explanations; a sensor map fitted to the walk within the 500-sample segments was named at LR
// 53, validation gain z 4.1 and signature 0.197. On 250-sample segments the diagnosis names the
// tie with a gain change, which does not hold the sensor map, and that diagnosis now stands.
TEST(GapIntegratingTest, UnderProcessNoiseATwoValuedInputsGainTieOnShorterSegmentsStands) {
  const GapCase c = ProcessNoiseBenchCase(2005, 5, EffectKind::kInputSaturation);
  ASSERT_EQ(c.excitation, "rbs");
  ASSERT_EQ(c.visibility_refit.size(), 1u);
  EXPECT_LT(c.visibility_refit[0], 1e-6);
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  const std::string again = LastNoteWith(report, "diagnosed again with segments of");
  std::printf("input saturation under a binary input and process noise: verdict %s, segment %ld; %s\n",
              v.effect.c_str(), v.shooting_segment, again.c_str());
  EXPECT_EQ(v.effect, "ambiguous");
  EXPECT_EQ(v.shooting_segment, 250);
  EXPECT_NE(std::find(v.tied.begin(), v.tied.end(), "input_saturation"), v.tied.end());
  EXPECT_NE(again.find("it names only a tie with a gain change"), std::string::npos) << again;
}

// A speed sensor that cannot see the sign (y = |x| + b) on an integrating rig under process noise
// (`idrig gap bench --cases 26 --seed 2005 --integrating --process-noise 0.5 --offsets`, case 24,
// PRBS). Behind |y| the shooting segments share the sensor's offset b (PredictFrom), and a
// segment's own b is fixed only where the plant passes the fold. With b the median of those
// segments' own, or the b of the segment that fits best, the |y| fit was worse than the truth's
// and an output clip was named (estimation MSE 0.00847 against 0.00822 with b free per segment);
// each folding segment's b is therefore scored on the whole record first. The verdict must be
// the |y| sensor.
TEST(GapAbsoluteSensorTest, AnIntegratingRigKeepsOneSensorOffsetForTheRecord) {
  const GapCase c = ProcessNoiseBenchCase(2005, 24, EffectKind::kSensorNonlinearity);
  ASSERT_EQ(c.effects.size(), 1u);
  ASSERT_TRUE(IsAbsoluteSensor(c.effects.front()));
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  std::printf("|y| sensor on an integrating rig under process noise (%s): verdict %s (%zu effects)\n",
              c.excitation.c_str(), v.effect.c_str(), v.effects.size());
  EXPECT_EQ(v.fit_scheme, "multiple_shooting");
  ASSERT_EQ(v.effect, "sensor_nonlinearity");
  EXPECT_TRUE(IsAbsoluteSensor(v.params));
}

TEST(GapPairTest, APairWhoseSecondEffectAddsNothingIsNotReported) {
  // `idrig gap bench --cases 26 --seed 51 --offsets --ts 0.002 --samples 6000`, case 23: an
  // output saturation, fast sampling. The single saturation fit had stopped above the noise; the
  // pair search from friction found the saturation's better fit with F_c ≈ 0 beside it, and the
  // verdict was coulomb_friction + output_saturation, until the backward check (each effect
  // refitted alone from the pair's fit) dropped the pair. Since the output maps act on the
  // segment's state the single fit reaches the noise floor and the pair search does not run.
  // Either way one effect is reported; a pair that is searched must be dropped.
  GapCaseOptions options;
  options.offsets = true;
  options.sample_time = 0.002;
  options.samples = 6000;
  const GapCase c = SeededBenchCase(51, 23, {EffectKind::kOutputSaturation}, options);
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  const std::string backward = LastNoteWith(report, "backward check");
  const std::string second = LastNoteWith(report, "second effect after");
  std::printf("fast-sampled output saturation: verdict %s (%zu effects); %s; %s\n", v.effect.c_str(),
              v.effects.size(), second.c_str(), backward.c_str());
  EXPECT_EQ(v.effect, "output_saturation");
  EXPECT_EQ(v.effects.size(), 1u);
  const bool not_searched = second.find("not searched") != std::string::npos;
  const bool dropped = backward.find("the pair is dropped") != std::string::npos;
  EXPECT_TRUE(not_searched || dropped) << second << " / " << backward;
}

TEST(GapPairTest, AnEffectThatFailsAsSecondAfterTheMainOneCannotComeFirstInstead) {
  // `idrig gap bench --cases 26 --seed 97 --snr 60 --offsets`, case 21: friction under PRBS at
  // 60 dB. After friction, a sensor map does not pass (its signature is too low); but the
  // search from the sensor map (third of the first effects) adds friction, and that pair had
  // the lowest validation BIC, so the verdict was sensor_nonlinearity + friction. The backward
  // check shows which is the main effect (friction alone 27.8 BIC units above the pair, the
  // sensor map alone 29902), and the sensor map must pass as a second after it. Whether a pair
  // from another first gets that far depends on its local minimum: at stop 50 a cubic spring
  // with friction beat friction alone by 3.9 BIC and was dropped by the check; since stop 51 (a
  // friction second also starts with the actuator offset at 0) no such pair beats friction
  // alone, and there is no check to make.
  GapCaseOptions options;
  options.offsets = true;
  options.snr_db = 60;
  const GapCase c = SeededBenchCase(97, 21, {EffectKind::kCoulombFriction}, options);
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  const std::string backward = LastNoteWith(report, "backward check");
  std::printf("friction at 60 dB: verdict %s (%zu effects); %s\n", v.effect.c_str(), v.effects.size(), backward.c_str());
  EXPECT_EQ(v.effect, "coulomb_friction");
  EXPECT_EQ(v.effects.size(), 1u);
  if (!backward.empty()) {
    EXPECT_NE(backward.find("does not pass as a second effect after it"), std::string::npos) << backward;
  }
}

TEST(GapPlantFamilyTest, AnActuatorLagOnATwoMassPlantIsNotAnOverdampedResonance) {
  // `idrig gap bench --cases 26 --seed 202 --offsets --plants two-mass`, case 3: an actuator lag
  // (T = 0.061 s) on a fourth-order plant under a random binary input. The resonance candidate
  // fitted ω = 304 rad/s, ζ = 9.3 — two real poles, the faster one at 5600 rad/s beyond the
  // band, i.e. a lag of 2ζ/ω = 0.061 s with a spare parameter — and won by 0.3 % in NRMSE. A
  // resonance has a peak (ζ ≤ 1/√2); the lag is named.
  const GapCase c = OffsetBenchCase(202, 3, {EffectKind::kActuatorLag}, false, "", "two-mass");
  ASSERT_EQ(c.sim.den.size(), 5);
  const GapReport report = DiagnoseOnOneThread(c);
  const CandidateFit& resonance = Ranked(report, EffectKind::kUnmodelledResonance);
  const CandidateFit& lag = Ranked(report, EffectKind::kActuatorLag);
  std::printf("two-mass lag: verdict %s; lag T = %.4f (truth %.4f); resonance zeta %.3f\n",
              report.verdict.effect.c_str(), lag.effect.params[0], c.effect.params[0], resonance.effect.params[1]);
  EXPECT_EQ(report.verdict.effect, "actuator_lag");
  EXPECT_LE(resonance.effect.params[1], M_SQRT1_2 + 1e-12);
  EXPECT_NEAR(lag.effect.params[0], c.effect.params[0], 0.1 * c.effect.params[0]);
}

TEST(GapPlantFamilyTest, AResonanceOnAShortRecordIsNamedWithItsOwnModeNotG0s) {
  // `idrig gap bench --cases 26 --seed 802 --samples 1500 --offsets`, case 4: a 13 rad/s mode
  // (ζ 0.084) behind a 3.1 rad/s plant, 15 s of `levels`. Two things went wrong: the
  // input-residual test, with little power on 1500 samples, read G0's validation residual as a
  // disturbance (N·R² 48.9 against 49.2) and set the resonance aside, so a delay was named at
  // twice the floor; and the fit had put the new mode into the refitted plant, leaving G0's own
  // mode in the resonance block (ω 3.14, ζ 0.455). A mode that dies out within the record cannot
  // stand in for a steady disturbance, and the added mode is the one far from G0's poles.
  const GapCase c = OffsetBenchCase(802, 4, {EffectKind::kUnmodelledResonance}, false, "", "", 1500);
  ASSERT_EQ(c.excitation, "levels");
  const GapReport report = DiagnoseOnOneThread(c);
  std::printf("short resonance: verdict %s, omega %.3f zeta %.4f (truth %.3f %.4f), NRMSE %.4f floor %.4f\n",
              report.verdict.effect.c_str(), report.verdict.params.params.at(0), report.verdict.params.params.at(1),
              c.effect.params[0], c.effect.params[1], report.verdict.nrmse_after, report.verdict.noise_nrmse);
  ASSERT_EQ(report.verdict.effect, "unmodelled_resonance");
  EXPECT_NEAR(report.verdict.params.params[0], c.effect.params[0], 0.03 * c.effect.params[0]);
  EXPECT_NEAR(report.verdict.params.params[1], c.effect.params[1], 0.15 * c.effect.params[1]);
  // The plant keeps G0's mode (the bench's sim model is the rig's plant here).
  ASSERT_EQ(report.verdict.plant.den.size(), c.sim.den.size());
  const double g0_w2 = c.sim.den(2) / c.sim.den(0), fit_w2 = report.verdict.plant.den(2) / report.verdict.plant.den(0);
  EXPECT_NEAR(fit_w2, g0_w2, 0.05 * g0_w2);
  EXPECT_LE(report.verdict.nrmse_after, 1.2 * report.verdict.noise_nrmse);
}

TEST(GapOffsetTest, AModeWithoutAPeakIsNotNamedAResonance) {
  // `idrig gap bench --cases 52 --seed 901 --offsets --combos 0.5`, case 49: a delay of 0.047 s
  // and a cubic sensor map under PRBS. A "resonance" at 30.9 rad/s with ζ at its bound 1/√2 (no
  // peak: a low-pass, the phase of the delay) beat the delay by 4 BIC and was named with the
  // sensor map at the floor. A mode fitted without a peak is set aside.
  const GapCase c = OffsetBenchCase(901, 49, BenchCaseTruth(49, 0.5));
  ASSERT_EQ(c.effects.size(), 2u);
  ASSERT_EQ(c.effects[0].kind, EffectKind::kTimeDelay);
  ASSERT_EQ(c.effects[1].kind, EffectKind::kSensorNonlinearity);
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  const CandidateFit& resonance = Ranked(report, EffectKind::kUnmodelledResonance);
  std::printf("delay + sensor map: verdict %s (%zu effects), NRMSE %.4f floor %.4f; resonance zeta %.4f, note '%s'\n",
              v.effect.c_str(), v.effects.size(), v.nrmse_after, v.noise_nrmse, resonance.effect.params.at(1),
              resonance.note.c_str());
  EXPECT_FALSE(resonance.eligible);
  EXPECT_NE(resonance.note.find("no resonant peak"), std::string::npos);
  ASSERT_EQ(v.effects.size(), 2u);
  EXPECT_EQ(v.effects[0].kind, EffectKind::kTimeDelay);
  EXPECT_EQ(v.effects[1].kind, EffectKind::kSensorNonlinearity);
  EXPECT_NEAR(v.effects[0].params[0], c.effects[0].params[0], 0.03 * c.effects[0].params[0]);
  EXPECT_LT(v.nrmse_after, 1.05 * v.noise_nrmse);
}

// `idrig gap bench --cases 54 --seed SEED --offsets --combos 1 --pairs any --excitation E
// [--integrating]` (seed 950 and levels unless said): pairs that the rig-pair list does not hold.
GapCase AnyPairCase(int index, const std::vector<EffectKind>& expected_truth = {}, uint64_t seed = 950,
                    const std::string& excitation = "levels", bool integrating = false,
                    const std::string& plants = "", double sample_time = 0) {
  const std::vector<EffectKind> truth = BenchCaseTruth(index, 1.0, true);
  if (!expected_truth.empty()) {
    EXPECT_EQ(truth, expected_truth) << "the bench's pair " << index << " moved";
  }
  return OffsetBenchCase(seed, index, truth, integrating, excitation, plants, 0, sample_time);
}

std::vector<std::string> NamedSorted(const GapVerdict& v) {
  std::vector<std::string> named;
  for (const Effect& e : v.effects) named.push_back(EffectName(e.kind));
  std::sort(named.begin(), named.end());
  return named;
}

// The diagnosis on one thread, its verdict printed under `what`.
GapReport DiagnoseAndPrint(const GapCase& c, const char* what) {
  GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  std::printf("%s: verdict %s (%zu effects), NRMSE %.4f floor %.4f\n", what, v.effect.c_str(), v.effects.size(),
              v.nrmse_after, v.noise_nrmse);
  return report;
}

// The verdict names exactly `sorted` (alphabetical) and simulates the validation records within
// 5 % of the independent noise floor.
void ExpectNamedAtTheFloor(const GapVerdict& v, const std::vector<std::string>& sorted) {
  EXPECT_EQ(NamedSorted(v), sorted);
  EXPECT_LT(v.nrmse_after, 1.05 * v.noise_nrmse);
}

// Diagnoses case `c` and expects exactly its withheld effects named at the floor
// (ExpectNamedAtTheFloor); the verdict, for the parameters.
GapVerdict DiagnoseTheTruthAtTheFloor(const GapCase& c, const char* what) {
  const GapReport report = DiagnoseAndPrint(c, what);
  std::vector<std::string> truth;
  for (const Effect& e : c.effects) truth.push_back(EffectName(e.kind));
  std::sort(truth.begin(), truth.end());
  ExpectNamedAtTheFloor(report.verdict, truth);
  return report.verdict;
}

// Parameter `index` of the verdict's effect `kind` within `share` of `truth` (the effect named:
// ExpectNamedAtTheFloor).
void ExpectParameterNear(const GapVerdict& v, EffectKind kind, size_t index, double truth, double share) {
  for (const Effect& e : v.effects) {
    if (e.kind == kind && e.params.size() > index) {
      EXPECT_NEAR(e.params[index], truth, share * std::abs(truth)) << EffectName(kind) << " parameter " << index;
    }
  }
}

TEST(GapOffsetTest, ARecordStartedMidRunHasTheInputBeforeItInTheDelayLine) {
  // A rig that ran before the record began: settled at an input c (est 0.8, val −0.7 of the
  // command's peak), then the record's own input. Over the first d samples a delayed plant is
  // still driven by c. With the line taken as empty (8ae8bbb), the start transient bought a
  // second effect and pulled the delay to 0.17 s instead of 0.3 s (records made the same way in
  // Python: an actuator lag beside a delay of 0.246 s). The line's level before the record is a
  // nuisance parameter per record beside the initial state (candidate_fit.cc).
  const GapCase shape = LevelsCase(EffectKind::kTimeDelay, 331, 3000);
  const double ts = shape.estimation.sample_time;
  const Effect delay{EffectKind::kTimeDelay, {30 * ts}};
  std::mt19937_64 rng(332);
  GapRecord est = shape.estimation, val = shape.validation;
  const long warm = 3000;  // the run before the record, at the level c: settled
  for (auto [r, level] : {std::pair{&est, 0.8}, std::pair{&val, -0.7}}) {
    const double c = level * r->u.cwiseAbs().maxCoeff();
    Eigen::VectorXd u(warm + r->u.size());
    u << Eigen::VectorXd::Constant(warm, c), r->u;
    const Eigen::VectorXd y = SimulateWithEffect(shape.sim, delay, u, ts).tail(r->u.size());
    std::normal_distribution<double> noise(0.0, Rms(y.array() - y.mean()) * std::pow(10.0, -30.0 / 20));
    r->y = y;
    for (long k = 0; k < r->y.size(); ++k) r->y(k) += noise(rng);
  }
  const GapReport report = DiagnoseGap(shape.sim, {est}, {val});
  const GapVerdict& v = report.verdict;
  std::printf("delay on a record started mid-run: verdict %s (%zu effects), tau %.4f (truth %.4f), NRMSE %.4f floor %.4f\n",
              v.effect.c_str(), v.effects.size(), v.params.params.empty() ? NAN : v.params.params[0],
              delay.params[0], v.nrmse_after, v.noise_nrmse);
  ExpectNamedAtTheFloor(v, {"time_delay"});
  ExpectParameterNear(v, EffectKind::kTimeDelay, 0, delay.params[0], 0.02);
  // The report says the line's level is a nuisance of the delayed model it reports.
  EXPECT_NE(v.nuisance.initial_state.find("delay line"), std::string::npos) << v.nuisance.initial_state;
}

TEST(GapPairTest, ADelayBesideFrictionIsFoundFromG0AsGiven) {
  // Case 5: a delay of two samples with Coulomb friction. Friction fitted alone bends the plant's
  // poles to mimic the delay, and from that fit the pair's delay stayed in a poor basin (ΔBIC
  // −3895 against −5816 for a lag, which was named). The pair is also started from G0 as given
  // with the first effect's parameters, and the delay from a grid (√2 apart): the better starts
  // by their cost are fitted.
  const GapCase c = AnyPairCase(5, {EffectKind::kTimeDelay, EffectKind::kCoulombFriction});
  const GapVerdict v = DiagnoseTheTruthAtTheFloor(c, "delay + friction");
  ExpectParameterNear(v, EffectKind::kTimeDelay, 0, c.effects[0].params[0], 0.05);
}

TEST(GapPairTest, ADelayBesideFrictionMovesOffItsWholeSamples) {
  // `idrig gap bench --seed 7102 --offsets --combos 0.5 --pairs any --excitation steps`, case 11: a
  // delay of 4.9 samples beside Coulomb friction on a third-order plant. Beside a feedback effect
  // the simulator rounded the delay to whole samples, the fit's cost was flat between them, and
  // the pair's delay stayed at its start of one sample (LR 1384) while a resonance was named beside
  // the friction (LR 5671). With the fractional part kept (effects.cc) the delay moves to its value.
  const std::vector<EffectKind> truth = BenchCaseTruth(11, 0.5, true);
  ASSERT_EQ(truth, (std::vector<EffectKind>{EffectKind::kTimeDelay, EffectKind::kCoulombFriction}))
      << "the bench's pair 11 moved";
  const GapCase c = OffsetBenchCase(7102, 11, truth, false, "steps");
  const GapVerdict v = DiagnoseTheTruthAtTheFloor(c, "delay of 4.9 samples + friction, steps");
  ExpectParameterNear(v, EffectKind::kTimeDelay, 0, c.effects[0].params[0], 0.05);
}

TEST(GapPairTest, ARecordSplitInTimeWeighsItsFirstEffectsResidualOverTheWholeRecord) {
  // One record, no validation record: the diagnosis splits it in time, and the validation record is
  // the whole record scored from its middle. The floor of what the first effect leaves
  // (ResidualFloor, gap_report.cc) took the stacked validation prediction, which holds only the
  // scored samples, as if it held the whole record, and read past its end (half a record of
  // memory that was not the prediction). It now predicts every sample of every record.
  // `--seed 7101 --combos 0.5 --pairs any`, case 4: a delay, named alone, within the floor.
  const std::vector<EffectKind> truth = BenchCaseTruth(4, 0.5, true);
  ASSERT_EQ(truth, std::vector<EffectKind>{EffectKind::kTimeDelay}) << "the bench's case 4 moved";
  const GapCase c = OffsetBenchCase(7101, 4, truth);
  GapOptions options;
  options.threads = 1;
  const GapReport report = DiagnoseGap(c.sim, {c.estimation}, {}, options);
  EXPECT_EQ(report.verdict.effect, "time_delay");
  EXPECT_EQ(report.verdict.effects.size(), 1u);
  const std::string skipped = LastNoteWith(report, "second effect after time_delay: not searched");
  EXPECT_FALSE(skipped.empty()) << "the second-effect search was not skipped within the floor";
  ExpectParameterNear(report.verdict, EffectKind::kTimeDelay, 0, c.effects[0].params[0], 0.05);
}

// `idrig gap bench --cases N --seed SEED --offsets --combos F [--pairs any] [--plants P] --snr
// 20`, case `index` (its pair `expected`): the first effect leaves the validation records within
// the floor, and the second is searched even so. The note that says why (`why`) must be there for
// `first`, and both effects must be named; the report, for the parameters.
GapReport SearchedThoughWithinTheFloor(uint64_t seed, int index, double combos, bool any_pairs,
                                       const std::string& plants, const std::vector<EffectKind>& expected,
                                       const char* why, const std::string& first, const char* what) {
  GapCaseOptions options;
  options.offsets = true;
  options.snr_db = 20;
  options.plants = plants;
  const std::vector<EffectKind> truth = BenchCaseTruth(index, combos, any_pairs);
  EXPECT_EQ(truth, expected) << "the bench's pair " << index << " moved";
  const GapCase c = SeededBenchCase(seed, index, truth, options);
  GapReport report = DiagnoseAndPrint(c, what);
  const std::string searched = LastNoteWith(report, why);
  std::printf("%s\n", searched.c_str());
  EXPECT_NE(searched.find("second effect after " + first + ": searched though"), std::string::npos) << searched;
  std::vector<std::string> named;
  for (EffectKind kind : expected) named.push_back(EffectName(kind));
  std::sort(named.begin(), named.end());
  EXPECT_EQ(NamedSorted(report.verdict), named);
  return report;
}

TEST(GapPairTest, AGapLeftOnTheEstimationRecordsAsksForASecondEffect) {
  // `--seed 6101 --combos 0.5 --pairs any`, case 35 (PRBS): an actuator lag and a y², y³ sensor
  // map (visibility 310 against a threshold of 11.4). The lag alone left the validation records at
  // 1.04 times the independent floor, within its tolerance of 1.045 at 20 dB, and the second
  // effect was not searched; on the estimation records it left 1.064 times the floor. Pooled over
  // both (1.053 against 1.032) the gap is above the floor, and the search finds the sensor map.
  const GapReport report = SearchedThoughWithinTheFloor(
      6101, 35, 0.5, true, "", {EffectKind::kActuatorLag, EffectKind::kSensorNonlinearity},
      "on the estimation and validation records together", "actuator_lag", "lag + sensor map at 20 dB");
  EXPECT_LT(report.verdict.nrmse_after, 1.05 * report.verdict.noise_nrmse);
}

TEST(GapPairTest, AFirstEffectUnderALooseFloorIsSearchedForASecondOnItsOwnResidual) {
  // `--seed 6104 --combos 1 --plants two-mass`, case 3 (PRBS): a delay of 0.02 s and an |y|
  // sensor on a two-mass rig. The ARX floor does not predict the fold: it read 0.00367 for a noise
  // variance of 0.00223, and the |y| map alone, at 0.00292, was "within the floor" and the delay
  // was not searched. The same estimator on what the map leaves reads 0.0027, under the map's MSE
  // by more than its tolerance: what it leaves is predictable, the search runs and the delay is
  // found.
  const GapReport report = SearchedThoughWithinTheFloor(
      6104, 3, 1.0, false, "two-mass", {EffectKind::kTimeDelay, EffectKind::kSensorNonlinearity},
      "what it leaves is predictable", "sensor_nonlinearity", "delay + |y| sensor on a two-mass rig at 20 dB");
  for (const Effect& e : report.verdict.effects)
    if (e.kind == EffectKind::kTimeDelay) {
      EXPECT_NEAR(e.params[0], 0.02, 0.05 * 0.02);
    }
}

TEST(GapPairTest, ALimitBesideADeadZoneIsNamedInTheGeneratorsCoordinates) {
  // Case 27: an input limit and a dead zone (a valve with overlap and a limited stroke). Two
  // input-side maps were never paired, and a sensor map took the limit's place at 1.3 times the
  // floor. Input maps act in a rig's order (the limit on the command, then the dead zone: stop
  // 34) whichever was found first, so the limits reported are the generator's, not the limits
  // after the dead zone (moved in by its width) that a fit in the order found reported.
  const GapCase c = AnyPairCase(27, {EffectKind::kInputSaturation, EffectKind::kDeadZone});
  const GapVerdict v = DiagnoseTheTruthAtTheFloor(c, "limit + dead zone");
  // No delay in the model reported: no delay line among its nuisance parameters.
  EXPECT_EQ(v.nuisance.initial_state.find("delay line"), std::string::npos) << v.nuisance.initial_state;
  const double d = c.effects[1].params[0];
  for (const Effect& e : v.effects) {
    if (e.kind == EffectKind::kDeadZone) {
      EXPECT_NEAR(e.params[0], d, 0.03 * d);
    }
    if (e.kind == EffectKind::kInputSaturation) {
      // The dead zone fixes the actuator offset (its flat part is about zero).
      EXPECT_NEAR(v.nuisance.input_offset, c.input_offset, 0.02 * d);
      EXPECT_NEAR(e.params[0], c.effects[0].params[0], 0.05 * std::abs(c.effects[0].params[0]));
      EXPECT_NEAR(e.params[1], c.effects[0].params[1], 0.05 * std::abs(c.effects[0].params[1]));
    }
  }
}

TEST(GapPairTest, AModeWithinTwoStandardErrorsOfNoPeakIsNotAResonance) {
  // Case 0: a delay of 0.053 s and an actuator lag of 0.039 s. A mode with ζ = 0.702 ± 0.005 (no
  // peak the data can show) beat the delay alone and was named with the lag.
  const GapCase c = AnyPairCase(0, {EffectKind::kTimeDelay, EffectKind::kActuatorLag});
  const GapReport report = DiagnoseAndPrint(c, "delay + lag");
  ExpectNamedAtTheFloor(report.verdict, {"actuator_lag", "time_delay"});
  EXPECT_FALSE(Ranked(report, EffectKind::kUnmodelledResonance).eligible);
}

TEST(GapPairTest, AClipBesideASensorMapMovesItsLimitsIntoThePlantsCoordinates) {
  // Case 51: an output clip and a mild cubic sensor map. A clip alone has its limits in the
  // measured coordinates (the output offset inside it); beside a sensor map the offset is after
  // both. The clip's measured limits were read as the plant's and the pair fitted far worse than
  // the clip alone (LR −10453): only the clip was named, at 1.1 times the floor.
  const GapCase c = AnyPairCase(51, {EffectKind::kOutputSaturation, EffectKind::kSensorNonlinearity});
  const GapVerdict v = DiagnoseTheTruthAtTheFloor(c, "clip + sensor map");
}

TEST(GapPairTest, AOneSidedDeadZoneAfterBacklashIsNotNamed) {
  // `idrig gap bench --cases 26 --seed 43 --offsets --excitation chirp`, case 20: backlash alone.
  // Once two input-side maps could pair, a "dead zone" of 0.42 after the backlash, at an
  // actuator offset of 1.74 (the whole command range on one side of it), made up for the
  // backlash's poorer single fit and was named beside it. Only one of its kinks is reached: after
  // another input map that is a limit on its output, not a dead zone.
  const GapCase c = OffsetBenchCase(43, 20, {EffectKind::kBacklash}, false, "chirp");
  DiagnoseTheTruthAtTheFloor(c, "backlash under a chirp");
}

TEST(GapPairTest, AResonanceBehindAnAbsoluteValueSensorIsTriedWhenADelayPassesInItsPlace) {
  // `--seed 974 --excitation steps`, case 25: a mode (ω 20.7 rad/s, ζ 0.20) with an |y| sensor.
  // What the sensor map leaves is the mode's response folded by the sign of y, which the linear
  // input-residual test reads as a disturbance: the resonance was not tried and a delay was named
  // in its place (NRMSE 0.062 for a floor of 0.035).
  const GapCase c = AnyPairCase(25, {EffectKind::kUnmodelledResonance, EffectKind::kSensorNonlinearity}, 974, "steps");
  const GapVerdict v = DiagnoseTheTruthAtTheFloor(c, "resonance + |y| sensor");
  ExpectParameterNear(v, EffectKind::kUnmodelledResonance, 0, c.effects[0].params[0], 0.02);
  ExpectParameterNear(v, EffectKind::kUnmodelledResonance, 1, c.effects[0].params[1], 0.05);
}

TEST(GapPairTest, ADelayBehindAnAbsoluteValueSensorStartingJustBelowTheFoldIsADelay) {
  // `--seed 974 --excitation steps`, case 8: a delay (0.086 s) with an |y| sensor; the rig sits
  // at −0.05 before the validation record (its actuator offset) and rises through the fold when
  // the first step arrives. Both starts of the segment's state put it at +0.05 (the mirror
  // basin, no dip), which left the delay pair 6× the floor over the first 200 samples; a
  // resonance's free states covered that, and resonance + |y| was named at the floor. The
  // grid over the level the rig was settled at finds the dip.
  const GapCase c = AnyPairCase(8, {EffectKind::kTimeDelay, EffectKind::kSensorNonlinearity}, 974, "steps");
  const GapVerdict v = DiagnoseTheTruthAtTheFloor(c, "delay + |y| sensor");
  ExpectParameterNear(v, EffectKind::kTimeDelay, 0, c.effects[0].params[0], 0.02);
}

TEST(GapPairTest, ADeadZoneBehindAnAbsoluteValueSensorIsFoundFromTheSensorMapAsAbsoluteValue) {
  // `--seed 973 --excitation noise`, case 38: a dead zone (0.48, actuator offset 0.26) read
  // through an |y| sensor. Alone, the dead zone takes the fold's other half as a far offset and a
  // wide flat part (du 1.16, d 1.44), and the sensor map fits best as a polynomial; beside the
  // dead zone that polynomial found the dead zone but folded the wrong way on validation (ΔBIC
  // +2737), and the verdict was the dead zone alone at NRMSE 0.19 for a floor of 0.028. In a pair
  // the polynomial sensor map is also tried as |y|, chosen on validation.
  const GapCase c = AnyPairCase(38, {EffectKind::kDeadZone, EffectKind::kSensorNonlinearity}, 973, "noise");
  const GapVerdict v = DiagnoseTheTruthAtTheFloor(c, "dead zone + |y| sensor");
  ExpectParameterNear(v, EffectKind::kDeadZone, 0, c.effects[0].params[0], 0.03);
}

TEST(GapPairTest, AnAbsoluteValueSensorOnAFourthOrderRigWhoseFitLeavesTheRealsIsFittedNotACrash) {
  // `--pairs any --seed 971 --plants two-mass --excitation levels`, case 32: an input limit with
  // an |y| sensor on a two-mass rig. During the sensor map's fit a trial simulation left the
  // reals; the grid over the |y| fold's start level then had no finite point, and refining from
  // that empty start read out of bounds (a segmentation fault of `idrig gap bench`, found at
  // this stop's first build). No finite grid point now means no third start.
  const GapCase c = AnyPairCase(32, {EffectKind::kInputSaturation, EffectKind::kSensorNonlinearity}, 971,
                                "levels", false, "two-mass");
  DiagnoseTheTruthAtTheFloor(c, "input limit + |y| sensor, two-mass");
}

TEST(GapPairTest, ADeadZoneBehindAnAbsoluteValueSensorOnAFourthOrderRigIsFoundFromG0AsGiven) {
  // `--pairs any --seed 971 --plants two-mass --excitation levels`, case 38: a dead zone (0.334)
  // read through an |y| sensor. The sensor map fitted alone is a polynomial whose plant and
  // actuator offset have bent to make up for the fold; the |y| variant of the pair started from
  // those wandered off, and sensor map + friction was named at 14 times the floor. The |y|
  // variant is also started from G0 as given, with no actuator offset.
  const GapCase c = AnyPairCase(38, {EffectKind::kDeadZone, EffectKind::kSensorNonlinearity}, 971, "levels",
                                false, "two-mass");
  const GapVerdict v = DiagnoseTheTruthAtTheFloor(c, "dead zone + |y| sensor, two-mass");
  ExpectParameterNear(v, EffectKind::kDeadZone, 0, c.effects[0].params[0], 0.03);
}

TEST(GapPairTest, ADelayRivalledByADampedModeIsStillPairedWithTheLimit) {
  // `--pairs any --seed 978 --ts 0.05 --excitation levels`, case 2: a delay of two samples with
  // an input limit on a first-order plant. Alone, a damped mode (ζ 0.57) fits 6 BIC ahead of
  // the delay (a Padé-like stand-in); its pair with the limit reached the floor first and the
  // search stopped, naming resonance + limit. The delay, a near rival, has its pair searched too,
  // and with one parameter fewer it has the lower validation BIC.
  const GapCase c = AnyPairCase(2, {EffectKind::kTimeDelay, EffectKind::kInputSaturation}, 978, "levels",
                                false, "", 0.05);
  const GapVerdict v = DiagnoseTheTruthAtTheFloor(c, "delay + limit, Ts 0.05 s");
  ExpectParameterNear(v, EffectKind::kTimeDelay, 0, c.effects[0].params[0], 0.02);
}

// `idrig gap bench --seed SEED --offsets --combos COMBOS` (with `--pairs any` where `any_pair`)
// with the rest of `options`, case `index`, whose truth must be `expected_truth`.
GapCase OffsetBenchCaseOf(uint64_t seed, int index, double combos, bool any_pair,
                          const std::vector<EffectKind>& expected_truth, GapCaseOptions options) {
  const std::vector<EffectKind> truth = BenchCaseTruth(index, combos, any_pair);
  EXPECT_EQ(truth, expected_truth) << "the bench's case " << index << " moved";
  options.offsets = true;
  return SeededBenchCase(seed, index, truth, options);
}

// The same with `--pairs any`.
GapCase AnyPairBenchCase(uint64_t seed, int index, double combos, const std::vector<EffectKind>& expected_truth,
                         GapCaseOptions options) {
  return OffsetBenchCaseOf(seed, index, combos, true, expected_truth, options);
}

// `idrig gap bench --cases 52 --seed 7601 --offsets --combos 0.3 --pairs any --damping 0.02,0.3`,
// case `index`: a share of pairs from every pair, on lightly damped plants.
GapCase LightlyDampedPairCase(int index, const std::vector<EffectKind>& expected_truth) {
  GapCaseOptions options;
  options.zeta_min = 0.02;
  options.zeta_max = 0.3;
  return AnyPairBenchCase(7601, index, 0.3, expected_truth, options);
}

// The diagnosis of pair case `c` names both its effects (`named`, sorted), a note holds `note`
// (unless empty), and the first effect's first parameter is within `share` of the truth's.
void ExpectPairNamed(const GapCase& c, const char* what, const std::vector<std::string>& named,
                     const std::string& note, double share) {
  const GapReport report = DiagnoseAndPrint(c, what);
  EXPECT_EQ(NamedSorted(report.verdict), named);
  if (!note.empty()) {
    EXPECT_NE(LastNoteWith(report, note), "") << note;
  }
  ExpectParameterNear(report.verdict, c.effects[0].kind, 0, c.effects[0].params[0], share);
}

TEST(GapPairTest, ASecondEffectThatValidationCannotTellFromItsKinIsChosenOnTheEstimationRecords) {
  // Case 9: a delay of 7.5 samples beside an input limit, under a staircase. After the limit, a
  // lag and the delay as its second pass alike; the lag's pair was 4.6 BIC ahead on validation
  // (their difference there z 0.07), the delay's 107 ahead in the LR on the estimation records,
  // and the lag was named.
  ExpectPairNamed(LightlyDampedPairCase(9, {EffectKind::kTimeDelay, EffectKind::kInputSaturation}),
                  "delay + input limit, lightly damped", {"input_saturation", "time_delay"},
                  "time_delay preferred to actuator_lag: the validation records cannot tell", 0.1);
}

TEST(GapPairTest, APairFromALagIsCheckedAgainstThePairFromItsKinTheDelay) {
  // Case 26: a delay of two samples beside an output clip on a plant with ζ 0.05. Alone the lag
  // ranked 22 BIC ahead of the delay (neither explains the clip); the lag's pair with the clip
  // ended the search, and lag + clip was named. The delay's pair with the clip is 423 BIC
  // ahead of it on validation.
  ExpectPairNamed(LightlyDampedPairCase(26, {EffectKind::kTimeDelay, EffectKind::kOutputSaturation}),
                  "delay + output clip, lightly damped", {"output_saturation", "time_delay"},
                  "it replaces actuator_lag with output_saturation", 0.1);
}

// `idrig gap bench --cases 52 --seed 7602 --offsets --combos 0.5 --pairs any --plants two-mass
// --snr 20`, case `index`.
GapCase TwoMassPairCase(int index, const std::vector<EffectKind>& expected_truth) {
  GapCaseOptions options;
  options.plants = "two-mass";
  options.snr_db = 20;
  return AnyPairBenchCase(7602, index, 0.5, expected_truth, options);
}

TEST(GapPairTest, BehindAnAbsoluteSensorWhatALagLeavesFollowsTheInputThroughTheFold) {
  // Case 35: an actuator lag of T 0.114 s before an |y| sensor, under PRBS. The sensor alone
  // left the validation records at 0.000368, within the loose floor 0.000374 (the noise variance
  // 0.000344), and what it left did not follow the input in the linear test (N·R² 36.6 against
  // 49.2): behind the fold a lag's error flips sign with the plant's output. Against u times the
  // fold's slope sign(y) it does, and the pair is searched.
  ExpectPairNamed(TwoMassPairCase(35, {EffectKind::kActuatorLag, EffectKind::kSensorNonlinearity}),
                  "lag + |y| sensor, two-mass, 20 dB", {"actuator_lag", "sensor_nonlinearity"},
                  "through the output maps' slope at the plant's output", 0.3);  // T 0.136 ± 0.016 s
}

TEST(GapPairTest, ALeanerSecondEffectGivesWayWhereTheEstimationRecordsPreferTheRicherOne) {
  // Case 49: a mode of ω 46 rad/s, ζ 0.15 beside an output clip. As the clip's second a delay
  // (one parameter) simulated validation within two standard errors of the mode and was
  // preferred, though the estimation records preferred the mode (LR 902 against 876).
  ExpectPairNamed(TwoMassPairCase(49, {EffectKind::kUnmodelledResonance, EffectKind::kOutputSaturation}),
                  "resonance + output clip, two-mass, 20 dB", {"output_saturation", "unmodelled_resonance"}, "", 0.1);
}

TEST(GapPairTest, AnInputLimitBesideFrictionIsFoundWhereFrictionAloneRanItsActuatorOffsetToTheBound) {
  // `idrig gap bench --cases 52 --seed 7704 --offsets --combos 0.3 --ts 0.002 --samples 6000`
  // (pairs that occur together on rigs, sampled fast), case 26: friction beside an input limit
  // whose upper side clips the staircase (an actuator offset of 0.38). Friction alone ran its
  // actuator offset to the bound of ±max|u| (2.64), where its tanh has no slope left; every start
  // of the limit from there clipped nothing or did worse, the three best alike did not move, and
  // a y², y³ sensor map was named as the second effect at six times the noise floor.
  GapCaseOptions options;
  options.sample_time = 0.002;
  options.samples = 6000;
  const GapCase c = OffsetBenchCaseOf(7704, 26, 0.3, false,
                                      {EffectKind::kCoulombFriction, EffectKind::kInputSaturation}, options);
  const GapVerdict v = DiagnoseTheTruthAtTheFloor(c, "friction + input limit, Ts 0.002 s");
  ExpectParameterNear(v, EffectKind::kCoulombFriction, 0, c.effects[0].params[0], 0.05);
  ExpectParameterNear(v, EffectKind::kInputSaturation, 1, c.effects[1].params[1], 0.05);
}

TEST(GapPairTest, ThePairsMainEffectAloneIsTheRankingsFitWhereItsRefitFromThePairStaysInThePairsBasin) {
  // `idrig gap bench --cases 52 --seed 7706 --offsets --combos 0.5 --plants zeros --noise-pole
  // 0.9`, case 20: an output clip alone, on a third-order plant with a zero, under strongly
  // coloured noise. From an |y| sensor as the first effect the clip passed as its second, and the
  // pair was 5 BIC ahead of the clip alone. The backward check refitted the clip alone from the
  // pair's fit (the plant's sign flipped under the fold) to 1998 BIC behind the pair, the |y|
  // sensor passed as a second against that, and clip + |y| was named — an |y| that never folds.
  // Against the clip as the ranking fitted it, the sensor does not pass. (Since stop 51 the only
  // test that takes the backward check's "does not pass as a second effect" route.)
  GapCaseOptions options;
  options.plants = "zeros";
  options.noise_pole = 0.9;
  const GapCase c = OffsetBenchCaseOf(7706, 20, 0.5, false, {EffectKind::kOutputSaturation}, options);
  const GapReport report = DiagnoseAndPrint(c, "output clip, zeros, noise pole 0.9");
  EXPECT_EQ(NamedSorted(report.verdict), std::vector<std::string>{"output_saturation"});
  EXPECT_NE(LastNoteWith(report, "does not pass as a second effect after it (LR"), "");
  EXPECT_NE(LastNoteWith(report, "against its single fit in the ranking"), "");
}

TEST(GapPairTest, ASecondEffectUnderALooseFloorIsSearchedWhenTheResidualFollowsTheInput) {
  // `--pairs any --seed 978 --ts 0.05 --excitation levels`, case 36: a dead zone with a cubic
  // spring, sampled coarsely. The one-step ARX predictor of the floor reads σ 1.6 times the
  // noise there, the dead zone alone (at twice the noise variance) sat within it, and the cubic
  // spring was never searched for. What the dead zone leaves still follows the input, so the
  // pair is searched.
  const GapCase c = AnyPairCase(36, {EffectKind::kDeadZone, EffectKind::kCubicStiffness}, 978, "levels",
                                false, "", 0.05);
  const GapVerdict v = DiagnoseTheTruthAtTheFloor(c, "dead zone + cubic spring, Ts 0.05 s");
  ExpectParameterNear(v, EffectKind::kDeadZone, 0, c.effects[0].params[0], 0.02);
  ExpectParameterNear(v, EffectKind::kCubicStiffness, 0, c.effects[1].params[0], 0.05);
}

TEST(GapPairTest, TwoTiedSinglesAboveTheFloorAreSettledByTheirPair) {
  // `--seed 970 --excitation multisine`, case 41: backlash (r 0.106) with a cubic spring. Each
  // alone explains the same part of the gap (their validation BICs 0.07 apart, five times the
  // floor): `ambiguous`, and no pair was searched from a tie.
  const GapCase c = AnyPairCase(41, {EffectKind::kBacklash, EffectKind::kCubicStiffness}, 970, "multisine");
  const GapVerdict v = DiagnoseTheTruthAtTheFloor(c, "backlash + cubic spring");
  EXPECT_TRUE(v.tied.empty());
  ExpectParameterNear(v, EffectKind::kBacklash, 0, c.effects[0].params[0], 0.03);
  ExpectParameterNear(v, EffectKind::kCubicStiffness, 0, c.effects[1].params[0], 0.05);
}

TEST(GapPairTest, TwoTiedSinglesThatKeepTheSameSecondEffectAreSettledByTheirTwoPairs) {
  // `idrig gap bench --cases 52 --seed 7801 --offsets --combos 0.5 --pairs any --snr 25 --damping
  // 0.05,0.3`, case 19: a delay of 3.4 samples beside an output quantiser whose step (0.19) is
  // seven noise sigmas, under a PRBS. Alone, a lag and the delay tie (validation BIC 1.6 apart);
  // each keeps the quantiser as its second effect (LR ~1000), and the tie stood because neither
  // pair holds both: `ambiguous`, the quantiser unnamed. The two pairs differ only in the tied
  // effect. The validation BIC prefers the lag's pair by 22, but the residual is a train of
  // whole-step flips: with the Newey–West lag the lag's validation gain is z 1.1, the delay's gain
  // on the estimation records z 3.7 (threshold 2.3). The estimation records settle it.
  GapCaseOptions options;
  options.snr_db = 25;
  options.zeta_min = 0.05;
  options.zeta_max = 0.3;
  const GapCase c = AnyPairBenchCase(7801, 19, 0.5, {EffectKind::kTimeDelay, EffectKind::kOutputQuantization},
                                     options);
  const GapReport report = DiagnoseAndPrint(c, "delay + quantiser, PRBS, 25 dB");
  const GapVerdict& v = report.verdict;
  EXPECT_EQ(NamedSorted(v), (std::vector<std::string>{"output_quantization", "time_delay"}));
  EXPECT_TRUE(v.tied.empty());
  EXPECT_NE(LastNoteWith(report, "the estimation records take time_delay's"), "");
  ExpectParameterNear(v, EffectKind::kTimeDelay, 0, c.effects[0].params[0], 0.1);
  // No surer than the z test that settled it (Φ(3.7)).
  EXPECT_LT(v.confidence, 1.0);
  EXPECT_GT(v.confidence, 0.99);
}

TEST(GapPairTest, ASecondEffectThatPassesOnItsValidationGainAloneWhereTheFirstLeavesNoiseClearsTheCorrectedLevel) {
  // `idrig gap bench --cases 52 --seed 7803 --offsets --combos 0.5 --pairs any --excitation noise
  // --snr 25 --process-noise 0.2`, case 40: a backlash alone, under a load disturbance. The
  // backlash leaves the validation records at 1.085 times the floor's variance (the disturbance,
  // coloured by the plant, is above the one-step floor), the seconds are searched, and a cubic
  // spring of k3 −0.038 passed: LR 33.7 (its threshold 14.3 assumes white residuals), signature
  // 0.09, and a validation gain of z 2.4 against the plain 1 % level 2.33 — the best of eight
  // seconds tried, after a first whose residual does not follow the input (N·R² 11.8 against
  // 49.2): a disturbance to chase. Its gain must then clear the level corrected for the effects
  // tried (3.1).
  GapCaseOptions options;
  options.snr_db = 25;
  options.excitation = "noise";
  options.process_noise = 0.2;
  const GapCase c = AnyPairBenchCase(7803, 40, 0.5, {EffectKind::kBacklash}, options);
  const GapReport report = DiagnoseAndPrint(c, "backlash, noise input, process noise 0.2");
  EXPECT_EQ(NamedSorted(report.verdict), std::vector<std::string>{"backlash"});
  EXPECT_NE(LastNoteWith(report, "second effect after backlash: none passes"), "");  // searched
  ExpectParameterNear(report.verdict, EffectKind::kBacklash, 0, c.effects[0].params[0], 0.03);
}

TEST(GapIntegratingTest, APairWhoseFirstEffectRanksLowAloneIsSearchedWhileTheBestIsFarAboveTheFloor) {
  // `--pairs any --integrating --seed 980`, case 28: an input limit beside a backlash of r 0.30.
  // Alone the backlash ranked fifth (its validation worse than a refit: the limit it lacks) and
  // the limit was not eligible; the pairs of the three firsts left 2.3 times the floor's variance
  // and |y| was named. While the best is that far above the floor, two more firsts are searched:
  // backlash first, the limit is its second at the floor.
  const GapCase c = AnyPairCase(28, {EffectKind::kInputSaturation, EffectKind::kBacklash}, 980, "levels", true);
  const GapVerdict v = DiagnoseTheTruthAtTheFloor(c, "input limit + backlash on an integrator");
  ExpectParameterNear(v, EffectKind::kBacklash, 0, c.effects[1].params[0], 0.05);
}

TEST(GapIntegratingTest, ASecondEffectSmallAgainstTheDriftIsKeptOnASignificantValidationGain) {
  // `--pairs any --integrating --seed 980`, case 15: an actuator lag beside a cubic spring. The
  // lag passed the LR test after the spring but correlated under the 0.2 share with what the
  // spring left (the drift sets the residual's scale), and only the spring was named. A second
  // effect now also passes on a significant validation gain over its first (Diebold–Mariano z
  // at the plain level, as a single effect does), on records it was not fitted to.
  const GapCase c = AnyPairCase(15, {EffectKind::kActuatorLag, EffectKind::kCubicStiffness}, 980, "levels", true);
  const GapReport report = DiagnoseAndPrint(c, "lag + cubic spring on an integrator");
  ExpectNamedAtTheFloor(report.verdict, {"actuator_lag", "cubic_stiffness"});
  ExpectParameterNear(report.verdict, EffectKind::kActuatorLag, 0, c.effects[0].params[0], 0.25);
  // The lag passed on its gain, not on its share: its line in the pair search's note.
  std::string second;
  for (const auto& n : report.notes)
    if (n.rfind("second effect after cubic_stiffness", 0) == 0) second = n;
  const size_t at = second.find("actuator_lag: LR");
  ASSERT_NE(at, std::string::npos) << second;
  double lr = 0, threshold = 0, signature = 0, gain_z = 0;
  ASSERT_EQ(std::sscanf(second.c_str() + at, "actuator_lag: LR %lf (threshold %lf), signature %lf, gain z %lf", &lr,
                        &threshold, &signature, &gain_z),
            4)
      << second;
  std::printf("lag as the second: LR %.1f (threshold %.1f), signature %.2f, gain z %.2f\n", lr, threshold, signature,
              gain_z);
  EXPECT_GT(lr, threshold);
  EXPECT_LT(signature, 0.2);
  EXPECT_GT(gain_z, 2.33);  // the one-sided normal quantile at 1 %
}

TEST(GapPairTest, AnInputLimitBeforeABacklashIsFoundBesideAFreePlay) {
  // `--pairs any --plants two-mass --seed 971`, case 28: an input limit before a backlash of
  // r 0.17. Named whole before the play became a nuisance; with the play free (PlayStates) the
  // backlash alone no longer pinned the actuator offset, which wandered off, and the limit
  // searched beside it was fitted against that offset (backlash + cubic spring named). Beside a
  // backlash alone du is now not fitted on a stable plant, and the limit acts before the play.
  const GapCase c = AnyPairCase(28, {EffectKind::kInputSaturation, EffectKind::kBacklash}, 971, "levels", false,
                                "two-mass");
  const GapVerdict v = DiagnoseTheTruthAtTheFloor(c, "input limit + backlash, two masses");
  ExpectParameterNear(v, EffectKind::kBacklash, 0, c.effects[1].params[0], 0.03);
}

TEST(GapIntegratingTest, ASecondEffectTheSegmentsTakeUpIsSearchedAtTheFloorAndFoundAgainOnLongerOnes) {
  // `idrig gap bench --cases 40 --seed 5002 --combos 1 --pairs any --integrating --offsets`, case
  // 36: a dead zone with a cubic spring (k3 6.3e-4) on K/(s(Ts + 1)), multilevel input. Each
  // 500-sample shooting segment's free state takes up most of what the spring does, the dead zone
  // alone reaches the floor (validation MSE 0.000899 against 0.000915), and the second effect was
  // not searched. It now is, from that first effect, and the pair is kept because the diagnosis
  // on segments of 1000 samples names it too.
  const GapCase c = AnyPairCase(36, {EffectKind::kDeadZone, EffectKind::kCubicStiffness}, 5002, "", true);
  const GapReport report = DiagnoseAndPrint(c, "dead zone + cubic spring on an integrator");
  const GapVerdict& v = report.verdict;
  ExpectNamedAtTheFloor(v, {"cubic_stiffness", "dead_zone"});
  const std::string searched = LastNoteWith(report, "second effect after dead_zone: searched though");
  EXPECT_NE(searched.find("shooting segments' free states"), std::string::npos) << searched;
  const std::string again = LastNoteWith(report, "searched at the floor, is found again on segments of 1000");
  EXPECT_FALSE(again.empty()) << "the pair was not confirmed on longer segments";
  ExpectParameterNear(v, EffectKind::kDeadZone, 0, c.effects[0].params[0], 0.05);
}

TEST(GapIntegratingTest, APairAtTheFloorThatLongerSegmentsDoNotFindIsDropped) {
  // `idrig gap bench --cases 26 --seed 2005 --integrating --process-noise 0.5 --offsets`, case 7:
  // a backlash (r 0.151) under a load disturbance that walks. The backlash alone reaches the
  // floor; searched at the floor, a cubic spring passes beside it (LR 21.1 against 11.4,
  // validation gain z 3.3) on segments of 500 samples: it follows the walk within the segments.
  // The diagnosis on segments of 1000 does not name it, so the backlash stands alone.
  const GapCase c = ProcessNoiseBenchCase(2005, 7, EffectKind::kBacklash);
  const GapReport report = DiagnoseAndPrint(c, "backlash on an integrator under process noise");
  const GapVerdict& v = report.verdict;
  EXPECT_EQ(NamedSorted(v), std::vector<std::string>{"backlash"});
  const std::string dropped = LastNoteWith(report, "is not found again on segments of 1000");
  EXPECT_NE(dropped.find("so it is dropped"), std::string::npos) << dropped;
  ExpectParameterNear(v, EffectKind::kBacklash, 0, c.effects[0].params[0], 0.05);
}

TEST(GapIntegratingTest, AQuantiserCrossingALevelIsNotASensorStep) {
  // `--seed 972 --integrating`, case 50: a quantiser of step 0.81 (noise 0.06) with a weak cubic
  // spring, on a position that moves slowly. Each crossing of a level is a sharp jump that lasts,
  // as a re-zeroed sensor's is: four "sensor steps" were marked, and the quantiser went unnamed
  // (a resonance with a lag of 1.2 s was named). A jump of one lattice step on a lattice is not
  // marked; a re-zeroed sensor that moves by several steps still is.
  GapCase c = AnyPairCase(50, {EffectKind::kCubicStiffness, EffectKind::kOutputQuantization}, 972, "levels", true);
  const double q = c.effects[1].params[0];
  {
    const GapReport report = DiagnoseAndPrint(c, "quantiser on an integrating plant");
    EXPECT_TRUE(report.sensor_steps.empty());
    const std::vector<std::string> named = NamedSorted(report.verdict);
    EXPECT_NE(std::find(named.begin(), named.end(), "output_quantization"), named.end());
    ExpectParameterNear(report.verdict, EffectKind::kOutputQuantization, 0, q, 0.001);
  }
  // The sensor re-zeroed by five steps halfway through the estimation record.
  const long half = c.estimation.y.size() / 2;
  c.estimation.y.tail(c.estimation.y.size() - half).array() += 5 * q;
  const GapReport report = DiagnoseAndPrint(c, "the same with a sensor step of five levels");
  ASSERT_EQ(report.sensor_steps.size(), 1u);
  EXPECT_NEAR(static_cast<double>(report.sensor_steps[0].sample), static_cast<double>(half), 2.0);
}

TEST(GapOffsetTest, ALimitTheValidationRecordsShowIsNotReleased) {
  // `idrig gap bench --cases 26 --seed 204 --offsets --plants zeros --combos 1`, case 18: an
  // actuator lag and an input saturation on a plant with a zero. 0.8 % of the estimation
  // samples reach below the lower limit (and as many of the validation ones); with the lag
  // unmodelled the estimation MSE hardly moved when it was released, and the released fit
  // left the validation NRMSE at 0.045 for a floor of 0.031. Validation keeps it.
  const GapCase c = OffsetBenchCase(204, 18, BenchCaseTruth(18, 1.0), false, "", "zeros");
  ASSERT_EQ(c.effects.size(), 2u);
  ASSERT_EQ(c.effects[1].kind, EffectKind::kInputSaturation);
  const GapReport report = DiagnoseOnOneThread(c);
  const CandidateFit& limit = Ranked(report, EffectKind::kInputSaturation);
  // Limits in the command's coordinates (u = u_phys − du), where the generator's and the fit's
  // actuator offsets (not identifiable apart from the limits' common shift) drop out.
  const double lo = limit.effect.params[0] - limit.input_offset;
  const double truth_lo = c.effects[1].params[0] - c.input_offset;
  std::printf("lag + limit: verdict %s; lower limit %.4f (truth %.4f); NRMSE %.4f, floor %.4f; note '%s'\n",
              report.verdict.effect.c_str(), lo, truth_lo, limit.nrmse_after, report.verdict.noise_nrmse,
              limit.note.c_str());
  EXPECT_EQ(limit.note.find("not reached"), std::string::npos);
  EXPECT_NEAR(lo, truth_lo, 0.05 * std::abs(truth_lo));
  EXPECT_LT(limit.nrmse_after, 1.05 * report.verdict.noise_nrmse);
}

TEST(GapOffsetTest, AFrictionThatRanksLowAloneIsSearchedAsAFirstBesideABentLimit) {
  // `idrig gap bench --cases 14 --seed 604 --offsets --combos 1 --plants zeros --excitation
  // levels`, case 7: Coulomb friction and an input saturation on a plant with a zero. Alone,
  // the saturation bends its limits to mimic the friction (both above the command's range),
  // and friction ranks fourth, after the three firsts the pair search starts from; the pair
  // kept was friction with a dead zone at validation NRMSE 0.33 for a floor of 0.033. The best
  // pair's other effect (friction) is now also a first, and the saturation found after it.
  // Without the sensor-drift nuisance (stop 28): with it the same pair is named, but its fit
  // lands in another basin of this fragile case (F_c 0.751 for 0.830, the lower limit bent to
  // −1.32, NRMSE 0.133 against 0.098; docs/gap.md, stop 28). Since stop 34 the search takes up
  // to five firsts while the best pair is far above the floor, and friction is reached that way
  // before the other-effect rule runs: either way friction is searched as a first.
  const GapCase c = OffsetBenchCase(604, 7, BenchCaseTruth(7, 1.0), false, "levels", "zeros");
  ASSERT_EQ(c.effects.size(), 2u);
  ASSERT_EQ(c.effects[0].kind, EffectKind::kCoulombFriction);
  ASSERT_EQ(c.effects[1].kind, EffectKind::kInputSaturation);
  const GapReport report = DiagnoseOnOneThread(c, /*fit_drift=*/false);
  std::vector<std::string> named;
  for (const Effect& e : report.verdict.effects) named.push_back(EffectName(e.kind));
  std::printf("friction + limit: named %s%s%s; NRMSE %.4f, floor %.4f\n", named.empty() ? "" : named[0].c_str(),
              named.size() > 1 ? " + " : "", named.size() > 1 ? named[1].c_str() : "", report.verdict.nrmse_after,
              report.verdict.noise_nrmse);
  ASSERT_EQ(named.size(), 2u);
  EXPECT_NE(std::find(named.begin(), named.end(), "coulomb_friction"), named.end());
  EXPECT_NE(std::find(named.begin(), named.end(), "input_saturation"), named.end());
  for (const Effect& e : report.verdict.effects) {
    if (e.kind == EffectKind::kCoulombFriction) {
      EXPECT_NEAR(e.params[0], c.effects[0].params[0], 0.05 * c.effects[0].params[0]);
    }
  }
  EXPECT_LT(report.verdict.nrmse_after, 0.5 * 0.33);
  EXPECT_TRUE(std::any_of(report.notes.begin(), report.notes.end(), [](const std::string& n) {
    return n.rfind("second effect after coulomb_friction", 0) == 0 && n.find("not searched") == std::string::npos;
  }));
}

TEST(GapOffsetTest, AKinkPassedByAHairAtASweepsPeakDoesNotMakeADeadZoneTwoSided) {
  // `idrig gap bench --cases 26 --seed 214 --offsets --plants two-mass --excitation chirp`,
  // case 5: an upper input limit under a constant-amplitude sweep. The dead zone fitted its flat
  // part away from zero command with the far kink 0.002 below the sweep's peak, where 1.5 % of
  // the samples sit: counted as a second side, so the one-sided rule did not apply, and the
  // dead zone won by one parameter at the same fit. A side must be passed by 2 % of the input's
  // span to count.
  const GapCase c = OffsetBenchCase(214, 5, {EffectKind::kInputSaturation}, false, "chirp", "two-mass");
  const GapReport report = DiagnoseOnOneThread(c);
  const CandidateFit& dead = Ranked(report, EffectKind::kDeadZone);
  std::printf("limit under a sweep: verdict %s; the dead zone's note: %s\n", report.verdict.effect.c_str(),
              dead.note.c_str());
  EXPECT_EQ(report.verdict.effect, "input_saturation");
  EXPECT_FALSE(dead.eligible);
  EXPECT_NE(dead.note.find("one-sided"), std::string::npos);
}

TEST(GapOffsetTest, OfTwoBarelyReachedLimitsTheUnreachedOneIsReleased) {
  // `idrig gap bench --cases 26 --seed 52 --offsets --ts 0.05`, case 18: the lower limit is
  // reached by 0.6 % of the estimation samples, the upper one by none. Both were "few", so
  // neither was released; the upper one stayed at the edge of the estimation records and
  // clipped validation samples beyond it, and the one-sided dead zone won (dead_zone, du at
  // its bound). Now the unreached one is released and the limit named.
  GapCaseOptions options;
  options.offsets = true;
  options.sample_time = 0.05;
  const GapCase c = SeededBenchCase(52, 18, {EffectKind::kInputSaturation}, options);
  const GapReport report = DiagnoseOnOneThread(c);
  const CandidateFit& limit = Ranked(report, EffectKind::kInputSaturation);
  std::printf("barely reached limits: verdict %s; the limit's note: %s\n", report.verdict.effect.c_str(),
              limit.note.c_str());
  EXPECT_EQ(report.verdict.effect, "input_saturation");
  EXPECT_NE(limit.note.find("upper limit not reached"), std::string::npos);
}

TEST(GapBadRecordTest, MostlyClippedRecordGetsAVerdictNotACrash) {
  // An actuator offset so large that the input saturation clips ~90 % of the record.
  GapCase c = LevelsCase(EffectKind::kInputSaturation, 331);
  const double u_max = c.estimation.u.cwiseAbs().maxCoeff();
  GapRecord est = c.estimation, val = c.validation;
  for (GapRecord* r : {&est, &val}) r->u.array() += 3 * u_max;
  Effect sat{EffectKind::kInputSaturation, {-u_max, 3.5 * u_max}};
  std::mt19937_64 rng(332);
  for (GapRecord* r : {&est, &val}) r->y = SimulateRig(c.real, sat, r->u, r->sample_time, 0.01, rng);
  GapReport report;
  ASSERT_NO_THROW(report = DiagnoseGap(c.sim, {est}, {val}));
  std::printf("mostly clipped: verdict %s; %s\n", report.verdict.effect.c_str(), report.verdict.explanation.c_str());
  EXPECT_FALSE(report.verdict.effect.empty());
  EXPECT_TRUE(std::isfinite(report.verdict.nrmse_after));
}

TEST(GapBadRecordTest, IntegratingSimModelOnADriftingRecordIsFittedWithoutDrift) {
  // G0 = 2/s, a biased input: the level ends far from where it started.
  TransferFunction sim;
  sim.num = Eigen::VectorXd::Constant(1, 2.0);
  sim.den = Eigen::Vector2d(1.0, 0.0);
  GapCase shape = LevelsCase(EffectKind::kNone, 341);
  std::mt19937_64 rng(342);
  GapRecord est = shape.estimation, val = shape.validation;
  for (GapRecord* r : {&est, &val}) {
    r->u.array() += 0.2 * Rms(r->u);
    r->y = SimulateRig(sim, Effect{}, r->u, r->sample_time, 0.0, rng);
    std::normal_distribution<double> noise(0.0, 0.01 * Rms(r->y.array() - r->y.mean()));
    for (long k = 0; k < r->y.size(); ++k) r->y(k) += noise(rng);
  }
  ASSERT_GT(std::abs(est.y(est.y.size() - 1) - est.y(0)), Rms(est.y.array() - est.y.mean()));
  GapReport report;
  ASSERT_NO_THROW(report = DiagnoseGap(sim, {est}, {val}));
  std::printf("drifting integrator: verdict %s, fit %s\n", report.verdict.effect.c_str(),
              report.verdict.fit_scheme.c_str());
  EXPECT_EQ(report.verdict.fit_scheme, "multiple_shooting");
  EXPECT_EQ(report.verdict.effect, "none");
}

TEST(GapBadRecordTest, TwoRecordsAtDifferentOperatingPointsAreNotAnEffect) {
  GapCase a = LevelsCase(EffectKind::kNone, 351), b = LevelsCase(EffectKind::kNone, 351);
  b.estimation.y.array() += 3 * Rms(b.estimation.y);  // the second record at another level
  a.estimation.y.array() -= 1 * Rms(a.estimation.y);
  GapReport report;
  ASSERT_NO_THROW(report = DiagnoseGap(a.sim, {a.estimation, b.estimation}, {a.validation}));
  std::printf("two operating points: verdict %s, output offsets %.3f %.3f\n", report.verdict.effect.c_str(),
              report.verdict.nuisance.output_offset.at(0), report.verdict.nuisance.output_offset.at(1));
  EXPECT_EQ(report.verdict.effect, "none");
  EXPECT_EQ(report.verdict.nuisance.output_offset.size(), 2u);
}

// A sensor that drifts: a ramp of 15 noise sigmas over each record (up on one, down on the
// other), on a stable plant. It does not follow the input; the output offset alone leaves it in
// the residual, where a static candidate that correlates with it by chance, or a higher-order
// part's free response, took it (docs/gap.md, stop 27: 2 of 5 `none` cases right, delays
// `unmodelled_dynamics`). A ramp per record beside the offset is a nuisance parameter.
struct DriftCase {
  EffectKind truth;
  uint64_t seed;
};

class GapDriftTest : public ::testing::TestWithParam<DriftCase> {};

TEST_P(GapDriftTest, ASensorDriftIsNuisanceNotAnEffect) {
  GapCase c = LevelsCase(GetParam().truth, GetParam().seed, 4000);
  const double ts = c.estimation.sample_time, n = c.estimation.y.size();
  const double rise = 15 * c.noise_sigma;  // over the record
  for (long k = 0; k < c.estimation.y.size(); ++k) c.estimation.y(k) += rise * k / (n - 1);
  for (long k = 0; k < c.validation.y.size(); ++k) c.validation.y(k) -= rise * k / (n - 1);
  const double slope = rise / ((n - 1) * ts);
  GapOptions options;
  options.second_effect = true;
  const GapReport report = DiagnoseGap(c.sim, {c.estimation}, {c.validation}, options);
  const GapVerdict& v = report.verdict;
  std::printf("drift: truth %-17s verdict %-20s [%zu effects] NRMSE %.4f -> %.4f floor %.4f, drift %.4g (true %.4g)\n",
              EffectName(c.truth), v.effect.c_str(), v.effects.size(), v.nrmse_before, v.nrmse_after,
              v.noise_nrmse, v.nuisance.output_drift.empty() ? NAN : v.nuisance.output_drift[0], slope);
  EXPECT_EQ(v.effect, EffectName(c.truth));
  EXPECT_LE(v.effects.size(), 1u);
  EXPECT_LT(v.nrmse_after, 1.5 * v.noise_nrmse) << "the drift is left in the residual";
  ASSERT_EQ(v.nuisance.output_drift.size(), 1u);
  EXPECT_NEAR(v.nuisance.output_drift[0], slope, 0.2 * slope);
}

INSTANTIATE_TEST_SUITE_P(Rigs, GapDriftTest,
                         ::testing::Values(DriftCase{EffectKind::kNone, 361}, DriftCase{EffectKind::kNone, 362},
                                           DriftCase{EffectKind::kTimeDelay, 363},
                                           DriftCase{EffectKind::kCoulombFriction, 364}),
                         [](const auto& info) {
                           return std::string(EffectName(info.param.truth)) + "_" + std::to_string(info.param.seed);
                         });

// An output clip read through a drifting sensor with offsets (`idrig gap bench --cases 39 --seed
// 7403 --offsets --add-drift 3 --excitation noise`, case 10): the drift (after the clip) rises
// over the estimation record and falls over the validation record, so the clipped readings sit
// 3 noise sigmas apart on the two records. With the drift's ramp centred on each record the
// limits (in the measured output's coordinates, the offset inside the clip) fitted the
// estimation record and missed the validation one: the clip alone left twice the noise variance
// there, and a sensor map beside it (its offset after the clip) was named. The ramp behind clips
// now starts at zero with the record.
TEST(GapClipDriftTest, AClipReadThroughADriftingSensorIsTheClipAlone) {
  GapCaseOptions options;
  options.offsets = true;
  options.drift = 3;
  options.excitation = "noise";
  const GapCase c = SeededBenchCase(7403, 10, {EffectKind::kOutputSaturation}, options);
  const GapReport report = DiagnoseOnOneThread(c);
  const GapVerdict& v = report.verdict;
  std::printf("clip behind a drifting sensor: verdict %s (%zu effects), NRMSE %.4f -> %.4f floor %.4f\n",
              v.effect.c_str(), v.effects.size(), v.nrmse_before, v.nrmse_after, v.noise_nrmse);
  EXPECT_EQ(v.effect, "output_saturation");
  EXPECT_EQ(v.effects.size(), 1u);
  EXPECT_LT(v.nrmse_after, 1.1 * v.noise_nrmse);
}

// A sensor re-zeroed part way through both records (8 noise sigmas at sample 1500 of the
// estimation record, −8 at 2500 of the validation record). Against G0 a friction case's step is
// smaller than what the missing friction leaves; the diagnosed model's residual shows it, and
// with the step a level of its own (the simulation running through it: the mass's stick
// position carries over) the friction is named at the floor. Without it the validation NRMSE stays
// twice the floor (docs/gap.md, stop 28).
class GapSensorStepTest : public ::testing::TestWithParam<DriftCase> {};

TEST_P(GapSensorStepTest, AReZeroedSensorIsALevelOfItsOwnNotAnEffect) {
  GapCase c = LevelsCase(GetParam().truth, GetParam().seed, 4000);
  const double step = 8 * c.noise_sigma;
  c.estimation.y.tail(2500).array() += step;
  c.validation.y.tail(1500).array() -= step;
  const GapReport report = DiagnoseGap(c.sim, {c.estimation}, {c.validation});
  const GapVerdict& v = report.verdict;
  std::printf("sensor step: truth %-17s verdict %-20s [%zu effects] NRMSE %.4f -> %.4f floor %.4f, %zu steps\n",
              EffectName(c.truth), v.effect.c_str(), v.effects.size(), v.nrmse_before, v.nrmse_after, v.noise_nrmse,
              report.sensor_steps.size());
  EXPECT_EQ(v.effect, EffectName(c.truth));
  ASSERT_EQ(report.sensor_steps.size(), 2u);
  for (const GapSensorStep& s : report.sensor_steps) {
    const bool est = s.records == "estimation";
    EXPECT_NEAR(s.sample, est ? 1500 : 2500, 1);
    EXPECT_NEAR(s.size, est ? step : -step, 2.5 * c.noise_sigma);
  }
  EXPECT_LT(v.nrmse_after, 1.3 * v.noise_nrmse) << "the step is left in the residual";
}

INSTANTIATE_TEST_SUITE_P(Rigs, GapSensorStepTest,
                         ::testing::Values(DriftCase{EffectKind::kNone, 371},
                                           DriftCase{EffectKind::kCoulombFriction, 364},
                                           DriftCase{EffectKind::kTimeDelay, 363}),
                         [](const auto& info) {
                           return std::string(EffectName(info.param.truth)) + "_" + std::to_string(info.param.seed);
                         });

}  // namespace
}  // namespace idrig
