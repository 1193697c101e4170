// The status every method's report carries after RunMethod's checks (issue 15): records from
// difference equations whose poles are known exactly, so ARX recovers them and the expected
// status follows from the pole placement.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "core/methods/registry.h"

namespace idrig {
namespace {

constexpr double kPi = 3.14159265358979323846;

// y[k] = −a1 y[k−1] − a2 y[k−2] + u[k−1] + e[k], u = ±1 random, Ts = 0.1 s.
IoRecord Record(double a1, double a2, int n, double noise, uint64_t seed = 1) {
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution coin;
  std::normal_distribution<double> n01;
  Eigen::MatrixXd u(n, 1), y = Eigen::MatrixXd::Zero(n, 1);
  for (int k = 0; k < n; ++k) u(k, 0) = coin(rng) ? 1.0 : -1.0;
  for (int k = 2; k < n; ++k) y(k, 0) = -a1 * y(k - 1, 0) - a2 * y(k - 2, 0) + u(k - 1, 0);
  for (int k = 0; k < n; ++k) y(k, 0) += noise * n01(rng);
  return MakeIoRecord(u, y, 0.1);
}

std::string Status(const MethodReport& r) { return r.json["status"].get<std::string>(); }

TEST(ReportChecks, StablePlantIsOkWithAnEmptyWarningList) {
  const MethodReport r = RunMethod("arx", Record(-1.2, 0.5, 400, 0.0), {{"order", 2}});
  EXPECT_EQ(Status(r), "ok") << r.json["message"];
  EXPECT_TRUE(r.json["warnings"].is_array());
  EXPECT_TRUE(r.json["warnings"].empty());
}

TEST(ReportChecks, UnstablePlantGivesUnstableWithWarningInJsonAndText) {
  // Poles 1.02 and 0.5: den z² − 1.52 z + 0.51.
  const MethodReport r = RunMethod("arx", Record(-1.52, 0.51, 300, 0.0), {{"order", 2}});
  EXPECT_EQ(Status(r), "unstable") << r.json["message"];
  ASSERT_FALSE(r.json["warnings"].empty());
  EXPECT_NE(r.json["warnings"][0].get<std::string>().find("unstable model"), std::string::npos);
  EXPECT_EQ(r.text.rfind("warning: unstable model", 0), 0u) << r.text.substr(0, 200);
  EXPECT_NE(r.text.find("status: unstable"), std::string::npos);
  EXPECT_NE(r.json["message"].get<std::string>().find("unstable model"), std::string::npos);
}

TEST(ReportChecks, PolePairAtTheNyquistFrequency) {
  // r = 0.8 at ±0.95π: den z² − 2r cos(0.95π) z + r².
  const double a1 = -2 * 0.8 * std::cos(0.95 * kPi), a2 = 0.64;
  const MethodReport r = RunMethod("arx", Record(a1, a2, 400, 0.0), {{"order", 2}});
  EXPECT_EQ(Status(r), "nyquist_pole") << r.json["message"];
  ASSERT_EQ(r.json["warnings"].size(), 1u);
  EXPECT_NE(r.json["warnings"][0].get<std::string>().find("Nyquist"), std::string::npos);
}

TEST(ReportChecks, OutputUnrelatedToTheInputIsAPoorFit) {
  IoRecord rec = Record(-1.2, 0.5, 400, 0.0);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n01;
  for (int k = 0; k < rec.y.rows(); ++k) rec.y(k, 0) = n01(rng);
  const MethodReport r = RunMethod("arx", rec, {{"order", 2}});
  EXPECT_LT(r.json["fit_percent"].get<double>(), 50.0);
  EXPECT_EQ(Status(r), "poor_fit") << r.json["message"];
  // The threshold is an option; null switches the fit check off.
  const MethodReport off = RunMethod("arx", rec, {{"order", 2}, {"min_fit_percent", nullptr}});
  EXPECT_NE(Status(off), "poor_fit");
  EXPECT_TRUE(off.json["checks"]["min_fit_percent"].is_null());
  EXPECT_THROW(RunMethod("arx", rec, {{"order", 2}, {"min_fit_percent", "high"}}), std::invalid_argument);
}

TEST(ReportChecks, SteiglitzMcBrideStoppedEarlyIsNotConverged) {
  const IoRecord rec = Record(-1.2, 0.5, 600, 0.3, 3);
  const MethodReport r = RunMethod("arx-oe", rec, {{"order", 2}, {"oe_iterations", 1}});
  EXPECT_EQ(Status(r), "not_converged") << r.json["message"];
  ASSERT_FALSE(r.json["warnings"].empty());
  EXPECT_EQ(r.json["warnings"][0].get<std::string>().rfind("not_converged: ", 0), 0u) << r.json["warnings"];
  EXPECT_GT(r.json["details"]["oe_relative_change"].get<double>(), 1e-6);
  // With the default 30 iterations the same record converges.
  EXPECT_EQ(Status(RunMethod("arx-oe", rec, {{"order", 2}})), "ok");
}

}  // namespace
}  // namespace idrig
