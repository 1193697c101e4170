// Plausibility checks of identified models (issue 15). References: poles placed by hand, so
// each case's answer follows from |z|, Re s and arg z directly.
#include <gtest/gtest.h>

#include <cmath>

#include "core/numeric/model/model_checks.h"

namespace idrig {
namespace {

constexpr double kPi = 3.14159265358979323846;

TransferFunction Discrete(const Eigen::VectorXcd& poles, double ts) {
  TransferFunction tf;
  tf.den = PolynomialFromRoots(poles);
  tf.num = Eigen::VectorXd::Ones(1);
  tf.sample_time = ts;
  return tf;
}

std::vector<SolverStatus> Statuses(const std::vector<ModelIssue>& issues) {
  std::vector<SolverStatus> out;
  for (const auto& i : issues) out.push_back(i.status);
  return out;
}

TEST(ModelChecks, StableDiscreteModelWithAGoodFitHasNoIssue) {
  Eigen::VectorXcd p(2);
  p << std::polar(0.9, 0.5), std::polar(0.9, -0.5);
  EXPECT_TRUE(CheckModel(Discrete(p, 0.1), 95.0, {}).empty());
}

TEST(ModelChecks, PoleOnOrOutsideTheUnitCircleIsUnstable) {
  Eigen::VectorXcd p(2);
  p << 1.01, 0.5;
  const auto issues = CheckModel(Discrete(p, 0.1), 99.0, {});
  ASSERT_EQ(Statuses(issues), std::vector<SolverStatus>{SolverStatus::kUnstable});
  EXPECT_NE(issues[0].warning.find("|z| = 1.01"), std::string::npos) << issues[0].warning;
  p << 1.0, 0.5;  // marginal counts as unstable
  EXPECT_EQ(Statuses(CheckModel(Discrete(p, 0.1), 99.0, {})), std::vector<SolverStatus>{SolverStatus::kUnstable});
  ModelCheckOptions o;
  o.expect_stable = false;  // a method identifying unstable plants on purpose
  EXPECT_TRUE(CheckModel(Discrete(p, 0.1), 99.0, o).empty());
}

TEST(ModelChecks, ContinuousPoleWithNonNegativeRealPartIsUnstable) {
  TransferFunction tf;
  tf.num = Eigen::VectorXd::Ones(1);
  tf.den = Eigen::Vector3d(1.0, 0.0, 4.0);  // s² + 4: poles ±2j, Re s = 0
  EXPECT_EQ(Statuses(CheckModel(tf, 99.0, {})), std::vector<SolverStatus>{SolverStatus::kUnstable});
  tf.den = Eigen::Vector3d(1.0, 0.1, 4.0);
  EXPECT_TRUE(CheckModel(tf, 99.0, {}).empty());
}

TEST(ModelChecks, PoleAtTheNyquistFrequency) {
  const double ts = 0.2;
  Eigen::VectorXcd p(2);
  p << std::polar(0.8, 0.95 * kPi), std::polar(0.8, -0.95 * kPi);
  EXPECT_EQ(Statuses(CheckModel(Discrete(p, ts), 90.0, {})), std::vector<SolverStatus>{SolverStatus::kNyquistPole});
  p << std::polar(0.8, 0.85 * kPi), std::polar(0.8, -0.85 * kPi);  // below 90 % of Nyquist
  EXPECT_TRUE(CheckModel(Discrete(p, ts), 90.0, {}).empty());
  p << std::polar(0.45, 0.95 * kPi), std::polar(0.45, -0.95 * kPi);  // |z| < 0.5: a negligible mode
  EXPECT_TRUE(CheckModel(Discrete(p, ts), 90.0, {}).empty());
  // Continuous: |Im s| against π/Ts of the record; without Ts there is no Nyquist frequency.
  TransferFunction tf;
  tf.num = Eigen::VectorXd::Ones(1);
  const double im = 0.95 * kPi / ts;
  tf.den = Eigen::Vector3d(1.0, 2.0, 1.0 + im * im);  // poles −1 ± j·im
  EXPECT_TRUE(CheckModel(tf, 90.0, {}).empty());
  ModelCheckOptions o;
  o.sample_time = ts;
  EXPECT_EQ(Statuses(CheckModel(tf, 90.0, o)), std::vector<SolverStatus>{SolverStatus::kNyquistPole});
}

TEST(ModelChecks, FitBelowTheThresholdIsPoor) {
  Eigen::VectorXcd p(1);
  p << 0.5;
  EXPECT_EQ(Statuses(CheckModel(Discrete(p, 1.0), 49.9, {})), std::vector<SolverStatus>{SolverStatus::kPoorFit});
  EXPECT_TRUE(CheckModel(Discrete(p, 1.0), 50.0, {}).empty());
  EXPECT_TRUE(CheckModel(Discrete(p, 1.0), std::nan(""), {}).empty());  // no fit known
  ModelCheckOptions o;
  o.min_fit_percent = std::nan("");  // check disabled
  EXPECT_TRUE(CheckModel(Discrete(p, 1.0), -1e6, o).empty());
}

TEST(ModelChecks, SeverityOrder) {
  EXPECT_EQ(WorseStatus(SolverStatus::kOk, SolverStatus::kPoorFit), SolverStatus::kPoorFit);
  EXPECT_EQ(WorseStatus(SolverStatus::kUnstable, SolverStatus::kPoorFit), SolverStatus::kUnstable);
  EXPECT_EQ(WorseStatus(SolverStatus::kNotConverged, SolverStatus::kUnstable), SolverStatus::kUnstable);
  EXPECT_EQ(WorseStatus(SolverStatus::kFailed, SolverStatus::kUnstable), SolverStatus::kFailed);
  EXPECT_EQ(WorseStatus(SolverStatus::kIllConditioned, SolverStatus::kNyquistPole), SolverStatus::kNyquistPole);
  SolverStatus s;
  ASSERT_TRUE(ParseSolverStatus("nyquist_pole", &s));
  EXPECT_EQ(s, SolverStatus::kNyquistPole);
  EXPECT_FALSE(ParseSolverStatus("fine", &s));
}

}  // namespace
}  // namespace idrig
