// The held-out folds of `auto` (core/methods/auto_method.h): splits at fractions of the input
// energy, checked against closed forms, and the choice on a record whose input is a burst.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/io/model_json.h"
#include "core/methods/auto_method.h"
#include "core/methods/registry.h"
#include "tests/unit/numeric/seed001_plant.h"

namespace idrig {
namespace {

// u[k] = ±amplitude alternating: zero mean over any even number of samples, energy amplitude²
// per sample.
Eigen::VectorXd Alternating(int samples, double amplitude) {
  Eigen::VectorXd u(samples);
  for (int k = 0; k < samples; ++k) u(k) = (k % 2 ? -1.0 : 1.0) * amplitude;
  return u;
}

TEST(AutoFolds, EnergySplitOfAStationaryInputIsTheSampleSplit) {
  // Constant energy per sample: the cumulative energy is k/N, the split at 2/3 is ⌈2N/3⌉.
  const Eigen::MatrixXd u = Alternating(1200, 3.0);
  EXPECT_EQ(InputEnergySplit(u, 2.0 / 3.0, 0, 0), 800);
  EXPECT_EQ(InputEnergySplit(u, 0.75, 0, 0), 900);
  EXPECT_EQ(AutoFoldSplits(u), (std::vector<int>{800, 900}));
}

TEST(AutoFolds, EnergySplitFollowsTheEnvelope) {
  // Amplitude 1 on samples 0..599, 2 on 600..1199: energy 600 + 4·600 = 3000. 2/3 of it (2000)
  // is reached when 600 + 4(s − 600) >= 2000, s = 950; 3/4 (2250): 4(s − 600) >= 1650, s = 1013.
  Eigen::MatrixXd u(1200, 1);
  u.col(0) << Alternating(600, 1.0), Alternating(600, 2.0);
  EXPECT_EQ(InputEnergySplit(u, 2.0 / 3.0, 0, 0), 950);
  EXPECT_EQ(InputEnergySplit(u, 0.75, 0, 0), 1013);
  EXPECT_EQ(InputEnergySplit(u, 0.75, 0, 250), 950);  // clamped to N − min_tail
  // Sample by sample the split is 800 and 900: the sample count gives the estimation part
  // (600 + 4·200)/3000 = 47 % of the energy instead of 2/3.
}

TEST(AutoFolds, EveryInputWeighsTheSameWhateverItsScale) {
  // u1 = ±1 over 1200 samples (share 1/1200 per sample), u2 = ±100 on the first 600 only
  // (share 1/600 per sample there): the summed shares reach 2·(2/3) at s/1200 + s/600 >= 4/3,
  // s = 533.3 → 534. The factor 100 does not enter.
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(1200, 2);
  u.col(0) = Alternating(1200, 1.0);
  u.col(1).head(600) = Alternating(600, 100.0);
  EXPECT_EQ(InputEnergySplit(u, 2.0 / 3.0, 0, 0), 534);
  u.col(1).head(600) = Alternating(600, 1e-3);
  EXPECT_EQ(InputEnergySplit(u, 2.0 / 3.0, 0, 0), 534);
}

TEST(AutoFolds, AnImpulseAtTheStartClampsToOneFoldAtHalfTheRecord) {
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(1000, 1);
  u(0, 0) = 1.0;  // nearly all of the energy in sample 0
  EXPECT_EQ(AutoFoldSplits(u), (std::vector<int>{500}));
  // A constant input has no energy about its mean: split by sample count.
  EXPECT_EQ(InputEnergySplit(Eigen::MatrixXd::Constant(1000, 1, 2.0), 2.0 / 3.0, 0, 0), 667);
}

TEST(AutoFolds, BadArgumentsAreRefused) {
  const Eigen::MatrixXd u = Alternating(100, 1.0);
  EXPECT_THROW(InputEnergySplit(u, 0.0, 0, 0), std::invalid_argument);
  EXPECT_THROW(InputEnergySplit(u, 1.0, 0, 0), std::invalid_argument);
  EXPECT_THROW(InputEnergySplit(u, 0.5, 60, 50), std::invalid_argument);
  EXPECT_THROW(RunMethod("auto", MakeIoRecord(Alternating(29, 1.0), Alternating(29, 1.0), 1.0),
                         nlohmann::json::object()),
               std::invalid_argument);
}

// Seed 001's third-order plant driven by a binary ±1 input (held 4 samples) whose amplitude is
// 0.05 on samples 0..1299 and 1 on 1300..1999 (a burst, as on the DaISy flutter record), output
// noise σ = 0.05: the first 2/3 of the samples carry 5 % of the input energy. The reference is
// the plant's order, 3. Measured on seeds 1..20 (2026-12-01): split by energy, `oe` order 3 on
// 19 of 20 (order 2 on one); split by sample count (option split=samples, the same two folds)
// on 11 of 20 (order 2 on 4, n4sid, arx-oe or oe nk=0 on the others).
IoRecord BurstRecord(std::uint64_t seed) {
  const int samples = 2000;
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution coin(0.5);
  std::normal_distribution<double> noise(0.0, 0.05);
  Eigen::MatrixXd binary(samples, 1), u(samples, 1);
  for (int k = 0; k < samples; ++k) {
    binary(k, 0) = k % 4 == 0 ? (coin(rng) ? 1.0 : -1.0) : binary(k - 1, 0);
    u(k, 0) = binary(k, 0) * (k < 1300 ? 0.05 : 1.0);
  }
  Eigen::MatrixXd y = Simulate(testing::PlantTf(), u, 0.2);
  for (int k = 0; k < samples; ++k) y(k, 0) += noise(rng);
  return MakeIoRecord(u, y, 0.2);
}

TEST(AutoFolds, ABurstRecordGivesThePlantsOrderWhenSplitByEnergy) {
  const Eigen::VectorXcd truth = Poles(DiscretizeZoh(ToStateSpace(testing::PlantTf()), 0.2));
  int right_by_energy = 0, right_by_samples = 0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    const IoRecord record = BurstRecord(seed);
    // Energy 1300·0.05² + 700 = 703.25 (about the mean, which moves it by a few samples): 2/3 of
    // it at 3.25 + (s − 1300) >= 468.8, s = 1766; 3/4 at s = 1825, clamped to N − N/10 = 1800.
    const std::vector<int> splits = AutoFoldSplits(record.u);
    ASSERT_EQ(splits.size(), 2u);
    EXPECT_NEAR(splits[0], 1766, 6);
    EXPECT_EQ(splits[1], 1800);
    const MethodReport r = RunMethod("auto", record, nlohmann::json::object());
    EXPECT_EQ(r.json.at("selection").at("folds").at(0).at("validation").at(0), splits[0]);
    const auto& chosen = r.json.at("selection").at("chosen");
    if (chosen.at("order") == 3 && chosen.at("candidate") == "oe") {
      ++right_by_energy;
      EXPECT_LT(testing::MaxPoleDistance(truth, Poles(ToStateSpace(ModelFromJson(r.json.at("model"))))), 0.03)
          << "seed " << seed;
    }
    const MethodReport by_samples = RunMethod("auto", record, {{"split", "samples"}});
    EXPECT_EQ(by_samples.json.at("selection").at("folds").at(0).at("validation").at(0), 1334);
    const auto& other = by_samples.json.at("selection").at("chosen");
    right_by_samples += other.at("order") == 3 && other.at("candidate") == "oe";
  }
  EXPECT_GE(right_by_energy, 7);
  EXPECT_LT(right_by_samples, right_by_energy);
  EXPECT_THROW(RunMethod("auto", BurstRecord(1), {{"split", "time"}}), std::invalid_argument);
}

}  // namespace
}  // namespace idrig
