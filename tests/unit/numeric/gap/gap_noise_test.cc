// The noise floor without candidates (gap_noise.h) on rigs whose noise σ is known by
// construction: periodic excitation (variance across periods) and non-periodic (de-biased ARX
// one-step error), with nonlinear effects that a linear predictor does not capture.
#include "core/numeric/gap/gap_noise.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/numeric/gap/gap_bench.h"
#include "core/numeric/gap/gap_diagnosis.h"
#include "core/numeric/signal/excitation.h"

namespace idrig {
namespace {

TEST(GapNoiseTest, FindsThePeriodOfARepeatedSignalAndNoneInARandomOne) {
  ExcitationSpec spec;
  spec.kind = ExcitationKind::kPrbs;
  spec.register_bits = 7;  // 127 bits
  spec.clock_hz = 25;      // 4 samples per bit at 100 Hz: period 508 samples
  spec.amplitude = 1;
  const Eigen::VectorXd prbs = GenerateExcitation(spec, 100.0, 508 * 4 + 100);
  const Periodicity p = FindPeriod(prbs);
  EXPECT_EQ(p.period, 508);
  EXPECT_EQ(p.periods, 4);
  spec.kind = ExcitationKind::kRandomBinary;
  EXPECT_EQ(FindPeriod(GenerateExcitation(spec, 100.0, 2000)).period, 0);
  // A slow ramp-like signal is nearly equal to itself shifted by a few samples: not periodic.
  Eigen::VectorXd slow(3000);
  for (long k = 0; k < slow.size(); ++k) slow(k) = std::sin(2 * M_PI * k / 7000.0);
  EXPECT_EQ(FindPeriod(slow).period, 0);
}

TEST(GapNoiseTest, VarianceAcrossPeriodsGivesTheNoiseOfANonlinearRig) {
  TransferFunction plant;
  plant.num = Eigen::VectorXd::Constant(1, 25.0);
  plant.den = Eigen::Vector3d(1.0, 4.0, 25.0);
  ExcitationSpec spec;
  spec.kind = ExcitationKind::kMultisine;
  spec.base_frequency_hz = 100.0 / 400;
  for (int k = 1; k <= 20; ++k) spec.lines.push_back(k);
  spec.line_set = MultisineLineSet::kOdd;
  spec.phase_rule = MultisinePhase::kRandom;
  spec.scale = MultisineScale::kRms;
  spec.amplitude = 1;
  const Eigen::VectorXd period = GenerateExcitation(spec, 100.0, 400);
  GapRecord r;
  r.sample_time = 0.01;
  r.u = period.replicate(8, 1);
  const double sigma = 0.02;
  std::mt19937_64 rng(4);
  r.y = SimulateRig(plant, Effect{EffectKind::kCubicStiffness, {10.0}}, r.u, r.sample_time, sigma, rng);
  const NoiseFloor f = EstimateNoiseFloor({r}, {r});
  EXPECT_EQ(f.method, "periods");
  EXPECT_EQ(f.period, 400);
  EXPECT_EQ(f.periods, 8);
  // About 2 × 400 × 6 degrees of freedom: the relative 1σ of σ̂ is about 1/√9600 ≈ 1 %.
  EXPECT_NEAR(f.sigma, sigma, 0.05 * sigma);
}

// An integrating rig (position from force) under a periodic odd multisine with an actuator
// offset: the output ramps by the integrated offset, so its periods do not repeat although the
// input's do.
GapRecord RampingRecord(const Effect& effect, double sigma, uint64_t seed) {
  TransferFunction plant;  // 4/(s(s + 4))
  plant.num = Eigen::VectorXd::Constant(1, 4.0);
  plant.den = Eigen::Vector3d(1.0, 4.0, 0.0);
  ExcitationSpec spec;
  spec.kind = ExcitationKind::kMultisine;
  spec.base_frequency_hz = 100.0 / 800;
  for (int k = 1; k <= 15; ++k) spec.lines.push_back(k);
  spec.line_set = MultisineLineSet::kOdd;
  spec.phase_rule = MultisinePhase::kRandom;
  spec.scale = MultisineScale::kRms;
  spec.amplitude = 1;
  spec.seed = seed;
  GapRecord r;
  r.sample_time = 0.01;
  r.u = GenerateExcitation(spec, 100.0, 800).replicate(5, 1);
  std::mt19937_64 rng(seed);
  r.y = SimulateRig(plant, {effect}, r.u, r.sample_time, sigma, rng, /*input_offset=*/0.1,
                    /*output_offset=*/2.0);
  return r;
}

TEST(GapNoiseTest, ARampFromAnIntegratedOffsetIsNotNoiseNorAnEvenNonlinearity) {
  const double sigma = 0.02;
  // Linear: the ramp shifts each period by a constant (0.1 × 8 s = 0.8 per period here). Without
  // it the spread across periods reads ~0.5 (the ramp), and its sawtooth leaks into every line.
  const GapRecord linear = RampingRecord(Effect{}, sigma, 1);
  const NoiseFloor f = EstimateNoiseFloor({linear}, {linear});
  EXPECT_GT(f.drifting_records, 0);
  EXPECT_GT(f.sigma, 0.95 * sigma);
  EXPECT_LT(f.sigma, 1.10 * sigma);
  const DetectionLines d = AnalyseDetectionLines({linear}, nullptr);
  ASSERT_TRUE(d.available) << d.reason;
  EXPECT_FALSE(d.even_distortion) << d.even_to_noise_db << " dB";
  EXPECT_FALSE(d.odd_distortion) << d.odd_to_noise_db << " dB";
  // An output clip that the ramp walks into answers each period differently: not noise either.
  GapRecord clipped = RampingRecord(Effect{EffectKind::kOutputSaturation, {-0.5, 2.5}}, sigma, 2);
  const NoiseFloor g = EstimateNoiseFloor({clipped}, {clipped});
  EXPECT_EQ(g.method, "arx_prediction");
  EXPECT_EQ(g.drifting_records, 2);
  EXPECT_LT(g.sigma, 1.2 * sigma);
  // A periodic output keeps the periods floor and counts no drift.
  TransferFunction stable;
  stable.num = Eigen::VectorXd::Constant(1, 16.0);
  stable.den = Eigen::Vector3d(1.0, 4.0, 16.0);
  GapRecord periodic = linear;
  std::mt19937_64 rng(3);
  periodic.y = SimulateRig(stable, {Effect{}}, periodic.u, periodic.sample_time, sigma, rng, 0.1, 2.0);
  const NoiseFloor h = EstimateNoiseFloor({periodic}, {periodic});
  EXPECT_EQ(h.method, "periods");
  EXPECT_EQ(h.drifting_records, 0);
  EXPECT_NEAR(h.sigma, sigma, 0.05 * sigma);
}

TEST(GapNoiseTest, ArxPredictionBoundsTheNoiseFromAboveAndTightly) {
  // Non-periodic excitations, effects a linear predictor misses: σ̂ ≥ σ (up to its own scatter)
  // and within 10 % of it, whatever the effect.
  for (EffectKind kind : {EffectKind::kNone, EffectKind::kCubicStiffness, EffectKind::kInputSaturation,
                          EffectKind::kSensorNonlinearity, EffectKind::kBacklash}) {
    for (uint64_t seed = 1; seed <= 2; ++seed) {
      std::mt19937_64 rng(seed);
      GapCaseOptions options;
      options.samples = 3000;
      options.offsets = seed == 2;
      const GapCase c = MakeGapCase(kind, rng, options);
      const NoiseFloor f = EstimateNoiseFloor({c.estimation}, {c.validation});
      EXPECT_EQ(f.method, "arx_prediction");
      EXPECT_GT(f.sigma, 0.95 * c.noise_sigma) << EffectName(kind) << " seed " << seed;
      EXPECT_LT(f.sigma, 1.10 * c.noise_sigma) << EffectName(kind) << " seed " << seed;
    }
  }
}

TEST(GapNoiseTest, TheDiagnosisShrinksAgainstTheIndependentFloor) {
  std::mt19937_64 rng(12);
  GapCaseOptions options;
  options.samples = 2500;
  options.excitation = "levels";
  const GapCase c = MakeGapCase(EffectKind::kCubicStiffness, rng, options);
  GapOptions gap;
  gap.threads = 1;
  const GapReport report = DiagnoseGap(c.sim, {c.estimation}, {c.validation}, gap);
  const GapVerdict& v = report.verdict;
  EXPECT_EQ(report.where.noise_floor.method, "arx_prediction");
  EXPECT_NEAR(report.where.noise_floor.sigma, c.noise_sigma, 0.1 * c.noise_sigma);
  EXPECT_DOUBLE_EQ(v.noise_nrmse, report.where.noise_nrmse);
  EXPECT_DOUBLE_EQ(v.remaining_gap_to_noise, v.nrmse_after - v.noise_nrmse);
  EXPECT_EQ(v.below_noise_floor, v.nrmse_after < v.noise_nrmse);
  EXPECT_LE(v.shrink, 1.0);
  // The right effect leaves about the noise: what remains is small against the gap it closed.
  EXPECT_LT(std::abs(v.remaining_gap_to_noise), 0.1 * (v.nrmse_before - v.noise_nrmse));
}

TEST(GapNoiseTest, ShrinkIsZeroWhenThereIsNothingToExplainAndFlaggedBelowTheFloor) {
  GapVerdict v;
  v.nrmse_before = 0.05;
  v.nrmse_after = 0.05;
  ApplyNoiseFloor(0.06, v);
  EXPECT_EQ(v.shrink, 0.0);
  EXPECT_TRUE(v.below_noise_floor);
  v.nrmse_before = 0.2;
  v.nrmse_after = 0.04;
  ApplyNoiseFloor(0.05, v);
  EXPECT_DOUBLE_EQ(v.shrink, 1.0);  // not 0.16 / 0.15: the model shows 0.16 was explainable
  EXPECT_TRUE(v.below_noise_floor);
  EXPECT_NEAR(v.remaining_gap_to_noise, -0.01, 1e-12);  // how far below, said here
  ApplyNoiseFloor(0.02, v);
  EXPECT_NEAR(v.shrink, 0.16 / 0.18, 1e-12);
  EXPECT_FALSE(v.below_noise_floor);
  EXPECT_NEAR(v.remaining_gap_to_noise, 0.02, 1e-12);
}

TEST(GapNoiseTest, RecordsTooShortForAnyPredictorAreNamed) {
  GapRecord r;
  r.sample_time = 0.01;
  r.u = Eigen::VectorXd::LinSpaced(60, 0, 1).array().sin();
  r.y = r.u;
  try {
    EstimateNoiseFloor({r}, {r});
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("too short"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace idrig
