// Operating-point offsets in identification (option "offsets", registry.h): a rig run about a
// set point, with an actuator offset ahead of the plant and a sensor offset after it.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "core/io/model_json.h"
#include "core/methods/auto_method.h"
#include "core/methods/registry.h"
#include "core/numeric/validation.h"
#include "tests/unit/numeric/seed001_plant.h"

namespace idrig {
namespace {

constexpr double kTs = 0.2;

// Seed 001's plant driven by a random binary command ±1 plus an actuator offset `actuator`,
// read with a sensor offset `sensor`, output noise sigma. The rig has settled at its operating
// point before the record starts (a warm-up of 200 samples at zero command is dropped).
IoRecord RigRecord(int samples, double actuator, double sensor, double sigma, std::uint64_t seed) {
  const int warm = 200;
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution coin(0.5);
  std::normal_distribution<double> noise(0.0, sigma);
  Eigen::MatrixXd command = Eigen::MatrixXd::Zero(warm + samples, 1);
  for (int k = warm; k < warm + samples; ++k)
    command(k, 0) = (k - warm) % 4 == 0 ? (coin(rng) ? 1.0 : -1.0) : command(k - 1, 0);
  const Eigen::MatrixXd physical = command.array() + actuator;
  Eigen::MatrixXd y = Simulate(testing::PlantTf(), physical, kTs).array() + sensor;
  for (int k = 0; k < y.rows(); ++k) y(k, 0) += noise(rng);
  return MakeIoRecord(command.bottomRows(samples), y.bottomRows(samples), kTs);
}

double PoleError(const nlohmann::json& model) {
  return testing::MaxPoleDistance(Poles(DiscretizeZoh(ToStateSpace(testing::PlantTf()), kTs)),
                                  Poles(ToStateSpace(ModelFromJson(model))));
}

// offsets=mean: the operating point is the record's means (computed here independently), the
// model fits the deviations, and y0 + G(u − u0) simulates the record. The plain fit of the same
// record, which must explain a constant 2.9 from a model without one, is far worse.
TEST(OperatingPoint, MeanOffsetsFitTheDeviationsAndTheModelCarriesThePoint) {
  const IoRecord record = RigRecord(2000, 0.6, 2.0, 0.01, 7);
  const MethodReport r = RunMethod("oe", record, {{"order", 3}, {"offsets", "mean"}});
  ASSERT_EQ(r.json.at("status"), "ok") << r.json.value("message", "");
  const OperatingPoint op = OperatingPointFromModelJson(r.json.at("model"));
  ASSERT_EQ(op.u.size(), 1);
  EXPECT_NEAR(op.u(0), record.u.col(0).sum() / record.NumSamples(), 1e-12);
  EXPECT_NEAR(op.y(0), record.y.col(0).sum() / record.NumSamples(), 1e-12);
  EXPECT_EQ(r.json.at("operating_point").at("source"), "record means");
  EXPECT_LT(PoleError(r.json.at("model")), 0.02);
  const Eigen::MatrixXd sim = SimulateModelJson(r.json.at("model"), record.u, kTs);
  EXPECT_GT(FitPercent(record.y, sim)(0), 95.0);
  EXPECT_NEAR(FitPercent(record.y, sim)(0), r.json.at("fit_percent").get<double>(), 0.5);

  const MethodReport plain = RunMethod("oe", record, {{"order", 3}, {"offsets", "none"}});
  EXPECT_FALSE(plain.json.at("model").contains("operating_point"));
  const Eigen::MatrixXd plain_sim = SimulateModelJson(plain.json.at("model"), record.u, kTs);
  EXPECT_LT(FitPercent(record.y, plain_sim)(0), FitPercent(record.y, sim)(0) - 20.0);
}

// An explicit method given no offsets, on a record whose means stand out: the three treatments
// are fitted before a split and scored after it, and the best is refitted on the whole record;
// each held-out fit is checked here against the same treatment asked for by name on the head.
TEST(OperatingPoint, AnExplicitMethodGivenNoOffsetsChoosesThemWhereTheMeansStandOut) {
  const IoRecord record = RigRecord(2000, 0.6, 2.0, 0.01, 7);
  ASSERT_TRUE(OffsetsStandOut(record));
  for (const char* method : {"oe", "arx", "n4sid"}) {
    const MethodReport r = RunMethod(method, record, {{"order", 3}});
    ASSERT_TRUE(r.json.contains("offsets")) << method;
    const nlohmann::json& fits = r.json.at("offsets").at("validation_fit_percent");
    const int split = r.json.at("offsets").at("split");
    EXPECT_EQ(split, InputEnergySplit(record.u, 2.0 / 3.0, 1000, 200));
    const IoRecord head = Slice(record, 0, split);
    for (const char* treatment : {"none", "mean", "initial"}) {
      const MethodReport named = RunMethod(method, head, {{"order", 3}, {"offsets", treatment}});
      if (fits.at(treatment).is_number()) {
        const Eigen::MatrixXd sim = SimulateModelJson(named.json.at("model"), record.u, kTs);
        const double tail = FitPercent(record.y.bottomRows(2000 - split), sim.bottomRows(2000 - split))(0);
        EXPECT_NEAR(fits.at(treatment).get<double>(), tail, 1e-9) << method << " " << treatment;
      } else {  // the initial "rest" of a binary record is one of its levels: a fit may fail there
        const std::string status = named.json.at("status");
        EXPECT_TRUE(status == "failed" || status == "unstable") << method << " " << treatment << ": " << status;
      }
    }
    ASSERT_TRUE(fits.at("mean").is_number()) << method;
    EXPECT_NE(r.json.at("offsets").at("chosen"), "none") << method;
    EXPECT_TRUE(r.json.at("model").contains("operating_point")) << method;
    const Eigen::MatrixXd sim = SimulateModelJson(r.json.at("model"), record.u, kTs);
    EXPECT_GT(FitPercent(record.y, sim)(0), 85.0) << method;  // arx: equation error, biased under output noise
    if (fits.at("none").is_number()) {  // n4sid's plain fit may not even simulate stably
      EXPECT_GT(fits.at(r.json.at("offsets").at("chosen").get<std::string>()).get<double>(),
                fits.at("none").get<double>() + 20.0) << method;
    }
  }
  // A sensor glitch in the held-out part is bridged once, before the treatments are scored, and
  // reported once: scored as measured, a +50 spike would sink every held-out fit.
  IoRecord glitched = record;
  glitched.y(1900, 0) += 50.0;
  const MethodReport g = RunMethod("oe", glitched, {{"order", 3}});
  ASSERT_EQ(g.json.at("glitches").size(), 1u);
  EXPECT_EQ(g.json.at("glitches")[0].at("sample"), 1900);
  EXPECT_NE(g.json.at("offsets").at("chosen"), "none");
  EXPECT_GT(g.json.at("offsets").at("validation_fit_percent").at("mean").get<double>(), 90.0);
  // About zero: nothing is chosen, the record is fitted as it is.
  const IoRecord about_zero = RigRecord(2000, 0.0, 0.0, 0.01, 7);
  ASSERT_FALSE(OffsetsStandOut(about_zero));
  const MethodReport z = RunMethod("oe", about_zero, {{"order", 3}});
  EXPECT_FALSE(z.json.contains("offsets"));
  EXPECT_FALSE(z.json.at("model").contains("operating_point"));
}

// A sensor offset moves y0 and nothing else: the same record read 37 units higher gives the
// same model, to rounding.
TEST(OperatingPoint, ASensorOffsetMovesOnlyThePoint) {
  const IoRecord a = RigRecord(1500, 0.3, -1.0, 0.02, 8);
  IoRecord b = a;
  b.y.array() += 37.0;
  const nlohmann::json options = {{"order", 3}, {"offsets", "mean"}};
  const nlohmann::json ma = RunMethod("n4sid", a, options).json.at("model");
  const nlohmann::json mb = RunMethod("n4sid", b, options).json.at("model");
  EXPECT_NEAR(mb["operating_point"]["y"][0].get<double>() - ma["operating_point"]["y"][0].get<double>(), 37.0, 1e-9);
  const Eigen::MatrixXd ya = SimulateModelJson(ma, a.u, kTs), yb = SimulateModelJson(mb, a.u, kTs);
  EXPECT_LT(((yb.array() - 37.0) - ya.array()).abs().maxCoeff(), 1e-6);
}

// auto: a record about an operating point has every candidate also fitted about the means of
// its estimation part, and one of those wins; a record about zero is taken as it is.
TEST(OperatingPoint, AutoFitsAboutTheMeansOnlyWhereTheyStandOut) {
  const IoRecord rig = RigRecord(2000, 0.6, 2.0, 0.01, 9);
  ASSERT_TRUE(OffsetsStandOut(rig));
  const MethodReport r = RunMethod("auto", rig, nlohmann::json::object());
  const auto& selection = r.json.at("selection");
  EXPECT_EQ(selection.at("candidates").size(), 60u);  // 10 candidates x orders 1..6
  EXPECT_EQ(selection.at("offsets"), "chosen on the folds");
  const std::string label = selection.at("chosen").at("candidate");
  EXPECT_EQ(label.substr(label.size() - 5), " mean") << label;
  EXPECT_GT(selection.at("chosen").at("validation_fit_percent").get<double>(), 95.0);
  EXPECT_TRUE(r.json.at("model").contains("operating_point"));
  EXPECT_LT(PoleError(r.json.at("model")), 0.05);

  const IoRecord about_zero = RigRecord(2000, 0.0, 0.0, 0.01, 9);
  ASSERT_FALSE(OffsetsStandOut(about_zero));
  const MethodReport z = RunMethod("auto", about_zero, nlohmann::json::object());
  EXPECT_EQ(z.json.at("selection").at("candidates").size(), 30u);
  EXPECT_EQ(z.json.at("selection").at("offsets"), "none (the record is about zero)");
  EXPECT_FALSE(z.json.at("model").contains("operating_point"));
}

// A step test from rest has means that stand out too, but its samples start at the true
// operating point (0, 0): the folds keep the plain fit, which simulates the record from rest.
TEST(OperatingPoint, AStepFromRestKeepsItsPlainFit) {
  const int samples = 400;
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(samples, 1);
  u.bottomRows(samples - 20).setOnes();
  Eigen::MatrixXd y = Simulate(testing::PlantTf(), u, kTs);
  std::mt19937_64 rng(10);
  std::normal_distribution<double> noise(0.0, 0.005);
  for (int k = 0; k < samples; ++k) y(k, 0) += noise(rng);
  const IoRecord step = MakeIoRecord(u, y, kTs);
  ASSERT_TRUE(OffsetsStandOut(step));
  const MethodReport r = RunMethod("auto", step, nlohmann::json::object());
  const std::string label = r.json.at("selection").at("chosen").at("candidate");
  EXPECT_EQ(label.find(" mean"), std::string::npos) << label;
  EXPECT_FALSE(r.json.at("model").contains("operating_point"));
  // oe named with no offsets: not about the means (the initial rest, when kept, is (0, ~0)).
  const MethodReport oe = RunMethod("oe", step, {{"order", 3}});
  EXPECT_NE(oe.json.at("offsets").at("chosen"), "mean");
  if (oe.json.at("model").contains("operating_point")) {
    const OperatingPoint op = OperatingPointFromModelJson(oe.json.at("model"));
    EXPECT_EQ(op.u(0), 0.0);
    EXPECT_LT(std::abs(op.y(0)), 0.01);
  }
}

// A step test from a set point: the rig settled at command 0.6 (sensor offset 2), stepped to 1.6
// at sample 30. offsets=initial takes u0 = 0.6 and y0 = the mean reading before the step
// (computed here independently) and simulates the record from rest there; the record's means
// are not a state the rig was ever at rest in, and about them the same method fits worse.
TEST(OperatingPoint, InitialRestFitsAStepTestFromASetPoint) {
  const int samples = 300, step = 30, warm = 200;
  Eigen::MatrixXd command = Eigen::MatrixXd::Constant(warm + samples, 1, 0.6);
  command.bottomRows(samples - step).setConstant(1.6);
  Eigen::MatrixXd y = Simulate(testing::PlantTf(), command, kTs).array() + 2.0;
  std::mt19937_64 rng(12);
  std::normal_distribution<double> noise(0.0, 0.005);
  for (int k = 0; k < y.rows(); ++k) y(k, 0) += noise(rng);
  const IoRecord record = MakeIoRecord(command.bottomRows(samples), y.bottomRows(samples), kTs);
  const MethodReport r = RunMethod("oe", record, {{"order", 3}, {"offsets", "initial"}});
  ASSERT_EQ(r.json.at("status"), "ok") << r.json.value("message", "");
  const OperatingPoint op = OperatingPointFromModelJson(r.json.at("model"));
  EXPECT_DOUBLE_EQ(op.u(0), 0.6);
  EXPECT_NEAR(op.y(0), record.y.col(0).head(step).sum() / step, 1e-12);
  EXPECT_EQ(r.json.at("operating_point").at("source"), "initial rest");
  EXPECT_LT(PoleError(r.json.at("model")), 0.05);
  const double fit = FitPercent(record.y, SimulateModelJson(r.json.at("model"), record.u, kTs))(0);
  EXPECT_GT(fit, 97.0);
  const MethodReport m = RunMethod("oe", record, {{"order", 3}, {"offsets", "mean"}});
  const double mean_fit = FitPercent(record.y, SimulateModelJson(m.json.at("model"), record.u, kTs))(0);
  std::printf("step from a set point: fit about the initial rest %.2f %%, about the means %.2f %%\n", fit, mean_fit);
  EXPECT_LT(mean_fit, fit - 5.0);
  const MethodReport a = RunMethod("auto", record, {{"offsets", "initial"}});
  const std::string label = a.json.at("selection").at("chosen").at("candidate");
  EXPECT_NE(label.find(" initial"), std::string::npos) << label;
}

TEST(OperatingPoint, BadOffsetsOptionsAndPointsAreNamed) {
  const IoRecord record = RigRecord(300, 0.2, 1.0, 0.01, 11);
  auto message = [&](const std::string& method, const nlohmann::json& options) {
    try {
      RunMethod(method, record, options);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("oe", {{"offsets", "median"}}).find("option 'offsets' must be"), std::string::npos);
  EXPECT_NE(message("oe", {{"offsets", "auto"}}).find("is for the method auto"), std::string::npos);
  EXPECT_NE(message("auto", {{"offsets", 3}}).find("option 'offsets' must be"), std::string::npos);
  try {
    RunMethod("pole-residue", "no-such-frf.csv", {{"offsets", "mean"}});
    ADD_FAILURE() << "offsets on an FRF method was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("take a time record"), std::string::npos) << e.what();
  }
  nlohmann::json model = RunMethod("oe", record, {{"order", 2}, {"offsets", "mean"}}).json.at("model");
  model["operating_point"]["y"] = {1.0, 2.0};
  try {
    SimulateModelJson(model, record.u, kTs);
    ADD_FAILURE() << "a two-output operating point on a one-output model was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("\"operating_point\" has 1 input and 2 output values"), std::string::npos)
        << e.what();
  }
  model["operating_point"] = "zero";
  EXPECT_THROW(OperatingPointFromModelJson(model), std::invalid_argument);
}

}  // namespace
}  // namespace idrig
