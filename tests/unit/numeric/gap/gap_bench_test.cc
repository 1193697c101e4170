// The blind-case generator's operating points and effect pairs, the bench's plan and its scores.
// References: superposition of a linear plant (offsets), the lattice an ADC puts its readings
// on, the stage order of a sensor after a delay, and counts made by hand.
#include "core/numeric/gap/gap_bench.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "core/numeric/gap/gap_noise.h"
#include "core/numeric/model/lti_model.h"

namespace idrig {
namespace {

// The noise of a linear stable rig without effects: by superposition (settled at G(0)·u_off
// before the record starts) y = G u + G(0) u_off + y_off + noise.
Eigen::VectorXd NoiseOf(const GapCase& c) {
  const double dc = c.real.num(c.real.num.size() - 1) / c.real.den(c.real.den.size() - 1);
  const Eigen::VectorXd lin = Simulate(c.real, c.estimation.u, c.estimation.sample_time).col(0);
  return c.estimation.y - lin - Eigen::VectorXd::Constant(lin.size(), dc * c.input_offset + c.output_offset);
}

// Mean square and lag-1 autocorrelation of a noise sequence, about zero (centre it first for
// moments about its mean).
struct NoiseMoments {
  double variance, lag1;
};
NoiseMoments MomentsOf(const Eigen::VectorXd& e) {
  const long n = e.size();
  const double var = e.squaredNorm() / n;
  return {var, e.head(n - 1).dot(e.tail(n - 1)) / (n - 1) / var};
}

TEST(GapBenchTest, OffsetsShiftALinearRigByTheSteadyStateOfTheActuatorOffsetAndTheSensorOffset) {
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    std::mt19937_64 rng(seed);
    GapCaseOptions options;
    options.samples = 1500;
    options.offsets = true;
    options.snr_db = 40;
    const GapCase c = MakeGapCase(EffectKind::kNone, rng, options);
    const double u_peak = c.estimation.u.cwiseAbs().maxCoeff();
    EXPECT_LE(std::abs(c.input_offset), 0.3 * u_peak + 1e-12);
    EXPECT_GT(std::abs(c.output_offset), 0.0);
    const double rms = std::sqrt(MomentsOf(NoiseOf(c)).variance);
    EXPECT_NEAR(rms, c.noise_sigma, 0.15 * c.noise_sigma) << "seed " << seed;
    // The sensor offset is a sizeable share of the output's range.
    const double range = c.estimation.y.maxCoeff() - c.estimation.y.minCoeff();
    EXPECT_GT(std::abs(c.output_offset), 0.05 * range);
  }
}

TEST(GapBenchTest, ASensorDriftIsARampOfTheRequestedSizeAndKeepsTheQuantisersLattice) {
  for (const EffectKind truth : {EffectKind::kNone, EffectKind::kOutputQuantization}) {
    GapCaseOptions options;
    options.samples = 1000;
    options.excitation = "levels";
    std::mt19937_64 rng_a(21), rng_b(21);
    const GapCase plain = MakeGapCase(truth, rng_a, options);
    options.drift = 10;
    const GapCase drifting = MakeGapCase(truth, rng_b, options);
    ASSERT_EQ(plain.noise_sigma, drifting.noise_sigma);
    const double sigma = plain.noise_sigma;
    const long n = plain.estimation.y.size();
    for (long k = 0; k < n; k += 111) {
      const double ramp = 10 * sigma * k / double(n - 1);
      const double tolerance = truth == EffectKind::kNone ? 1e-9 : plain.effect.params[0];  // one lattice step
      EXPECT_NEAR(drifting.estimation.y(k) - plain.estimation.y(k), ramp, tolerance + 1e-9) << k;
      EXPECT_NEAR(drifting.validation.y(k) - plain.validation.y(k), -ramp, tolerance + 1e-9) << k;
    }
    if (truth == EffectKind::kOutputQuantization) {
      // Before the ADC: every reading is still on the lattice q·k.
      const double q = plain.effect.params[0];
      for (long k = 0; k < n; ++k)
        ASSERT_NEAR(drifting.estimation.y(k) / q, std::round(drifting.estimation.y(k) / q), 1e-6) << k;
    }
  }
}

TEST(GapBenchTest, ColouredNoiseHasTheRequestedPoleAndTheSameVariance) {
  // AR(1) noise e(k) = a e(k−1) + √(1 − a²) σ w(k): variance σ², lag-1 autocorrelation a
  // (closed form), on a linear rig without effects, so y − G u − offsets is the noise.
  for (const double a : {0.0, 0.5, 0.9}) {
    std::mt19937_64 rng(11);
    GapCaseOptions options;
    options.samples = 20000;
    options.offsets = true;
    options.noise_pole = a;
    const GapCase c = MakeGapCase(EffectKind::kNone, rng, options);
    const NoiseMoments m = MomentsOf(NoiseOf(c));
    EXPECT_NEAR(std::sqrt(m.variance), c.noise_sigma, (a > 0.8 ? 0.1 : 0.05) * c.noise_sigma) << "pole " << a;
    EXPECT_NEAR(m.lag1, a, 0.03) << "pole " << a;
  }
}

TEST(GapBenchTest, ProcessNoiseSplitsTheVarianceAndIsColouredByThePlant) {
  // A share F of σ² enters at the plant's input and is low-passed by it; the rest is white output
  // noise: the total variance stays σ², and the lag-1 autocovariance is F σ² ρ_p(1), where the
  // plant's own ρ_p(1) lies between e^(−ω Ts) ≥ e^(−0.15) (its fastest corner, 15 rad/s at 0.01 s)
  // and 1. F = 0 draws the same case as before the option existed.
  for (const double f : {0.0, 0.5, 0.9}) {
    for (uint64_t seed = 21; seed <= 23; ++seed) {
      std::mt19937_64 rng(seed), plain_rng(seed);
      GapCaseOptions options;
      options.samples = 20000;
      options.offsets = true;
      options.process_noise = f;
      const GapCase c = MakeGapCase(EffectKind::kNone, rng, options);
      const Eigen::VectorXd e = NoiseOf(c);
      const NoiseMoments m = MomentsOf(e.array() - e.mean());
      EXPECT_NEAR(std::sqrt(m.variance), c.noise_sigma, 0.15 * c.noise_sigma) << "share " << f << ", seed " << seed;
      EXPECT_GT(m.lag1, std::exp(-0.15) * f - 0.03) << "share " << f << ", seed " << seed;
      EXPECT_LT(m.lag1, f + 0.03) << "share " << f << ", seed " << seed;
      if (f == 0) {
        GapCaseOptions before;
        before.samples = 20000;
        before.offsets = true;
        const GapCase plain = MakeGapCase(EffectKind::kNone, plain_rng, before);
        EXPECT_EQ(plain.estimation.y, c.estimation.y);
      }
    }
  }
}

TEST(GapBenchTest, DampingRatiosAreDrawnInTheRequestedRange) {
  // ζ of a second-order plant s² + 2ζω s + ω²: den(1)/(2√den(2)).
  int second_order = 0;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    std::mt19937_64 rng(seed);
    GapCaseOptions options;
    options.samples = 300;
    options.zeta_min = 0.02;
    options.zeta_max = 0.1;
    const GapCase c = MakeGapCase(EffectKind::kCubicStiffness, rng, options);  // second order or more
    if (c.real.den.size() != 3) continue;
    ++second_order;
    const double zeta = c.real.den(1) / (2 * std::sqrt(c.real.den(2)));
    EXPECT_GE(zeta, 0.02 - 1e-12);
    EXPECT_LE(zeta, 0.1 + 1e-12);
  }
  EXPECT_GT(second_order, 5);
}

TEST(GapBenchTest, AParameterMismatchNeverMakesTheRigUnstable) {
  // Lightly damped third-order plants s³ + a1 s² + a2 s + a3 with every coefficient 10–30 % off:
  // Hurwitz needs a1·a2 > a3, which the draw can break (`--seed 111 --damping 0.02,0.1
  // --excitation multisine`, case 14 had a1·a2 = 3465 < a3 = 4685, its output grew to 1e11).
  int third_order = 0;
  for (uint64_t seed = 1; seed <= 120; ++seed) {
    std::mt19937_64 rng(seed);
    GapCaseOptions options;
    options.samples = 300;
    options.zeta_min = 0.02;
    options.zeta_max = 0.1;
    const GapCase c = MakeGapCase(EffectKind::kParameterMismatch, rng, options);
    if (c.real.den.size() != 4) continue;
    ++third_order;
    const Eigen::VectorXd& a = c.real.den;
    EXPECT_GT(a(1) * a(2), a(3)) << "seed " << seed;
    EXPECT_TRUE(c.estimation.y.allFinite());
  }
  EXPECT_GT(third_order, 20);
}

TEST(GapBenchTest, TheMultisineExcitationIsFivePeriodsOfAnOddMultisine) {
  std::mt19937_64 rng(5);
  GapCaseOptions options;
  options.samples = 2000;
  options.excitation = "multisine";
  const GapCase c = MakeGapCase(EffectKind::kNone, rng, options);
  const Eigen::VectorXd& u = c.estimation.u;
  const Periodicity p = FindPeriod(u);
  EXPECT_EQ(p.period, 400);
  EXPECT_EQ(p.periods, 5);
  EXPECT_LT((u.segment(400, 1600) - u.head(1600)).norm(), 1e-9 * u.norm());
  // Odd lines only: the DFT of one period has no energy on even lines (a half-period shift
  // flips the sign of the signal).
  EXPECT_LT((u.segment(0, 200) + u.segment(200, 200)).norm(), 1e-9 * u.head(400).norm());
  // A different realisation for validation, same period.
  EXPECT_EQ(FindPeriod(c.validation.u).period, 400);
  EXPECT_GT((c.validation.u - u).norm(), 0.1 * u.norm());
}

TEST(GapBenchTest, BacklashWithQuantisationReadsOnALatticeOffsetByTheSensorOffset) {
  std::mt19937_64 rng(7);
  GapCaseOptions options;
  options.samples = 1000;
  options.offsets = true;
  const GapCase c = MakeGapCase({EffectKind::kBacklash, EffectKind::kOutputQuantization}, rng, options);
  ASSERT_EQ(c.effects.size(), 2u);
  EXPECT_EQ(c.effects[0].kind, EffectKind::kBacklash);
  const double q = c.effects[1].params.at(0);
  for (long k = 0; k < c.estimation.y.size(); ++k) {
    const double level = (c.estimation.y(k) - c.output_offset) / q;
    ASSERT_NEAR(level, std::round(level), 1e-6) << "sample " << k;
  }
}

TEST(GapBenchTest, TwoEffectsActInStageOrder) {
  // A delay on the input and a sensor map on the output, given in either order: the sensor reads
  // the delayed linear output.
  TransferFunction plant;
  plant.num = Eigen::VectorXd::Constant(1, 4.0);
  plant.den = Eigen::Vector3d(1.0, 1.2, 4.0);
  const Effect delay{EffectKind::kTimeDelay, {0.05}};
  const Effect sensor{EffectKind::kSensorNonlinearity, {1.0, 0.1, -0.2, 0.0}};
  Eigen::VectorXd u(400);
  for (long k = 0; k < u.size(); ++k) u(k) = std::sin(0.05 * k) + 0.3 * std::sin(0.31 * k);
  std::mt19937_64 rng(1);
  const Eigen::VectorXd y = SimulateRig(plant, {sensor, delay}, u, 0.01, 0.0, rng);
  const Eigen::VectorXd delayed = Simulate(ApplyLinearEffect(plant, delay), u, 0.01).col(0);
  for (long k = 0; k < u.size(); ++k) EXPECT_NEAR(y(k), SensorMap(delayed(k), sensor.params), 1e-6);
}

TEST(GapBenchTest, AnyPairIsEveryPairOfElevenEffectsButTheTwoFeedbackTerms) {
  // 11 effects (none and parameter_mismatch aside): C(11, 2) = 55 pairs, less friction with a
  // cubic spring (one feedback effect per simulation).
  const auto& pairs = AnyEffectPairs();
  EXPECT_EQ(pairs.size(), 54u);
  std::set<std::pair<EffectKind, EffectKind>> seen;
  for (const auto& [a, b] : pairs) {
    EXPECT_NE(a, b);
    for (EffectKind k : {a, b}) {
      EXPECT_NE(k, EffectKind::kNone);
      EXPECT_NE(k, EffectKind::kParameterMismatch);
    }
    EXPECT_FALSE(IsFeedbackEffect(a) && IsFeedbackEffect(b));
    EXPECT_TRUE(seen.insert({std::min(a, b), std::max(a, b)}).second) << EffectName(a) << "+" << EffectName(b);
  }
  // The plan walks them in turn.
  for (int i = 0; i < 60; ++i) {
    const auto t = BenchCaseTruth(i, 1.0, true);
    ASSERT_EQ(t.size(), 2u);
    EXPECT_EQ(t[0], pairs[i % pairs.size()].first);
    EXPECT_EQ(t[1], pairs[i % pairs.size()].second);
  }
}

TEST(GapBenchTest, ThePlanHasTheRequestedShareOfPairsSpreadEvenly) {
  const auto& kinds = AllEffects();
  for (int i = 0; i < 30; ++i) {
    const auto t = BenchCaseTruth(i, 0.0);
    ASSERT_EQ(t.size(), 1u);
    EXPECT_EQ(t[0], kinds[i % kinds.size()]);
  }
  int pairs = 0, longest_run = 0, run = 0;
  std::set<std::pair<EffectKind, EffectKind>> seen;
  for (int i = 0; i < 100; ++i) {
    const auto t = BenchCaseTruth(i, 0.4);
    if (t.size() == 2) {
      ++pairs;
      seen.insert({t[0], t[1]});
      run = 0;
    } else {
      longest_run = std::max(longest_run, ++run);
    }
  }
  EXPECT_EQ(pairs, 40);
  EXPECT_LE(longest_run, 2);
  EXPECT_EQ(seen.size(), CoOccurringEffectPairs().size());
  for (const auto& [a, b] : CoOccurringEffectPairs()) {
    std::mt19937_64 rng(3);
    GapCaseOptions options;
    options.samples = 600;
    EXPECT_NO_THROW(MakeGapCase({a, b}, rng, options)) << EffectName(a) << " + " << EffectName(b);
  }
}

TEST(GapBenchTest, ScoresCountBothNamedOrderFreeAndTopOneAsEitherOfThePair) {
  std::vector<GapBenchOutcome> o(6);
  const double inf = std::numeric_limits<double>::infinity();
  o[0] = {{EffectKind::kDeadZone}, "dead_zone", {"dead_zone"}, "levels", {}};  // visibility unknown: counted
  o[1] = {{EffectKind::kNone}, "backlash", {"backlash"}, "prbs", {inf}};
  o[2] = {{EffectKind::kNone}, "none", {}, "prbs", {inf}};  // no effects list: verdict.effect alone
  o[3] = {{EffectKind::kBacklash, EffectKind::kOutputQuantization}, "output_quantization",
          {"output_quantization", "backlash"}, "levels", {50.0, 400.0}};
  o[4] = {{EffectKind::kBacklash, EffectKind::kOutputQuantization}, "backlash", {"backlash"}, "rbs", {50.0, 400.0}};
  o[5] = {{EffectKind::kDeadZone, EffectKind::kCubicStiffness}, "time_delay",
          {"time_delay", "dead_zone"}, "rbs", {50.0, 400.0}};
  o.push_back({{EffectKind::kCoulombFriction, EffectKind::kOutputSaturation}, "coulomb_friction",
               {"coulomb_friction"}, "levels", {300.0, 2.0}});  // the clip within the noise
  const GapBenchScore s = ScoreGapBench(o);
  EXPECT_EQ(s.single_cases, 3);
  EXPECT_EQ(s.single_correct, 2);
  EXPECT_EQ(s.none_cases, 2);
  EXPECT_EQ(s.false_alarms, 1);
  EXPECT_EQ(s.combo_cases, 4);
  EXPECT_EQ(s.combo_both, 1);
  EXPECT_EQ(s.combo_either, 3);
  EXPECT_DOUBLE_EQ(s.combo_both_rate, 1.0 / 4);
  EXPECT_EQ(s.confusion.at("backlash+output_quantization").at("output_quantization+backlash"), 1);
  EXPECT_EQ(s.by_pair.at("backlash+output_quantization").first, 1);
  // Undecidable: backlash or a dead zone under a two-valued input (o[4], o[5]); o[1], o[2]
  // (none under prbs) stay decidable.
  EXPECT_EQ(s.decidable_single_cases, 3);
  EXPECT_EQ(s.decidable_single_correct, 2);
  EXPECT_EQ(s.decidable_combo_cases, 2);
  EXPECT_EQ(s.decidable_combo_both, 1);
  EXPECT_DOUBLE_EQ(s.combo_both_decidable, 0.5);
  // Detectable: decidable, and each withheld effect above BenchVisibilityThreshold() (about 11.4):
  // the last pair's clip (2.0) is not.
  EXPECT_NEAR(BenchVisibilityThreshold(), 11.4, 0.1);
  EXPECT_EQ(s.detectable_single_cases, 3);
  EXPECT_EQ(s.detectable_single_correct, 2);
  EXPECT_EQ(s.detectable_combo_cases, 1);
  EXPECT_EQ(s.detectable_combo_both, 1);
  EXPECT_DOUBLE_EQ(s.combo_both_detectable, 1.0);
  // After the refit: the detectable cases whose effects also show above the threshold once the
  // refit is taken out; an unknown visibility_refit (all of the above) counts as visible.
  EXPECT_EQ(s.refit_single_cases, 3);
  EXPECT_EQ(s.refit_combo_cases, 1);
  o.push_back({{EffectKind::kActuatorLag}, "none", {}, "levels", {200.0}, {3.0}});  // the refit takes it up
  o.push_back({{EffectKind::kTimeDelay}, "time_delay", {"time_delay"}, "levels", {200.0}, {40.0}});
  const GapBenchScore t = ScoreGapBench(o);
  EXPECT_EQ(t.detectable_single_cases, 5);
  EXPECT_EQ(t.detectable_single_correct, 3);
  EXPECT_EQ(t.refit_single_cases, 4);
  EXPECT_EQ(t.refit_single_correct, 3);
  EXPECT_DOUBLE_EQ(t.top1_refit, 0.75);
}

TEST(GapBenchTest, BadPairsAndSharesAreNamed) {
  std::mt19937_64 rng(1);
  try {
    MakeGapCase({EffectKind::kCoulombFriction, EffectKind::kCubicStiffness}, rng);
    FAIL() << "two feedback effects accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("feedback"), std::string::npos) << e.what();
  }
  EXPECT_THROW(MakeGapCase({EffectKind::kParameterMismatch, EffectKind::kDeadZone}, rng), std::invalid_argument);
  EXPECT_THROW(MakeGapCase(std::vector<EffectKind>{}, rng), std::invalid_argument);
  EXPECT_THROW(BenchCaseTruth(0, 1.5), std::invalid_argument);
  GapCaseOptions reversed;
  reversed.zeta_min = 0.5;
  reversed.zeta_max = 0.1;
  try {
    MakeGapCase(EffectKind::kNone, rng, reversed);
    FAIL() << "a reversed damping range accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("LO <= HI"), std::string::npos) << e.what();
  }
  GapCaseOptions unstable_noise;
  unstable_noise.noise_pole = 1.0;
  EXPECT_THROW(MakeGapCase(EffectKind::kNone, rng, unstable_noise), std::invalid_argument);
  GapCaseOptions all_process_noise;
  all_process_noise.process_noise = 1.0;  // no output noise left, and a share is below 1
  try {
    MakeGapCase(EffectKind::kNone, rng, all_process_noise);
    FAIL() << "a process-noise share of 1 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("process-noise share"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ScoreGapBench({GapBenchOutcome{}}), std::invalid_argument);
}

TEST(GapBenchTest, PlantFamiliesHaveTheirZerosAndModes) {
  // "zeros": a third-order plant with one real zero, a third of them in the right half-plane;
  // "two-mass": fourth order, two stable complex modes 2–5 times apart, relative degree 2 or 4.
  int rhp = 0, lhp = 0, antiresonant = 0, plain = 0;
  for (uint64_t seed = 1; seed <= 60; ++seed) {
    for (const std::string family : {"zeros", "two-mass"}) {
      std::mt19937_64 rng(seed);
      GapCaseOptions options;
      options.samples = 300;
      options.plants = family;
      const GapCase c = MakeGapCase(EffectKind::kNone, rng, options);
      const Eigen::VectorXcd poles = Poles(c.sim);
      for (long i = 0; i < poles.size(); ++i) EXPECT_LT(poles(i).real(), 0.0) << family << " seed " << seed;
      if (family == "zeros") {
        ASSERT_EQ(c.sim.den.size(), 4);
        ASSERT_EQ(c.sim.num.size(), 2);
        const double zero = -c.sim.num(1) / c.sim.num(0);
        (zero > 0 ? rhp : lhp)++;
        // DC gain positive whatever the zero's side.
        EXPECT_GT(c.sim.num(1) / c.sim.den(3), 0.0);
      } else {
        ASSERT_EQ(c.sim.den.size(), 5);
        ASSERT_TRUE(c.sim.num.size() == 1 || c.sim.num.size() == 3);
        (c.sim.num.size() == 3 ? antiresonant : plain)++;
        std::vector<double> w;
        for (long i = 0; i < poles.size(); ++i)
          if (poles(i).imag() > 0) w.push_back(std::abs(poles(i)));
        ASSERT_EQ(w.size(), 2u) << "seed " << seed;
        const double ratio = std::max(w[0], w[1]) / std::min(w[0], w[1]);
        EXPECT_GE(ratio, 2.0 - 1e-9);
        EXPECT_LE(ratio, 5.0 + 1e-9);
      }
    }
  }
  EXPECT_GT(rhp, 8);
  EXPECT_GT(lhp, 25);
  EXPECT_GT(antiresonant, 15);
  EXPECT_GT(plain, 15);
  std::mt19937_64 rng(1);
  GapCaseOptions bad;
  bad.plants = "three-mass";
  EXPECT_THROW(MakeGapCase(EffectKind::kNone, rng, bad), std::invalid_argument);
}


// GapCase::visibility against closed forms. An |y| sensor on an output that never changes sign
// is y itself (or −y, a gain): nothing is left once an offset and a gain are fitted, whatever
// a diagnosis does (`gap bench --offsets --integrating --combos 1 --pairs any --excitation
// levels --seed 980`, case 49: a cubic spring and an |y| sensor on a rig that walks away from
// zero and stays on one side). A quantiser's rounding error on an output spanning many steps is
// uniform on [−q/2, q/2]: N·q²/12 over σ². And none is +inf.
TEST(GapBenchTest, VisibilityIsWhatNoGainAndOffsetAbsorbAgainstTheNoise) {
  GapCaseOptions options;
  options.offsets = true;
  options.integrating = true;
  options.excitation = "levels";
  {
    const std::vector<EffectKind> truth = BenchCaseTruth(49, 1.0, true);
    ASSERT_EQ(truth, (std::vector<EffectKind>{EffectKind::kCubicStiffness, EffectKind::kSensorNonlinearity}));
    std::mt19937_64 rng(BenchCaseSeed(980, 49));
    const GapCase c = MakeGapCase(truth, rng, options);
    ASSERT_EQ(c.visibility.size(), 2u);
    ASSERT_EQ(c.effects[1].params.back(), 1.0) << "the sensor is |y|";
    EXPECT_GT(c.visibility[0], BenchVisibilityThreshold()) << "the cubic spring shows";
    EXPECT_LT(c.visibility[1], 1e-6) << "the |y| sensor on a one-signed output";
  }
  int quantisers = 0;
  for (int i = 0; i < 40 && quantisers < 3; ++i) {
    const std::vector<EffectKind> truth = BenchCaseTruth(i, 0.0);
    if (truth[0] != EffectKind::kOutputQuantization && truth[0] != EffectKind::kNone) continue;
    std::mt19937_64 rng(BenchCaseSeed(7, i));
    GapCaseOptions plain;
    plain.excitation = "levels";
    const GapCase c = MakeGapCase(truth, rng, plain);
    ASSERT_EQ(c.visibility.size(), 1u);
    if (truth[0] == EffectKind::kNone) {
      EXPECT_TRUE(std::isinf(c.visibility[0]));
      continue;
    }
    ++quantisers;
    const double q = c.effects[0].params[0];
    const double expected = c.validation.y.size() * q * q / 12 / (c.noise_sigma * c.noise_sigma);
    EXPECT_NEAR(c.visibility[0] / expected, 1.0, 0.15) << "case " << i << ", q " << q;
  }
  EXPECT_EQ(quantisers, 3);
}

// GapCase::visibility_refit against a closed form: a static map of a two-valued input is affine
// (a gain and an offset of the command), so the rig's output with it is the output without it
// times a gain plus the response to a constant input — the refit of the linear part and the
// actuator offset take it up exactly. On an integrating rig the second is a ramp, which the
// offset and gain of GapCase::visibility do not absorb (`gap bench --cases 26 --seed 7406
// --integrating --offsets`, cases 5, 6, 19, 20: visibility above the threshold, `ambiguous`).
TEST(GapBenchTest, TheRefitTakesUpAnInputMapOfATwoValuedInputWhichTheGainAndOffsetDoNot) {
  GapCaseOptions options;
  options.offsets = true;
  options.integrating = true;
  options.excitation = "prbs";
  int overstated = 0;
  for (EffectKind k : {EffectKind::kInputSaturation, EffectKind::kDeadZone, EffectKind::kBacklash}) {
    for (int i = 0; i < 2; ++i) {
      std::mt19937_64 rng(BenchCaseSeed(7406, 100 + i));
      const GapCase c = MakeGapCase({k}, rng, options);
      ASSERT_EQ(c.visibility_refit.size(), 1u);
      EXPECT_LT(c.visibility_refit[0], 1e-6 * std::max(1.0, c.visibility[0])) << EffectName(k) << ", draw " << i;
      overstated += c.visibility[0] > BenchVisibilityThreshold();
    }
  }
  EXPECT_GE(overstated, 3) << "the gain and offset alone leave the ramp";
  // A dynamic effect is not affine in the input: the refit leaves most of a delay of a few samples
  // on a first-order rig (single shooting) visible.
  GapCaseOptions plain;
  plain.excitation = "prbs";
  int delays = 0;
  for (int i = 0; i < 40; ++i) {
    if (BenchCaseTruth(i, 0.0)[0] != EffectKind::kTimeDelay) continue;
    ++delays;
    std::mt19937_64 rng(BenchCaseSeed(7406, i));
    const GapCase c = MakeGapCase({EffectKind::kTimeDelay}, rng, plain);
    ASSERT_EQ(c.visibility_refit.size(), 1u);
    EXPECT_LE(c.visibility_refit[0], c.visibility[0] * (1 + 1e-9)) << "a projection on more columns";
    EXPECT_GT(c.visibility_refit[0], BenchVisibilityThreshold()) << "case " << i;
  }
  EXPECT_EQ(delays, 3);
}

}  // namespace
}  // namespace idrig
