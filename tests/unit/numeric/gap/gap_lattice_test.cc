// The output lattice (gap_noise.h, DetectOutputLattice): an ADC's readings sit on offset + k·q
// whatever the noise before it; the lattice of numbers printed with few digits sits far below
// the noise and is not quantisation. References: the construction of the records.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "core/numeric/gap/gap_bench.h"
#include "core/numeric/gap/gap_diagnosis.h"
#include "core/numeric/gap/gap_internal.h"
#include "core/numeric/gap/gap_noise.h"

namespace idrig {
namespace {

TEST(GapLatticeTest, FindsTheStepAndOffsetOfAnAdcEvenWithNoiseAsLargeAsTheStep) {
  for (double snr : {30.0, 20.0}) {
    std::mt19937_64 rng(9);
    GapCaseOptions options;
    options.samples = 2000;
    options.offsets = true;
    options.snr_db = snr;
    const GapCase c = MakeGapCase(EffectKind::kOutputQuantization, rng, options);
    const double q = c.effect.params[0];
    double strength = 0;
    const double step = gap_detail::QuantisationStep({c.estimation}, &strength);
    EXPECT_NEAR(step, q, 0.002 * q) << "SNR " << snr;
    double strength_2 = 0;  // the grid scored on two threads: the same step to the bit
    EXPECT_EQ(gap_detail::QuantisationStep({c.estimation}, &strength_2, 2), step);
    EXPECT_EQ(strength_2, strength);
    const NoiseFloor floor = EstimateNoiseFloor({c.estimation}, {c.validation});
    const OutputLattice l = DetectOutputLattice({c.estimation, c.validation}, step, floor.sigma);
    EXPECT_TRUE(l.lattice) << l.reason;
    EXPECT_TRUE(l.detected) << l.reason;
    EXPECT_GT(l.on_lattice, 0.99);
    // The sensor offset, modulo the step, is the lattice's offset.
    const double expected = std::fmod(std::fmod(c.output_offset, q) + q, q);
    const double diff = std::remainder(l.offset - expected, q);
    EXPECT_LT(std::abs(diff), 0.02 * q) << "offset " << l.offset << " expected " << expected;
  }
}

TEST(GapLatticeTest, OnAnOutputHeldAtAFewLevelsTheStepIsNotAQLinedUpWithHalfOfThem) {
  // Eight levels held for the sample counts of `idrig gap bench --cases 54 --seed 972 --offsets
  // --combos 1 --pairs any --integrating --excitation levels`, case 50 (a slow position through
  // a quantiser of step 0.806): a q a fifth larger lines up about half of the samples (R ≈ 0.53),
  // which the rule "the largest local maximum within half of the best" took as the step.
  const double q = 0.806, offset = 0.317;
  const int counts[8] = {289, 1438, 755, 159, 302, 272, 375, 410};
  GapRecord r;
  long n = 0;
  for (int c : counts) n += c;
  r.y.resize(n);
  r.u = Eigen::VectorXd::Zero(n);
  r.sample_time = 0.01;
  long k = 0;
  for (int level = 0; level < 8; ++level)
    for (int i = 0; i < counts[level]; ++i) r.y(k++) = offset + level * q;
  double strength = 0;
  const double step = gap_detail::QuantisationStep({r}, &strength);
  EXPECT_NEAR(step, q, 1e-3 * q);
  EXPECT_GT(strength, 0.99);
  EXPECT_TRUE(DetectOutputLattice({r}, step, 0.05).lattice);
}

TEST(GapLatticeTest, ContinuousDataPrintedWithFewDigitsIsNotQuantisation) {
  std::mt19937_64 rng(4);
  GapCaseOptions options;
  options.samples = 2000;
  GapCase c = MakeGapCase(EffectKind::kNone, rng, options);
  // Printed with 4 decimals: a lattice of 1e-4, a hundredth of the noise or less.
  ASSERT_GT(c.noise_sigma, 0.01 * 1e2 * 1e-4);
  for (GapRecord* r : {&c.estimation, &c.validation})
    for (long k = 0; k < r->y.size(); ++k) r->y(k) = std::round(r->y(k) * 1e4) / 1e4;
  const NoiseFloor floor = EstimateNoiseFloor({c.estimation}, {c.validation});
  const OutputLattice printed = DetectOutputLattice({c.estimation, c.validation}, 1e-4, floor.sigma);
  EXPECT_TRUE(printed.lattice);
  EXPECT_FALSE(printed.detected) << printed.reason;
  EXPECT_NE(printed.reason.find("resolution of the numbers"), std::string::npos) << printed.reason;
  // The search itself does not find a coarse lattice in such data.
  double strength = 0;
  const double step = gap_detail::QuantisationStep({c.estimation}, &strength);
  const OutputLattice found = DetectOutputLattice({c.estimation, c.validation}, step, floor.sigma);
  EXPECT_FALSE(found.lattice) << found.reason;
  EXPECT_FALSE(found.detected);
}

TEST(GapLatticeTest, NoStepNoLattice) {
  GapRecord r;
  r.u = Eigen::VectorXd::LinSpaced(100, 0, 1);
  r.y = r.u;
  r.sample_time = 0.01;
  EXPECT_FALSE(DetectOutputLattice({r}, 0.0, 0.1).lattice);
}

TEST(GapLatticeTest, SmoothedStaircaseIsTheConditionalMeanOfTheRoundedNoisyValue) {
  // Reference: the definition, Σ_level level·P(round((y + n)/q) = level) with n ~ N(0, s²),
  // summed over ±60 levels with erfc (the predictor's fast forms are a Fourier series and a
  // two-boundary sum).
  const double q = 0.37;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uniform(-4.0, 4.0);
  Eigen::VectorXd y(400);
  for (long k = 0; k < y.size(); ++k) y(k) = uniform(rng);
  y(0) = 0.5 * q, y(1) = -1.5 * q, y(2) = 0.0;  // on a boundary, and on a level
  for (double sigma : {1e-4, 0.01, 0.05, 0.0999, 0.1, 0.3, 1.0, 3.0}) {
    const double s = sigma * q;
    Eigen::VectorXd fast = y;
    gap_detail::SmoothedStaircase(fast, q, s);
    for (long k = 0; k < y.size(); ++k) {
      const double m = std::round(y(k) / q);
      double mean = 0;
      for (int j = -60; j <= 60; ++j) {
        const double level = m + j;
        mean += level * 0.5 * (std::erfc(-((level + 0.5) * q - y(k)) / (s * M_SQRT2)) -
                               std::erfc(-((level - 0.5) * q - y(k)) / (s * M_SQRT2)));
      }
      ASSERT_NEAR(fast(k), q * mean, 1e-9 * q) << "sigma " << sigma << ", y " << y(k);
    }
  }
}

TEST(GapLatticeTest, QuantisationIsNamedWhereverASensorOffsetPutsTheLattice) {
  // A sensor offset after the ADC moves the lattice to offset + k·q. The quantisation
  // candidate's staircase must sit where the samples do, not at multiples of q: the same
  // records shifted by a third and a half of a step are still quantised.
  std::mt19937_64 rng(12);
  GapCaseOptions options;
  options.samples = 2000;
  options.excitation = "levels";
  options.snr_db = 40;  // noise before the rounding well below q: the staircase is sharp
  const GapCase c = MakeGapCase(EffectKind::kOutputQuantization, rng, options);
  const double q = c.effect.params[0];
  ASSERT_LT(c.noise_sigma, 0.2 * q);
  for (double shift : {q / 3, q / 2}) {
    GapRecord est = c.estimation, val = c.validation;
    est.y.array() += shift;
    val.y.array() += shift;
    const GapReport report = DiagnoseGap(c.sim, {est}, {val});
    EXPECT_EQ(report.verdict.effect, "output_quantization") << "shift " << shift / q << " q";
    // And the candidate itself explains the rounding: a staircase in the wrong place is no
    // better than the linear refit (its smoothing grows until it is a straight line).
    double quantised = NAN, linear = NAN;
    for (const CandidateFit& f : report.ranking) {
      if (f.effect.kind == EffectKind::kOutputQuantization) quantised = f.validation_mse;
      if (f.effect.kind == EffectKind::kParameterMismatch) linear = f.validation_mse;
    }
    std::printf("shift %.3f q: validation MSE quantisation %.3g, linear refit %.3g\n", shift / q, quantised, linear);
    EXPECT_LT(quantised, 0.7 * linear) << "shift " << shift / q << " q";
  }
}

}  // namespace
}  // namespace idrig
