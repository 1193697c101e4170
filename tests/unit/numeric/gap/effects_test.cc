// The effect library against closed forms: static maps, the play operator, and the linear and
// feedback effects on plants whose responses are known analytically.
#include "core/numeric/gap/effects.h"

#include <gtest/gtest.h>

#include <cmath>

namespace idrig {
namespace {

TransferFunction FirstOrder(double gain, double pole) {  // gain·pole/(s + pole)
  TransferFunction tf;
  tf.num = Eigen::VectorXd::Constant(1, gain * pole);
  tf.den = Eigen::Vector2d(1.0, pole);
  return tf;
}

TEST(EffectsTest, VocabularyIsTheFixedThirteenNames) {
  const std::vector<std::string> expected = {
      "none", "parameter_mismatch", "time_delay", "actuator_lag", "unmodelled_resonance",
      "input_saturation", "dead_zone", "backlash", "coulomb_friction", "cubic_stiffness",
      "output_saturation", "sensor_nonlinearity", "output_quantization"};
  ASSERT_EQ(AllEffects().size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(EffectName(AllEffects()[i]), expected[i]);
    EXPECT_EQ(EffectFromName(expected[i]), AllEffects()[i]);
  }
}

TEST(EffectsTest, StaticMaps) {
  EXPECT_DOUBLE_EQ(DeadZone(0.3, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(DeadZone(-0.3, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(DeadZone(1.5, 0.5), 1.0);
  EXPECT_DOUBLE_EQ(DeadZone(-2.0, 0.5), -1.5);
  EXPECT_DOUBLE_EQ(SensorMap(2.0, {1.0, 0.5, 0.25, 0.0}), 2.0 + 0.5 * 4 + 0.25 * 8);
  EXPECT_DOUBLE_EQ(SensorMap(-2.0, {3.0, 0.0, 0.0, 1.0}), 6.0);
}

TEST(EffectsTest, BacklashIsThePlayOperator) {
  // Up to 1, back to 0.5, down to −1, back up: the output lags by the play 2r = 0.4.
  Eigen::VectorXd u(7);
  u << 0.0, 1.0, 0.5, 0.9, -1.0, 0.0, 1.0;
  Eigen::VectorXd expected(7);
  expected << 0.0, 0.8, 0.7, 0.7, -0.8, -0.2, 0.8;
  EXPECT_TRUE(Backlash(u, 0.2).isApprox(expected, 1e-12)) << Backlash(u, 0.2).transpose();
}

TEST(EffectsTest, BacklashStartsWherePlayWasLeftBeforeTheRecord) {
  // The play at 0.65 before the record, r = 0.2, by hand: 0.65 stays inside [0.3, 0.7] and
  // [0.4, 0.8], is pushed down to 0.5 by u = 0.3, then up to 0.8 by u = 1.0. From rest (0) the
  // first sample would have taken it to 0.3 instead.
  Eigen::VectorXd u(4);
  u << 0.5, 0.6, 0.3, 1.0;
  Eigen::VectorXd played(4);
  played << 0.65, 0.65, 0.5, 0.8;
  EffectSimulationOptions options;
  options.play_state = 0.65;
  const Eigen::VectorXd y = SimulateWithEffect(FirstOrder(1.0, 3.0), {EffectKind::kBacklash, {0.2}}, u, 0.1, options);
  EXPECT_TRUE(y.isApprox(SimulateWithEffect(FirstOrder(1.0, 3.0), {}, played, 0.1), 1e-12)) << y.transpose();
  options.play_state = NAN;
  EXPECT_THROW(SimulateWithEffect(FirstOrder(1.0, 3.0), {EffectKind::kBacklash, {0.2}}, u, 0.1, options),
               std::invalid_argument);
}

TEST(EffectsTest, EveryStartOfThePlayIsTakenUpOnceItsInputHasMoved2r) {
  // Candidate::Predict chooses where the play was before the record on the segments before the
  // play's input first moves 2r from its first value v0 (PlayStates' `taken_up`): every start in
  // [v0 − r, v0 + r] is then at v ∓ r. After that sample the two simulations below differ only by
  // the free response of the plant's state: for 3/(s + 3) sampled at ts, by a factor
  // a = exp(−3 ts) per sample, exactly; before it, not.
  const double r = 0.2, ts = 0.1, v0 = 0.5;
  Eigen::VectorXd u(60);
  for (long k = 0; k < u.size(); ++k) u(k) = v0 + 0.5 * std::sin(0.05 * k);
  long taken_up = 0;
  while (std::abs(u(taken_up) - v0) < 2 * r) ++taken_up;
  ASSERT_EQ(taken_up, 19);  // 0.5 sin(0.05 k) ≥ 0.4 first at k = 19
  EffectSimulationOptions low, high;
  low.play_state = v0 - r;
  high.play_state = v0 + r;
  const Effect play{EffectKind::kBacklash, {r}};
  const Eigen::VectorXd e = SimulateWithEffect(FirstOrder(1.0, 3.0), play, u, ts, high) -
                            SimulateWithEffect(FirstOrder(1.0, 3.0), play, u, ts, low);
  const double a = std::exp(-3.0 * ts);
  for (long k = taken_up; k + 1 < u.size(); ++k) EXPECT_NEAR(e(k + 1), a * e(k), 1e-9 * std::abs(e(k))) << k;
  double before = 0;
  for (long k = 1; k < taken_up; ++k) before = std::max(before, std::abs(e(k + 1) - a * e(k)));
  EXPECT_GT(before, 1e-3);
}

TEST(EffectsTest, InputMapsInARigsOrderLimitThenDeadZoneThenPlay) {
  const std::vector<Effect> found = {{EffectKind::kBacklash, {0.1}},
                                     {EffectKind::kSensorNonlinearity, {1, 0, 0, 1}},
                                     {EffectKind::kTimeDelay, {0.02}},
                                     {EffectKind::kInputSaturation, {-1, 1}},
                                     {EffectKind::kDeadZone, {0.2}}};
  std::vector<EffectKind> kinds;
  for (const Effect& e : InRigOrder(found)) kinds.push_back(e.kind);
  EXPECT_EQ(kinds, (std::vector<EffectKind>{EffectKind::kInputSaturation, EffectKind::kDeadZone,
                                            EffectKind::kBacklash, EffectKind::kSensorNonlinearity,
                                            EffectKind::kTimeDelay}));
  // The order matters: a limit before the play keeps the play's input inside it, so the play
  // turns back at once when the command does; after the play it clips what the play gives.
  Eigen::VectorXd u(3);
  u << 0.0, 2.0, 0.5;
  const Effect limit{EffectKind::kInputSaturation, {-1, 1}}, play{EffectKind::kBacklash, {0.3}};
  const TransferFunction g = FirstOrder(1.0, 3.0);
  Eigen::VectorXd limit_first(3), play_first(3);
  limit_first << 0.0, 0.7, 0.7;  // play of clamp(u): 0, 1 − 0.3, then clamp(0.5) = 0.5 is within 0.3 of 0.7
  play_first << 0.0, 1.0, 0.8;   // clamp of play(u): play 0, 1.7, 0.8
  EXPECT_TRUE(SimulateWithEffects(g, {limit, play}, u, 0.1).isApprox(SimulateWithEffect(g, {}, limit_first, 0.1), 1e-12));
  EXPECT_TRUE(SimulateWithEffects(g, {play, limit}, u, 0.1).isApprox(SimulateWithEffect(g, {}, play_first, 0.1), 1e-12));
}

TEST(EffectsTest, ActuatorLagMatchesTheClosedFormStepResponse) {
  // 1/((s + 1)(T s + 1)) to a unit step: 1 − (e^(−t) − T e^(−t/T))/(1 − T); ZOH exact at samples.
  const double lag = 0.3, ts = 0.05;
  const int n = 200;
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(n);
  const Eigen::VectorXd y =
      SimulateWithEffect(FirstOrder(1.0, 1.0), {EffectKind::kActuatorLag, {lag}}, u, ts);
  for (int k = 0; k < n; ++k) {
    const double t = k * ts;
    const double exact = 1 - (std::exp(-t) - lag * std::exp(-t / lag)) / (1 - lag);
    EXPECT_NEAR(y(k), exact, 1e-12) << "k = " << k;
  }
}

// The simulator's state update has a fixed-size form for up to 6 states and a general one above
// (EffectSimulator::Step): a chain of k unit lags 1/(s + 1)^k to a unit step, 1 − e^(−t)·Σ_{i<k}
// tⁱ/i!, for k = 3 and k = 8, on the linear path and on the sub-step path of the feedback effects
// (friction with F_c = 0: a force of zero, ZOH still exact at the samples).
TEST(EffectsTest, AChainOfLagsMatchesItsClosedFormOnEitherSizeOfState) {
  const double ts = 0.1;
  const int n = 150;
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(n);
  for (int order : {3, 8}) {
    TransferFunction chain;
    chain.num = Eigen::VectorXd::Ones(1);
    chain.den = Eigen::VectorXd::Zero(order + 1);
    for (int i = 0; i <= order; ++i) chain.den(i) = std::tgamma(order + 1.0) / (std::tgamma(i + 1.0) * std::tgamma(order - i + 1.0));
    for (const Effect& effect : {Effect{EffectKind::kNone, {}}, Effect{EffectKind::kCoulombFriction, {0.0}}}) {
      const Eigen::VectorXd y = SimulateWithEffect(chain, effect, u, ts);
      for (int k = 0; k < n; ++k) {
        const double t = k * ts;
        double sum = 0, term = 1;
        for (int i = 0; i < order; ++i) {
          sum += term;  // tⁱ/i!
          term *= t / (i + 1);
        }
        EXPECT_NEAR(y(k), 1 - std::exp(-t) * sum, 1e-9) << "order " << order << ", " << EffectName(effect.kind) << ", k = " << k;
      }
    }
  }
}

TEST(EffectsTest, TimeDelayShiftsTheResponse) {
  const double ts = 0.1;
  const int n = 100;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
  u.segment(10, 30).setOnes();
  const Eigen::VectorXd plain = SimulateWithEffect(FirstOrder(2.0, 3.0), {}, u, ts);
  const Eigen::VectorXd delayed =
      SimulateWithEffect(FirstOrder(2.0, 3.0), {EffectKind::kTimeDelay, {0.7}}, u, ts);
  EXPECT_TRUE(delayed.tail(n - 7).isApprox(plain.head(n - 7), 1e-12));
  EXPECT_TRUE(delayed.head(7).isZero(0));
  // A fractional delay of 0.25 Ts: first-order step response 2(1 − e^(−3(t − τ))) for t > τ.
  const Eigen::VectorXd step =
      SimulateWithEffect(FirstOrder(2.0, 3.0), {EffectKind::kTimeDelay, {0.025}}, Eigen::VectorXd::Ones(n), ts);
  for (int k = 1; k < n; ++k) EXPECT_NEAR(step(k), 2 * (1 - std::exp(-3 * (k * ts - 0.025))), 1e-12);
}

// Beside a feedback effect the simulator runs in sub-steps with the force inside; a delay there
// keeps its fractional part (the drive holds the previous command for that share of the sample).
// With a cubic spring too weak to matter, the response must be the exact ZOH discretisation's with
// the fractional delay (the linear path, an independent method): to rounding where the instant
// falls on a sub-step's edge (2.5 and 3.75 samples at 16 sub-steps), within 10^-4 of the peak where
// a sub-step is blended (0.3). Rounded to whole samples, as it was, 2.5 samples read as 3 and the
// fit's cost was a staircase in τ.
TEST(EffectsTest, ADelayBesideAFeedbackEffectKeepsItsFractionalPart) {
  TransferFunction plant;  // 25/(s² + 5s + 25)
  plant.num = Eigen::VectorXd::Constant(1, 25.0);
  plant.den = Eigen::Vector3d(1.0, 5.0, 25.0);
  const double ts = 0.02;
  const int n = 400;
  Eigen::VectorXd u(n);
  for (int k = 0; k < n; ++k) u(k) = (k / 37) % 2 == 0 ? 1.0 : -0.6;
  const double peak = SimulateWithEffect(plant, {}, u, ts).cwiseAbs().maxCoeff();
  for (const double samples : {0.3, 1.0, 2.5, 3.75}) {
    const Effect delay{EffectKind::kTimeDelay, {samples * ts}};
    const Eigen::VectorXd exact = SimulateWithEffect(plant, delay, u, ts);
    EffectSimulationOptions fine;
    fine.substeps = 16;
    const Eigen::VectorXd fed =
        SimulateWithEffects(plant, {delay, Effect{EffectKind::kCubicStiffness, {1e-12}}}, u, ts, fine);
    EXPECT_LT((fed - exact).cwiseAbs().maxCoeff(), 1e-4 * peak) << samples << " samples";
  }
}

// A delay far beyond any record (a delay candidate's fit wandering to its parameter bound, on
// an integrating plant) was an 85 TB delay line and an OOM kill; now a clear error.
TEST(EffectsTest, ADelayOfMoreThanAHundredMillionSamplesIsRefusedNotAllocated) {
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(50);
  try {
    SimulateWithEffect(FirstOrder(2.0, 3.0), {EffectKind::kTimeDelay, {1e12}}, u, 0.01);
    FAIL() << "a 10^14-sample delay was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("more than 10^8"), std::string::npos) << e.what();
  }
  // Up to the bound it is a plain shift: 10^4 s at 100 Hz delays 50 samples out of the record.
  EXPECT_TRUE(SimulateWithEffect(FirstOrder(2.0, 3.0), {EffectKind::kTimeDelay, {1e4}}, u, 0.01).isZero(0));
}

TEST(EffectsTest, ResonanceKeepsTheStaticGainAndSaturationsClip) {
  const int n = 4000;
  const Eigen::VectorXd u = Eigen::VectorXd::Constant(n, 1.5);
  const auto plant = FirstOrder(2.0, 1.0);
  const Eigen::VectorXd y = SimulateWithEffect(plant, {EffectKind::kUnmodelledResonance, {20.0, 0.1}}, u, 0.01);
  EXPECT_NEAR(y(n - 1), 3.0, 1e-9);
  const Eigen::VectorXd clipped_in =
      SimulateWithEffect(plant, {EffectKind::kInputSaturation, {-1.0, 1.0}}, u, 0.01);
  EXPECT_NEAR(clipped_in(n - 1), 2.0, 1e-9);
  const Eigen::VectorXd clipped_out =
      SimulateWithEffect(plant, {EffectKind::kOutputSaturation, {-1.0, 2.5}}, u, 0.01);
  EXPECT_NEAR(clipped_out(n - 1), 2.5, 1e-12);
  EXPECT_LE(clipped_out.maxCoeff(), 2.5);
  const Eigen::VectorXd dead = SimulateWithEffect(plant, {EffectKind::kDeadZone, {0.5}}, u, 0.01);
  EXPECT_NEAR(dead(n - 1), 2.0, 1e-9);
  const Eigen::VectorXd quantised =
      SimulateWithEffect(plant, {EffectKind::kOutputQuantization, {0.4}}, u, 0.01);
  EXPECT_NEAR(quantised(n - 1), 3.2, 1e-12);  // 3.0 rounds to 8·0.4
}

TEST(EffectsTest, CubicStiffnessSettlesAtTheRootOfTheStaticBalance) {
  // Mass–spring–damper ω²/(s² + 2ζωs + ω²) (unit static gain) with u_eff = u − k3 y³ and
  // constant u: the rest point solves y = u − k3 y³.
  TransferFunction plant;
  plant.num = Eigen::VectorXd::Constant(1, 25.0);
  plant.den = Eigen::Vector3d(1.0, 5.0, 25.0);
  const double u0 = 2.0, k3 = 0.5;
  const Eigen::VectorXd y = SimulateWithEffect(plant, {EffectKind::kCubicStiffness, {k3}},
                                               Eigen::VectorXd::Constant(3000, u0), 0.005);
  double root = 1.0;  // Newton on k3 y³ + y − u0 = 0
  for (int i = 0; i < 50; ++i) root -= (k3 * root * root * root + root - u0) / (3 * k3 * root * root + 1);
  EXPECT_NEAR(y(y.size() - 1), root, 1e-6);
}

TEST(EffectsTest, CoulombFrictionReducesTheDrivingForce) {
  // Position of a damped mass 1/(s(s + c)): at constant force u > F_c the velocity settles at
  // (u − F_c)/c.
  TransferFunction plant;
  plant.num = Eigen::VectorXd::Constant(1, 1.0);
  plant.den = Eigen::Vector3d(1.0, 2.0, 0.0);
  const double u0 = 1.0, friction = 0.3, ts = 0.01;
  const Eigen::VectorXd y = SimulateWithEffect(plant, {EffectKind::kCoulombFriction, {friction}},
                                               Eigen::VectorXd::Constant(2000, u0), ts);
  const double velocity = (y(1999) - y(1998)) / ts;
  EXPECT_NEAR(velocity, (u0 - friction) / 2.0, 1e-6);
}

TEST(EffectsTest, CoulombFrictionHoldsAMassBelowItsBreakawayForce) {
  // Filippov's solution of m v' = u − c v − F_c·sign(v) from rest with |u| < F_c: v ≡ 0. The
  // explicit F_c·sign(v) rule chatters there and creeps; the stick rule must not.
  TransferFunction plant;
  plant.num = Eigen::VectorXd::Constant(1, 1.0);
  plant.den = Eigen::Vector3d(1.0, 2.0, 0.0);
  for (int substeps : {1, 4, 16}) {
    const Eigen::VectorXd y = SimulateWithEffect(plant, {EffectKind::kCoulombFriction, {0.3}},
                                                 Eigen::VectorXd::Constant(500, 0.25), 0.01, {substeps});
    EXPECT_LT(y.cwiseAbs().maxCoeff(), 1e-12) << substeps << " sub-steps";
  }
}

TEST(EffectsTest, CoulombFrictionStopsAMassWhereTheClosedFormSays) {
  // 1/(s(s + c)) driven by u0 for T1 (velocity settles at (u0 − F)/c), then u = 0: v(t) =
  // (v1 + F/c) e^{−ct} − F/c until it reaches 0 at t* = ln(1 + c v1/F)/c, and then it stays at
  // rest. Final position = y(T1) + [(v1 + F/c)(1 − e^{−ct*}) − F t*]/c.
  TransferFunction plant;
  plant.num = Eigen::VectorXd::Constant(1, 1.0);
  plant.den = Eigen::Vector3d(1.0, 2.0, 0.0);
  const double c = 2.0, u0 = 1.0, friction = 0.3, ts = 0.01;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3000);
  u.head(1500).setConstant(u0);
  for (int substeps : {4, 64}) {
    const Eigen::VectorXd y =
        SimulateWithEffect(plant, {EffectKind::kCoulombFriction, {friction}}, u, ts, {substeps});
    const double v1 = (y(1500) - y(1499)) / ts;  // (u0 − F)/c to 1e-6 after 15 s
    ASSERT_NEAR(v1, (u0 - friction) / c, 1e-5);
    const double t_stop = std::log(1 + c * v1 / friction) / c;
    const double travel = ((v1 + friction / c) * (1 - std::exp(-c * t_stop)) - friction * t_stop) / c;
    // y(1501) is the first sample after u falls; one sample of ZOH skew → tolerance ~ v1·ts².
    EXPECT_NEAR(y(2999) - y(1500), travel, 2e-3) << substeps << " sub-steps";
    EXPECT_EQ(y(2999), y(2500)) << "no creep once stopped (" << substeps << " sub-steps)";
  }
}

// A drive lag in front of a damped mass: G = 1/(τs + 1) · 1/(s(s + c)), relative degree 3.
static TransferFunction LagThenMass(double tau, double c, double gain = 1.0) {
  TransferFunction plant;
  plant.num = Eigen::VectorXd::Constant(1, gain / tau);
  plant.den = Eigen::Vector4d(1.0, c + 1.0 / tau, c / tau, 0.0);
  return plant;
}

TEST(EffectsTest, AboveRelativeDegreeTwoTheForceActsOnTheSlowestTwoPoles) {
  // The mass 1/(s(s + c)) and the drive 1/(τs + 1) are recovered from their product, drive(0) = 1
  // (the gain stays with the mechanics), and their product is the plant again.
  const double tau = 0.05, c = 2.0, gain = 3.0;
  const ForcePath path = SplitAtForce(LagThenMass(tau, c, gain));
  ASSERT_TRUE(path.split);
  ASSERT_EQ(path.mechanics.den.size(), 3);
  EXPECT_NEAR(path.mechanics.den(1), c, 1e-9);
  EXPECT_NEAR(path.mechanics.den(2), 0.0, 1e-9);
  EXPECT_NEAR(path.mechanics.num(0), gain, 1e-9);
  EXPECT_NEAR(std::abs(FrequencyResponse(path.drive, 0.0)), 1.0, 1e-12);
  for (double w : {0.1, 1.0, 30.0})
    EXPECT_NEAR(std::abs(FrequencyResponse(path.drive, w) * FrequencyResponse(path.mechanics, w) -
                         FrequencyResponse(LagThenMass(tau, c, gain), w)),
                0.0, 1e-9 * std::abs(FrequencyResponse(LagThenMass(tau, c, gain), w)));
  // A complex pair slower than the real pole is the mechanics; relative degree 2 is not split.
  TransferFunction resonant;
  resonant.num = Eigen::VectorXd::Constant(1, 50.0);
  resonant.den = PolynomialFromRoots((Eigen::VectorXcd(3) << std::complex<double>(-0.5, 3.0),
                                      std::complex<double>(-0.5, -3.0), -20.0).finished());
  const ForcePath r = SplitAtForce(resonant);
  ASSERT_TRUE(r.split);
  EXPECT_NEAR(r.mechanics.den(1), 1.0, 1e-9);
  EXPECT_NEAR(r.mechanics.den(2), 9.25, 1e-9);
  EXPECT_FALSE(SplitAtForce(FirstOrder(1.0, 1.0)).split);
}

TEST(EffectsTest, FrictionBehindADriveLagHoldsBelowBreakawayAndSlidesAtTheClosedFormSpeed) {
  // Friction acts on the mass behind the lag: at constant u the drive's force tends to u, so
  // below F_c the mass does not move, above it the speed settles at (u − F_c)/c —
  // and neither depends on the sub-step (a relay behind the lag would chatter by the sub-step).
  const double tau = 0.05, c = 2.0, friction = 0.3, ts = 0.01;
  for (int substeps : {1, 4, 16}) {
    const Eigen::VectorXd held = SimulateWithEffect(LagThenMass(tau, c), {EffectKind::kCoulombFriction, {friction}},
                                                    Eigen::VectorXd::Constant(500, 0.25), ts, {substeps});
    // The friction force is held over a sub-step while the drive's force still rises, so the
    // mass is brought back to rest at each sub-step's end: a creep of second order in the
    // sub-step (2·10⁻⁶ at one sub-step, where the mass without friction would travel ~15).
    EXPECT_LT(held.cwiseAbs().maxCoeff(), 3e-6 / (substeps * substeps)) << substeps << " sub-steps";
    const Eigen::VectorXd y = SimulateWithEffect(LagThenMass(tau, c), {EffectKind::kCoulombFriction, {friction}},
                                                 Eigen::VectorXd::Constant(2000, 1.0), ts, {substeps});
    EXPECT_NEAR((y(1999) - y(1998)) / ts, (1.0 - friction) / c, 1e-6) << substeps << " sub-steps";
  }
}

TEST(EffectsTest, BadEffectsAreRejectedWithTheirNames) {
  const auto plant = FirstOrder(1.0, 1.0);
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(10);
  auto message = [&](const Effect& e) {
    try {
      SimulateWithEffect(plant, e, u, 0.1);
    } catch (const std::invalid_argument& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message({EffectKind::kDeadZone, {}}).find("dead_zone takes 1 parameters, got 0"), std::string::npos);
  EXPECT_NE(message({EffectKind::kBacklash, {-0.1}}).find("r must be >= 0"), std::string::npos);
  EXPECT_NE(message({EffectKind::kInputSaturation, {1.0, -1.0}}).find("lower limit"), std::string::npos);
  EXPECT_NE(message({EffectKind::kOutputQuantization, {0.0}}).find("q must be > 0"), std::string::npos);
  EXPECT_NE(message({EffectKind::kTimeDelay, {NAN}}).find("not finite"), std::string::npos);
  try {
    EffectFromName("stiction");
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("unknown effect 'stiction'"), std::string::npos);
  }
}

}  // namespace
}  // namespace idrig

#include "core/io/gap_json.h"

namespace idrig {
namespace {

TEST(EffectJsonTest, RoundTripAndClearErrors) {
  const Effect backlash{EffectKind::kBacklash, {0.25}};
  const Effect back = EffectFromJson(EffectToJson(backlash));
  EXPECT_EQ(back.kind, EffectKind::kBacklash);
  EXPECT_EQ(back.params, backlash.params);
  const Effect sensor = EffectFromJson({{"effect", "sensor_nonlinearity"}, {"params", {{"a3", 0.1}}}});
  EXPECT_EQ(sensor.params, (std::vector<double>{1.0, 0.0, 0.1, 0.0}));
  auto error = [](const nlohmann::json& j) {
    try {
      EffectFromJson(j);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error({{"effect", "dead_zone"}}).find("missing parameter 'd'"), std::string::npos);
  EXPECT_NE(error({{"effect", "dead_zone"}, {"params", {{"width", 1}}}}).find("unknown parameter 'width'"),
            std::string::npos);
  EXPECT_NE(error({{"effect", "stiction"}}).find("unknown effect 'stiction'"), std::string::npos);
  EXPECT_NE(error({{"effect", "dead_zone"}, {"params", {{"d", -1}}}}).find("d must be >= 0"), std::string::npos);
}

}  // namespace
}  // namespace idrig
