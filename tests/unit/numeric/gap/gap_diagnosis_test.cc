// The gap diagnosis on generated rigs whose withheld effect is known by construction (the
// generator simulates the rig 4× finer than the diagnosis for the feedback effects), plus the
// bad-input cases. The full blind benchmark is `idrig gap bench` (docs/gap.md), not a test.
#include "core/numeric/gap/gap_diagnosis.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "core/numeric/gap/gap_bench.h"

namespace idrig {
namespace {

GapCase Case(EffectKind truth, uint64_t seed, const std::string& excitation = "levels") {
  // Draw until the generator picks the requested excitation (it chooses one per case).
  for (uint64_t s = seed;; ++s) {
    std::mt19937_64 rng(s);
    GapCaseOptions options;
    options.samples = 2500;
    GapCase c = MakeGapCase(truth, rng, options);
    if (c.excitation == excitation) return c;
  }
}

struct Expectation {
  EffectKind truth;
  uint64_t seed;
};

class DiagnosisTest : public ::testing::TestWithParam<Expectation> {};

TEST_P(DiagnosisTest, FindsTheWithheldEffectAndClosesTheGapOnValidationData) {
  const GapCase c = Case(GetParam().truth, GetParam().seed);
  const GapReport report = DiagnoseGap(c.sim, {c.estimation}, {c.validation});
  const GapVerdict& v = report.verdict;
  std::printf("truth %-22s verdict %-22s confidence %.3f NRMSE %.4f -> %.4f shrink %.3f\n",
              EffectName(c.truth), v.effect.c_str(), v.confidence, v.nrmse_before, v.nrmse_after,
              v.shrink);
  if (std::getenv("GAP_DEBUG")) {
    for (const auto& r : report.ranking)
      std::printf("  %-22s nrmse %.4f est_mse %.3g bic %.1f LR %.1f/%.1f sig %.2f elig %d du %.3g\n",
                  EffectName(r.effect.kind), r.nrmse_after, r.estimation_mse, r.bic, r.likelihood_ratio,
                  r.lr_threshold, r.signature, r.eligible, r.input_offset);
    for (const auto& n : report.notes) std::printf("  note: %s\n", n.c_str());
  }
  EXPECT_EQ(v.effect, EffectName(c.truth));
  if (c.truth != EffectKind::kNone) {
    EXPECT_GE(v.shrink, 0.8);
    EXPECT_LT(v.nrmse_after, v.nrmse_before);
    EXPECT_TRUE(report.where.gap_significant);
  }
  EXPECT_GT(v.confidence, 0.5);
  ASSERT_EQ(report.ranking.size(), AllEffects().size());
  EXPECT_EQ(report.ranking.front().effect.kind == c.truth, true);
}

INSTANTIATE_TEST_SUITE_P(
    Effects, DiagnosisTest,
    ::testing::Values(Expectation{EffectKind::kNone, 11}, Expectation{EffectKind::kParameterMismatch, 12},
                      Expectation{EffectKind::kActuatorLag, 13}, Expectation{EffectKind::kDeadZone, 14},
                      Expectation{EffectKind::kCoulombFriction, 15},
                      Expectation{EffectKind::kOutputQuantization, 16}),
    [](const auto& info) { return std::string(EffectName(info.param.truth)); });

TEST(GapDiagnosisTest, RecoversTheDeadZoneWidthWithinItsUncertainty) {
  const GapCase c = Case(EffectKind::kDeadZone, 21);
  const GapReport report = DiagnoseGap(c.sim, {c.estimation}, {c.validation});
  ASSERT_EQ(report.verdict.effect, "dead_zone");
  const double truth = c.effect.params[0], fitted = report.verdict.params.params[0];
  const double sigma = report.verdict.param_std[0];
  std::printf("dead zone: true %.4f, fitted %.4f ± %.4f\n", truth, fitted, sigma);
  EXPECT_NEAR(fitted, truth, 0.05 * truth);
  EXPECT_TRUE(std::isfinite(sigma));
  EXPECT_GT(sigma, 0.0);
}

TEST(GapDiagnosisTest, BinaryInputCannotSeparateInputNonlinearityFromGain) {
  // On a two-valued input a dead zone is a gain: the verdict says so instead of guessing.
  const GapCase c = Case(EffectKind::kDeadZone, 31, "rbs");
  const GapReport report = DiagnoseGap(c.sim, {c.estimation}, {c.validation});
  EXPECT_EQ(report.verdict.effect, "ambiguous");
  ASSERT_FALSE(report.verdict.tied.empty());
  bool names_dead_zone = false;
  for (const auto& t : report.verdict.tied) names_dead_zone |= t == "dead_zone";
  EXPECT_TRUE(names_dead_zone);
  ASSERT_FALSE(report.notes.empty());
  EXPECT_NE(report.notes.back().find("two values"), std::string::npos);
}

TEST(GapDiagnosisTest, OneRecordIsSplitInTimeAndSaysSo) {
  const GapCase c = Case(EffectKind::kTimeDelay, 41);
  GapRecord whole;
  whole.sample_time = c.estimation.sample_time;
  whole.u.resize(2 * c.estimation.u.size());
  whole.u << c.estimation.u, c.validation.u;
  whole.y.resize(2 * c.estimation.y.size());
  whole.y << c.estimation.y, c.validation.y;
  const GapReport report = DiagnoseGap(c.sim, {whole}, {});
  ASSERT_FALSE(report.notes.empty());
  EXPECT_NE(report.notes.front().find("first half"), std::string::npos);
  EXPECT_EQ(report.verdict.effect, "time_delay");
  EXPECT_EQ(report.validation_samples, static_cast<int>(whole.u.size() - whole.u.size() / 2));
}

std::string ErrorOf(const TransferFunction& sim, const std::vector<GapRecord>& est,
                    const std::vector<GapRecord>& val = {}) {
  try {
    DiagnoseGap(sim, est, val);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

TEST(GapDiagnosisTest, BadInputGetsClearErrors) {
  const GapCase c = Case(EffectKind::kNone, 51);
  GapRecord nan = c.estimation;
  nan.y(17) = NAN;
  EXPECT_NE(ErrorOf(c.sim, {nan}, {c.validation}).find("sample 18 is NaN"), std::string::npos);
  GapRecord constant = c.estimation;
  constant.u.setConstant(0.5);
  EXPECT_NE(ErrorOf(c.sim, {constant}, {c.validation}).find("the input is constant"), std::string::npos);
  GapRecord short_record = c.estimation;
  short_record.u.conservativeResize(50);
  short_record.y.conservativeResize(50);
  EXPECT_NE(ErrorOf(c.sim, {short_record}).find("too short to split"), std::string::npos);
  GapRecord uneven = c.estimation;
  uneven.y.conservativeResize(uneven.y.size() - 1);
  EXPECT_NE(ErrorOf(c.sim, {uneven}, {c.validation}).find("u has 2500 samples but y has 2499"),
            std::string::npos);
  GapRecord other_rate = c.validation;
  other_rate.sample_time *= 2;
  EXPECT_NE(ErrorOf(c.sim, {c.estimation}, {other_rate}).find("differs from"), std::string::npos);
  TransferFunction discrete = c.sim;
  discrete.sample_time = 0.05;  // the data are at 0.01 s
  discrete.den = Eigen::Vector2d(1.0, -0.5);
  discrete.num = Eigen::VectorXd::Constant(1, 0.5);
  EXPECT_NE(ErrorOf(discrete, {c.estimation}, {c.validation}).find("sample time"), std::string::npos);
  EXPECT_NE(ErrorOf(c.sim, {}).find("no estimation records"), std::string::npos);
}

}  // namespace
}  // namespace idrig

namespace idrig {
namespace {

TEST(GapWhereTest, AResonanceGapSitsInTheBandOfTheResonance) {
  // A first-order plant whose rig has a resonance at 30 rad/s (4.8 Hz), under a broadband
  // random binary input: the model-error FRF relative to G0 peaks in the resonance's band.
  TransferFunction sim;
  sim.num = Eigen::VectorXd::Constant(1, 4.0);
  sim.den = Eigen::Vector2d(1.0, 2.0);
  const Effect resonance{EffectKind::kUnmodelledResonance, {30.0, 0.1}};
  std::mt19937_64 rng(61);
  GapRecord record;
  record.sample_time = 0.01;
  record.u.resize(4000);
  for (long k = 0; k < record.u.size(); ++k) record.u(k) = (rng() & 1) ? 1.0 : -1.0;
  const double sigma = 0.02;
  record.y = SimulateRig(sim, resonance, record.u, record.sample_time, sigma, rng);
  const GapWhere where = LocateGap(sim, {record}, sigma);
  const double f_res = resonance.params[0] / (2 * M_PI);
  bool found = false;
  double strongest_power = 0, strongest_f = 0;
  for (const auto& b : where.bands) {
    if (b.relative_error > strongest_power)
      strongest_power = b.relative_error, strongest_f = std::sqrt(b.f_lo_hz * b.f_hi_hz);
    if (b.f_lo_hz <= f_res && f_res < b.f_hi_hz) found = b.significant;
  }
  std::printf("resonance at %.2f Hz; strongest band centre %.2f Hz; %s\n", f_res, strongest_f, where.summary.c_str());
  EXPECT_TRUE(found);
  EXPECT_TRUE(where.gap_significant);
  EXPECT_NEAR(std::log(strongest_f), std::log(f_res), std::log(2.5));
}

TEST(GapWhereTest, ADeadZoneGapDependsOnAmplitudeAndNoGapIsWithinNoise) {
  const GapCase dz = Case(EffectKind::kDeadZone, 62);
  const GapWhere where = LocateGap(dz.sim, {dz.validation}, dz.noise_sigma);
  const GapFactor* amplitude = nullptr;
  for (const auto& f : where.factors)
    if (f.name == "amplitude") amplitude = &f;
  ASSERT_NE(amplitude, nullptr);
  // The dead zone removes a constant d from |u|: relative to the signal, the gap is largest at
  // small amplitudes.
  EXPECT_GT(amplitude->relative_ratio, 1.5);
  EXPECT_GT(amplitude->bins.front().relative_rms, amplitude->bins.back().relative_rms);
  const GapCase none = Case(EffectKind::kNone, 63);
  const GapWhere clean = LocateGap(none.sim, {none.validation}, none.noise_sigma);
  std::printf("dead zone: %s\nnone: %s\n", where.summary.c_str(), clean.summary.c_str());
  EXPECT_FALSE(clean.gap_significant);
  EXPECT_NEAR(clean.gap_to_noise, 1.0, 0.1);
}

}  // namespace
}  // namespace idrig

#include "core/numeric/signal/excitation.h"

namespace idrig {
namespace {

TEST(DiagnoseSignalTest, BlockAndSampleBySampleAgreeAndTheSegmentsAreWhereDocumented) {
  const ExcitationSpec spec = ParseExcitationSpec("diagnose:amp=2,T=40,f1=3,seed=4");
  EXPECT_EQ(FormatExcitationSpec(spec), "diagnose:amp=2,T=40,f1=3,seed=4");
  const double fs = 50;
  const Eigen::VectorXd block = GenerateExcitation(spec, fs, 4000);  // two periods
  ExcitationGenerator generator(spec, fs);
  for (int k = 0; k < 4000; ++k) ASSERT_EQ(generator.Next(), block(k)) << k;
  EXPECT_TRUE(block.head(2000).isApprox(block.tail(2000), 1e-12));
  EXPECT_DOUBLE_EQ(ExcitationPeriod(spec, fs), 40.0);
  // Multisine blocks: RMS 0.06, 0.15, 0.3 × amp (whole multisine periods of 8 s each).
  const double levels[3] = {0.06, 0.15, 0.3};
  for (int b = 0; b < 3; ++b) {
    const Eigen::VectorXd part = block.segment(b * 400, 400);
    EXPECT_NEAR(std::sqrt(part.squaredNorm() / 400), levels[b] * 2, 1e-9 * 2);
  }
  // Triangle peaks ±1.2 in [24, 32) s; steps +1, −1, +2, −2 in [32, 40) s.
  EXPECT_NEAR(block.segment(1200, 400).maxCoeff(), 1.2, 1e-9);
  EXPECT_NEAR(block.segment(1200, 400).minCoeff(), -1.2, 1e-9);
  EXPECT_DOUBLE_EQ(block(1650), 1.0);
  EXPECT_DOUBLE_EQ(block(1750), -1.0);
  EXPECT_DOUBLE_EQ(block(1850), 2.0);
  EXPECT_DOUBLE_EQ(block(1950), -2.0);
  try {
    GenerateExcitation(ParseExcitationSpec("diagnose:T=10,f1=40"), fs, 10);
    FAIL() << "f1 above Nyquist accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("not below fs/2"), std::string::npos);
  }
}

TEST(DiagnoseSignalTest, SeparatesADeadZoneThatABinaryInputCannot) {
  // The dead zone of BinaryInputCannotSeparateInputNonlinearityFromGain, now excited by the
  // diagnose sequence: the verdict is the dead zone itself.
  const GapCase c = Case(EffectKind::kDeadZone, 31, "rbs");
  const double u_max = c.estimation.u.cwiseAbs().maxCoeff();
  const ExcitationSpec est = ParseExcitationSpec("diagnose:T=25,f1=5,seed=1");
  const ExcitationSpec val = ParseExcitationSpec("diagnose:T=25,f1=5,seed=2");
  std::mt19937_64 rng(7);
  auto record = [&](const ExcitationSpec& spec) {
    GapRecord r;
    r.sample_time = c.estimation.sample_time;
    r.u = u_max * GenerateExcitation(spec, 1.0 / r.sample_time, 2500);
    r.y = SimulateRig(c.real, c.effect, r.u, r.sample_time, c.noise_sigma, rng);
    return r;
  };
  const GapReport report = DiagnoseGap(c.sim, {record(est)}, {record(val)});
  std::printf("dead zone d = %.4f: verdict %s, fitted d = %.4f\n", c.effect.params[0],
              report.verdict.effect.c_str(), report.verdict.params.params.empty() ? NAN : report.verdict.params.params[0]);
  EXPECT_EQ(report.verdict.effect, "dead_zone");
  EXPECT_NEAR(report.verdict.params.params[0], c.effect.params[0], 0.1 * c.effect.params[0]);
}

// A gap outside the library: the rig answers twice, its response echoed 3 s later at 30 % (a
// reflection, a second load path). No effect and no linear part of order n0 + 2 reproduces a
// 3 s echo, the residual that G0 leaves follows the input, and the verdict must not be `none`
// ("G0 fits within the noise"): it is `unexplained`, with the gap left as it was.
TEST(GapDiagnosisTest, AnEchoNoEffectExplainsIsUnexplainedNotNone) {
  GapCase c = Case(EffectKind::kNone, 11);
  const long echo = static_cast<long>(std::lround(3.0 / c.estimation.sample_time));
  for (GapRecord* r : {&c.estimation, &c.validation}) {
    const Eigen::VectorXd y = r->y;
    for (long t = echo; t < y.size(); ++t) r->y(t) += 0.3 * y(t - echo);
  }
  const GapReport report = DiagnoseGap(c.sim, {c.estimation}, {c.validation});
  const GapVerdict& v = report.verdict;
  EXPECT_EQ(v.effect, "unexplained") << v.explanation;
  EXPECT_TRUE(v.effects.empty());
  EXPECT_GT(v.nrmse_after, 3 * v.noise_nrmse);
  EXPECT_DOUBLE_EQ(v.shrink, 0.0);
  EXPECT_NE(v.explanation.find("follows the input"), std::string::npos) << v.explanation;
}

// An output disturbance that does not follow the input: mains hum (a sinusoid at 0.23 of the
// sample rate, 3 noise sigmas, its own phase per record) on a rig G0 describes. A lightly damped
// resonance with a free initial state reproduces a hum through its free response, and the
// verdict was unmodelled_resonance, then unmodelled_dynamics. The residual G0 leaves does not
// follow the input, so the linear effects are set aside and the verdict is `none`, the gap
// named as a disturbance. The same hum on a delay case leaves the delay named: first at stop 36
// (CI's machine), but on an AMD EPYC with AVX-512 (stop 37, stop 36's code as well) a pair comes
// first whose resonance sits at the hum's frequency (144.6 rad/s, ζ 0.0015: its free response,
// fitted per record, carries the hum; G0's residual follows the input — the delay — so the
// disturbance rules do not apply); the delay is then its second effect. Asserted: it is named.
TEST(GapDiagnosisTest, MainsHumIsADisturbanceNotUnmodelledDynamics) {
  const double kPi = 3.14159265358979323846;
  auto add_hum = [&](GapCase& c) {
    double phase = 0.3;
    for (GapRecord* r : {&c.estimation, &c.validation}) {
      for (long t = 0; t < r->y.size(); ++t) r->y(t) += 3 * c.noise_sigma * std::sin(2 * kPi * 0.23 * t + phase);
      phase += 1.4;
    }
  };
  GapCase quiet = Case(EffectKind::kNone, 12);
  add_hum(quiet);
  const GapReport report = DiagnoseGap(quiet.sim, {quiet.estimation}, {quiet.validation});
  EXPECT_EQ(report.verdict.effect, "none") << report.verdict.explanation;
  EXPECT_GT(report.verdict.nrmse_before, 1.5 * report.verdict.noise_nrmse);  // the hum is above the floor
  EXPECT_TRUE(std::any_of(report.notes.begin(), report.notes.end(), [](const std::string& n) {
    return n.find("does not follow the input") != std::string::npos;
  }));
  for (const CandidateFit& c : report.ranking) {
    if (c.effect.kind == EffectKind::kUnmodelledResonance) {
      EXPECT_FALSE(c.eligible);
    }
  }

  GapCase delayed = Case(EffectKind::kTimeDelay, 13);
  add_hum(delayed);
  const GapReport d = DiagnoseGap(delayed.sim, {delayed.estimation}, {delayed.validation});
  std::vector<std::string> named;
  for (const Effect& e : d.verdict.effects) named.push_back(EffectName(e.kind));
  const bool delay_named = d.verdict.effect == "time_delay" ||
                           std::find(named.begin(), named.end(), "time_delay") != named.end();
  EXPECT_TRUE(delay_named) << d.verdict.effect << ": " << d.verdict.explanation;
}

}  // namespace
}  // namespace idrig
