// Even/odd detection lines on periodic odd multisines (gap_noise.h, AnalyseDetectionLines):
// a linear rig shows noise only on them and its BLA is G0; an odd nonlinearity (cubic spring)
// lights the odd detection lines and not the even ones; an even one (a y² sensor term) the
// even lines. Reference: the symmetry argument of Pintelon and Schoukens §3.5 (odd-degree
// terms of an odd-line input produce odd lines only).
#include <gtest/gtest.h>

#include <cmath>

#include "core/numeric/gap/gap_bench.h"
#include "core/numeric/gap/gap_noise.h"
#include "core/numeric/signal/excitation.h"

namespace idrig {
namespace {

TransferFunction Plant() {
  TransferFunction plant;
  plant.num = Eigen::VectorXd::Constant(1, 25.0);
  plant.den = Eigen::Vector3d(1.0, 4.0, 25.0);
  return plant;
}

GapRecord Periodic(const Effect& effect, MultisineLineSet set, int periods = 6, double sigma = 0.005) {
  ExcitationSpec spec;
  spec.kind = ExcitationKind::kMultisine;
  spec.base_frequency_hz = 100.0 / 512;
  for (int k = 1; k <= 60; ++k) spec.lines.push_back(k);
  spec.line_set = set;
  spec.phase_rule = MultisinePhase::kRandom;
  spec.scale = MultisineScale::kRms;
  spec.amplitude = 1;
  spec.seed = 3;
  GapRecord r;
  r.sample_time = 0.01;
  r.u = GenerateExcitation(spec, 100.0, 512).replicate(periods, 1);
  std::mt19937_64 rng(5);
  r.y = SimulateRig(Plant(), effect, r.u, r.sample_time, sigma, rng);
  return r;
}

TEST(GapLinesTest, LinearRigShowsNoiseOnlyAndItsBlaIsG0) {
  const TransferFunction g0 = Plant();
  const DetectionLines d = AnalyseDetectionLines({Periodic(Effect{}, MultisineLineSet::kOddOdd)}, &g0);
  ASSERT_TRUE(d.available) << d.reason;
  EXPECT_EQ(d.period_samples, 512);
  EXPECT_GE(d.periods, 5);
  EXPECT_EQ(d.excited, 15);  // lines 1, 5, …, 57
  EXPECT_GT(d.odd_lines, 10);
  EXPECT_GT(d.even_lines, 25);
  EXPECT_FALSE(d.odd_distortion);
  EXPECT_FALSE(d.even_distortion);
  EXPECT_LT(std::abs(d.odd_to_noise_db), 3.0);   // noise over noise: 0 dB within its scatter
  EXPECT_LT(std::abs(d.even_to_noise_db), 3.0);
  // The BLA is G0 (sampled with a hold) within its noise on every excited line.
  StateSpace zoh = DiscretizeZoh(ToStateSpace(g0), 0.01);
  for (const auto& line : d.lines) {
    if (line.kind != "excited") continue;
    const std::complex<double> g = FrequencyResponse(zoh, 2 * M_PI * line.f_hz)(0, 0);
    EXPECT_LT(std::abs(std::polar(line.bla_magnitude, line.bla_phase) - g), 4.5 * line.bla_noise_std + 1e-3 * std::abs(g))
        << "line " << line.line;
  }
  EXPECT_LT(d.bla_vs_sim, 0.1);
}

TEST(GapLinesTest, ACubicSpringLightsTheOddLinesOnly) {
  const TransferFunction g0 = Plant();
  const DetectionLines d = AnalyseDetectionLines(
      {Periodic(Effect{EffectKind::kCubicStiffness, {10.0}}, MultisineLineSet::kOddOdd)}, &g0);
  ASSERT_TRUE(d.available) << d.reason;
  EXPECT_TRUE(d.odd_distortion);
  EXPECT_GT(d.odd_to_noise_db, 10.0);
  EXPECT_FALSE(d.even_distortion);
  EXPECT_LT(d.even_to_noise_db, 3.0);
  // The BLA's nonlinear 1σ is known at the excited lines next to odd detection lines.
  int with_distortion = 0;
  for (const auto& line : d.lines)
    if (line.kind == "excited" && std::isfinite(line.bla_distortion_std) && line.bla_distortion_std > line.bla_noise_std)
      ++with_distortion;
  EXPECT_GT(with_distortion, 3);
}

TEST(GapLinesTest, AnEvenSensorTermLightsTheEvenLines) {
  const DetectionLines d = AnalyseDetectionLines(
      {Periodic(Effect{EffectKind::kSensorNonlinearity, {1.0, 0.3, 0.0, 0.0}}, MultisineLineSet::kOdd)},
      nullptr);
  ASSERT_TRUE(d.available) << d.reason;
  EXPECT_TRUE(d.odd_out_of_band);  // every odd line is excited: odd lines above the band used
  EXPECT_TRUE(d.even_distortion);
  EXPECT_GT(d.even_to_noise_db, 10.0);
  EXPECT_FALSE(d.odd_distortion);
}

TEST(GapLinesTest, RecordsThatDoNotQualifySayWhy) {
  EXPECT_FALSE(AnalyseDetectionLines({Periodic(Effect{}, MultisineLineSet::kAll)}, nullptr).available);
  EXPECT_NE(AnalyseDetectionLines({Periodic(Effect{}, MultisineLineSet::kAll)}, nullptr).reason.find("even lines"),
            std::string::npos);
  std::mt19937_64 rng(2);
  GapCaseOptions options;
  options.samples = 1000;
  const GapCase c = MakeGapCase(EffectKind::kNone, rng, options);
  const DetectionLines d = AnalyseDetectionLines({c.estimation}, nullptr);
  EXPECT_FALSE(d.available);
  EXPECT_NE(d.reason.find("periodic"), std::string::npos) << d.reason;
}

}  // namespace
}  // namespace idrig
