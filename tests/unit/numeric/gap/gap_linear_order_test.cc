// When the linear part is the problem (linear_order.cc): the rig has dynamics the sim model
// lacks and that no effect of the vocabulary is (an anti-resonance with its resonance: two more
// zeros and poles), behind a static output nonlinearity. The diagnosis must say
// `unmodelled_dynamics` and then report the static map on the higher-order linear part, not spend
// the verdict on a lag or a resonance. Truth by construction (the rig is simulated with the
// effect library).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

#include "core/numeric/gap/gap_bench.h"
#include "core/numeric/gap/gap_diagnosis.h"
#include "core/numeric/model/lti_model.h"

namespace idrig {
namespace {

// A `levels` case whose sim model is second order: ω²·k/(s² + 2ζωs + ω²), excited up to ≈ 3ω.
GapCase SecondOrderLevelsCase(uint64_t seed, int samples) {
  for (uint64_t s = seed;; ++s) {
    std::mt19937_64 rng(s);
    GapCaseOptions options;
    options.samples = samples;
    options.excitation = "levels";
    GapCase c = MakeGapCase(EffectKind::kCubicStiffness, rng, options);
    if (c.excitation == "levels" && c.sim.Order() == 2) return c;
  }
}

double Rms(const Eigen::VectorXd& v) { return std::sqrt(v.squaredNorm() / v.size()); }


void PrintReport(const GapReport& report) {
  const GapVerdict& v = report.verdict;
  std::printf("verdict %s, effects", v.effect.c_str());
  for (const auto& e : v.effects) std::printf(" %s", EffectName(e.kind));
  std::printf(", linear order %d (NRMSE %.4f), NRMSE %.4f -> %.4f\n", v.linear_order, v.linear_nrmse_after,
              v.nrmse_before, v.nrmse_after);
  if (std::getenv("GAP_DEBUG")) {
    for (const auto& r : report.ranking)
      std::printf("  %-22s nrmse %.4f bic %.1f LR %.1f/%.1f sig %.2f elig %d\n", EffectName(r.effect.kind),
                  r.nrmse_after, r.bic, r.likelihood_ratio, r.lr_threshold, r.signature, r.eligible);
    for (const auto& n : report.notes) std::printf("  note: %s\n", n.c_str());
  }
}

// A two-mass drive seen from the motor side: G = G0 · (ωp²/ωz²)(s² + 2ζωz s + ωz²)/(s² + 2ζωp s + ωp²),
// the anti-resonance ωz = 1.3ω below the resonance ωp = 2ω, both inside the excited band (≈ 3ω).
struct Rig {
  GapCase c;
  TransferFunction real;
};

Rig TwoMassRig(uint64_t seed, double wz_over_w0 = 1.3) {
  Rig rig{SecondOrderLevelsCase(seed, 3000), {}};
  const TransferFunction& g0 = rig.c.sim;
  const double w0 = std::sqrt(g0.den(2) / g0.den(0));
  const double wz = wz_over_w0 * w0, wp = 2.0 * w0, zeta = 0.08;
  rig.real = g0;
  rig.real.num = PolynomialProduct(g0.num, Eigen::Vector3d(1.0, 2 * zeta * wz, wz * wz)) * (wp * wp / (wz * wz));
  rig.real.den = PolynomialProduct(g0.den, Eigen::Vector3d(1.0, 2 * zeta * wp, wp * wp));
  return rig;
}

// The two-mass rig (seed 401) read through y + a2 y² + a3 y³, the terms `quadratic` and `cubic`
// of y at max|y|; 30 dB output noise from `noise_seed`; 16 sub-steps.
Rig SensorRig(double wz_over_w0, double quadratic, double cubic, uint64_t noise_seed) {
  Rig rig = TwoMassRig(401, wz_over_w0);
  std::mt19937_64 rng(noise_seed);
  const Eigen::VectorXd y_lin =
      SimulateWithEffect(rig.real, Effect{}, rig.c.estimation.u, rig.c.estimation.sample_time);
  const double y_max = y_lin.cwiseAbs().maxCoeff();
  const Effect sensor{EffectKind::kSensorNonlinearity, {1.0, quadratic / y_max, cubic / (y_max * y_max), 0.0}};
  EffectSimulationOptions fine;
  fine.substeps = 16;
  for (GapRecord* r : {&rig.c.estimation, &rig.c.validation}) {
    r->y = SimulateWithEffect(rig.real, sensor, r->u, r->sample_time, fine);
    std::normal_distribution<double> noise(0.0, Rms(r->y.array() - r->y.mean()) * std::pow(10.0, -30.0 / 20));
    for (long k = 0; k < r->y.size(); ++k) r->y(k) += noise(rng);
  }
  return rig;
}

// Disabled from stop 31 to stop 35: the linear part's fit from the G0·P/P starts stopped in a
// basin that moved with the machine's arithmetic and the noise draw (NRMSE 0.41 with this seed,
// 0.116 with seed 407 and no map after it, for 0.066 with most seeds). With the subspace start
// (linear_order.cc, SubspaceStart) the fit starts at the rig's own poles: 0.0675 here, 0.066
// with seed 407, and the map after it at 0.031 for seeds 402 and 405–413 alike.
TEST(GapLinearOrderTest, MissingAntiResonanceThenASensorMapIsUnmodelledDynamicsThenTheMap) {
  const Rig rig = SensorRig(1.3, 0.15, -0.1, 402);
  const GapReport report = DiagnoseGap(rig.c.sim, {rig.c.estimation}, {rig.c.validation});
  PrintReport(report);
  const GapVerdict& v = report.verdict;
  EXPECT_EQ(v.effect, "unmodelled_dynamics");
  EXPECT_EQ(v.linear_order, rig.c.sim.Order() + 2);
  ASSERT_FALSE(v.effects.empty());
  EXPECT_EQ(v.effects[0].kind, EffectKind::kSensorNonlinearity);
  EXPECT_LT(v.nrmse_after, v.linear_nrmse_after);  // the map closes what the linear fix leaves
  EXPECT_LT(v.linear_nrmse_after, v.nrmse_before);
  // The linear part is as good as the rig's own (the best linear output-error model of this
  // structure is at least as good as the true linear part, the map unmodelled; 0.076 here). From
  // the G0·P/P starts alone it stopped at 0.41.
  const GapRecord& val = rig.c.validation;
  Eigen::VectorXd y_linear = SimulateWithEffect(rig.real, Effect{}, val.u, val.sample_time);
  y_linear.array() += (val.y - y_linear).mean();
  const double true_linear_nrmse = (val.y - y_linear).norm() / (val.y.array() - val.y.mean()).matrix().norm();
  std::printf("the rig's own linear part: validation NRMSE %.4f\n", true_linear_nrmse);
  EXPECT_LT(v.linear_nrmse_after, 1.05 * true_linear_nrmse);
}

TEST(GapLinearOrderTest, MildMissingDynamicsUnderAStrongSensorMapStillGoesToTheLinearPartFirst) {
  // The missing dynamics smaller (anti-resonance at 1.85ω: the gain rises by 1.17 above it), the
  // map stronger (40 % and −25 % at max|y|): a static effect on G0 now beats the higher-order
  // linear part alone, yet the linear part lacks dynamics — the map must be named on the fixed
  // linear part, not next to a lag or a resonance standing in for it.
  const Rig rig = SensorRig(1.85, 0.4, -0.25, 404);
  const GapReport report = DiagnoseGap(rig.c.sim, {rig.c.estimation}, {rig.c.validation});
  PrintReport(report);
  const GapVerdict& v = report.verdict;
  EXPECT_NE(report.ranking.front().effect.kind, EffectKind::kParameterMismatch);  // a static effect led
  EXPECT_EQ(v.effect, "unmodelled_dynamics");
  ASSERT_FALSE(v.effects.empty());
  EXPECT_EQ(v.effects[0].kind, EffectKind::kSensorNonlinearity);
  EXPECT_LT(v.nrmse_after, report.ranking.front().nrmse_after);
}

TEST(GapLinearOrderTest, AdequateLinearPartWithASensorMapIsTheMapNotUnmodelledDynamics) {
  // The same rig, with the sim model of the right order: nothing for the linear-order check to
  // find, the verdict is the map.
  const Rig rig = SensorRig(1.3, 0.15, -0.1, 403);
  const GapReport report = DiagnoseGap(rig.real, {rig.c.estimation}, {rig.c.validation});
  PrintReport(report);
  EXPECT_EQ(report.verdict.effect, "sensor_nonlinearity");
}

TEST(GapLinearOrderTest, TwoStaticEffectsOnAnAdequateLinearPartAreNotUnmodelledDynamics) {
  // `idrig gap bench --cases 14 --seed 46 --offsets --integrating --combos 1 --excitation
  // levels`, case 8: a dead zone and a cubic spring on an integrating plant whose sim model is
  // exact. A linear part of order 4 beats every single effect (each explains only part of the
  // gap), and it was adopted before any pair was tried: unmodelled_dynamics + dead_zone +
  // cubic_stiffness. The pair search now runs first, and the higher-order part (with what it
  // leaves) must beat the pair.
  std::mt19937_64 rng(BenchCaseSeed(46, 8));
  GapCaseOptions options;
  options.offsets = true;
  options.integrating = true;
  options.excitation = "levels";
  const std::vector<EffectKind> truth = BenchCaseTruth(8, 1.0);
  ASSERT_EQ(truth, (std::vector<EffectKind>{EffectKind::kDeadZone, EffectKind::kCubicStiffness}));
  const GapCase c = MakeGapCase(truth, rng, options);
  GapOptions gap;
  gap.threads = 1;
  const GapReport report = DiagnoseGap(c.sim, {c.estimation}, {c.validation}, gap);
  PrintReport(report);
  const GapVerdict& v = report.verdict;
  EXPECT_EQ(v.effect, "dead_zone");
  ASSERT_EQ(v.effects.size(), 2u);
  EXPECT_EQ(v.effects[1].kind, EffectKind::kCubicStiffness);
  EXPECT_EQ(v.linear_order, 0);
}

TEST(GapLinearOrderTest, AFixedFitSchemeIsKeptSoThatTheInnerDiagnosisComparesWithTheOuter) {
  // The diagnosis on a higher-order part runs with the outer fit scheme (linear_order.cc): the
  // option that carries it must override the scheme chosen from G0. An integrating plant gets
  // multiple shooting from G0; told single shooting, or another segment, it uses that.
  std::mt19937_64 rng(BenchCaseSeed(46, 0));
  GapCaseOptions options;
  options.samples = 1200;
  options.integrating = true;
  const GapCase c = MakeGapCase({EffectKind::kNone}, rng, options);
  GapOptions gap;
  gap.threads = 1;
  gap.candidates = {EffectKind::kNone, EffectKind::kParameterMismatch};
  gap.check_linear_order = false;
  gap.second_effect = false;
  const GapReport chosen = DiagnoseGap(c.sim, {c.estimation}, {c.validation}, gap);
  EXPECT_EQ(chosen.verdict.fit_scheme, "multiple_shooting");
  gap.fixed_segment = 0;
  gap.fixed_integrating = true;
  EXPECT_EQ(DiagnoseGap(c.sim, {c.estimation}, {c.validation}, gap).verdict.fit_scheme, "single_shooting");
  gap.fixed_segment = 450;
  const GapReport fixed = DiagnoseGap(c.sim, {c.estimation}, {c.validation}, gap);
  EXPECT_EQ(fixed.verdict.fit_scheme, "multiple_shooting");
  EXPECT_EQ(fixed.verdict.shooting_segment, 450);
  EXPECT_NE(chosen.verdict.shooting_segment, 450);
}

// An integrating rig under process noise (`idrig gap bench --cases 26 --seed 2005 --offsets
// --integrating --process-noise 0.5`, cases 3 and 16): an actuator lag, and half the noise variance
// a load at the plant's input, which the integrator turns into a walk. A linear part of order
// n0 + 2 gained over the verdict on validation (z 3.23 and 3.09 with the automatic lag) and was
// adopted: unmodelled_dynamics. Its two extra states are fitted on every validation segment and
// follow the walk within it; given each other's free response on every segment, the two models
// differ by z 0.50 and −3.58. What the verdict leaves does not follow the input, so that gain is
// required too, and the lag stays.
class GapWalkOrderTest : public ::testing::TestWithParam<int> {};

TEST_P(GapWalkOrderTest, AHigherOrderThatOnlyFollowsAWalkThroughItsFreeStatesIsNotAdopted) {
  std::mt19937_64 rng(BenchCaseSeed(2005, GetParam()));
  GapCaseOptions options;
  options.offsets = true;
  options.integrating = true;
  options.process_noise = 0.5;
  const GapCase c = MakeGapCase(BenchCaseTruth(GetParam(), 0).front(), rng, options);
  ASSERT_EQ(c.truth, EffectKind::kActuatorLag);
  GapOptions gap;
  gap.threads = 1;
  const GapReport report = DiagnoseGap(c.sim, {c.estimation}, {c.validation}, gap);
  PrintReport(report);
  std::string note;
  for (const std::string& n : report.notes)
    if (n.rfind("linear order check: validation gain over the verdict so far", 0) == 0) note = n;
  std::printf("  %s\n", note.c_str());
  EXPECT_EQ(report.verdict.effect, "actuator_lag");
  EXPECT_EQ(report.verdict.linear_order, 0);
  EXPECT_EQ(report.verdict.fit_scheme, "multiple_shooting");
  // The plain gain passes (the rule before), the gain given each other's free response does not.
  double z = 0, z_free = 0, z_crit = 0;
  ASSERT_EQ(std::sscanf(note.c_str(), "linear order check: validation gain over the verdict so far z = %lf "
                                      "(Newey–West, automatic lag; needs > %lf)",
                        &z, &z_crit), 2) << note;
  const size_t at = note.find("free response on every shooting segment z = ");
  ASSERT_NE(at, std::string::npos) << note;
  ASSERT_EQ(std::sscanf(note.c_str() + at, "free response on every shooting segment z = %lf", &z_free), 1);
  EXPECT_GT(z, z_crit);
  EXPECT_LT(z_free, z_crit);
  EXPECT_NE(note.find("does not follow the input"), std::string::npos) << note;
}

INSTANTIATE_TEST_SUITE_P(Seed2005, GapWalkOrderTest, ::testing::Values(3, 16),
                         [](const auto& info) { return "case" + std::to_string(info.param); });

TEST(GapLinearOrderTest, MissingDynamicsOnAnIntegratingRigAreStillAdopted) {
  // The other side: an integrating sim model K/(s(Ts + 1)) (multiple shooting) and a rig that adds
  // an anti-resonance at 1.3/T and a resonance at 2/T (a two-mass drive seen from the motor, as
  // TwoMassRig), output noise only. What the verdict leaves before the order check follows the
  // input, so the higher-order part is adopted on its plain validation gain.
  std::mt19937_64 rng(BenchCaseSeed(46, 0));
  GapCaseOptions options;
  options.integrating = true;
  options.excitation = "levels";
  GapCase c = MakeGapCase({EffectKind::kNone}, rng, options);
  ASSERT_EQ(c.sim.Order(), 2);
  const double w0 = c.sim.den(1) / c.sim.den(0);  // the pole 1/T of K/(s(Ts + 1))
  const double wz = 1.3 * w0, wp = 2.0 * w0, zeta = 0.08;
  TransferFunction real = c.sim;
  real.num = PolynomialProduct(c.sim.num, Eigen::Vector3d(1.0, 2 * zeta * wz, wz * wz)) * (wp * wp / (wz * wz));
  real.den = PolynomialProduct(c.sim.den, Eigen::Vector3d(1.0, 2 * zeta * wp, wp * wp));
  std::mt19937_64 noise_rng(4601);
  EffectSimulationOptions fine;
  fine.substeps = 16;
  for (GapRecord* r : {&c.estimation, &c.validation}) {
    r->y = SimulateWithEffect(real, Effect{}, r->u, r->sample_time, fine);
    std::normal_distribution<double> noise(0.0, Rms(r->y.array() - r->y.mean()) * std::pow(10.0, -30.0 / 20));
    for (long k = 0; k < r->y.size(); ++k) r->y(k) += noise(noise_rng);
  }
  GapOptions gap;
  gap.threads = 1;
  const GapReport report = DiagnoseGap(c.sim, {c.estimation}, {c.validation}, gap);
  PrintReport(report);
  for (const std::string& n : report.notes)
    if (n.rfind("linear order check: validation gain", 0) == 0) std::printf("  %s\n", n.c_str());
  EXPECT_EQ(report.verdict.fit_scheme, "multiple_shooting");
  EXPECT_EQ(report.verdict.effect, "unmodelled_dynamics");
  EXPECT_EQ(report.verdict.linear_order, 4);
}

}  // namespace
}  // namespace idrig
