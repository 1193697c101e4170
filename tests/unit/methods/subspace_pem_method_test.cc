// n4sid, oe, armax, bj and auto through the method registry, as the workers run them.
#include <gtest/gtest.h>

#include <fstream>
#include <random>
#include <sstream>

#include "core/numeric/validation.h"

#include "core/io/model_json.h"
#include "core/methods/registry.h"
#include "tests/unit/numeric/seed001_plant.h"

namespace idrig {
namespace {

IoRecord Seed001Record(int samples, double sigma, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution coin(0.5);
  std::normal_distribution<double> noise(0.0, sigma);
  Eigen::MatrixXd u(samples, 1);
  for (int k = 0; k < samples; ++k) u(k, 0) = k % 4 == 0 ? (coin(rng) ? 1.0 : -1.0) : u(k - 1, 0);
  Eigen::MatrixXd y = Simulate(testing::PlantTf(), u, 0.2);
  for (int k = 0; k < samples; ++k) y(k, 0) += noise(rng);
  return MakeIoRecord(u, y, 0.2);
}

TEST(SubspacePemMethods, AreRegisteredAndReturnModelsWithStandardErrors) {
  for (const char* name : {"n4sid", "oe", "armax", "bj", "auto"}) EXPECT_NO_THROW(FindMethod(name)) << name;
  const IoRecord record = Seed001Record(1500, 0.01, 1);
  const MethodReport n4sid = RunMethod("n4sid", record, {{"order", 3}, {"weighting", "moesp"}});
  EXPECT_EQ(n4sid.json.at("method"), "n4sid");
  EXPECT_EQ(n4sid.json.at("status"), "ok");
  EXPECT_EQ(n4sid.json.at("details").at("order"), 3);
  EXPECT_NO_THROW(ModelFromJson(n4sid.json.at("model")));
  for (const char* name : {"oe", "armax", "bj"}) {
    const MethodReport r = RunMethod(name, record, {{"order", 3}});
    EXPECT_EQ(r.json.at("status"), "ok") << name << ": " << r.json.at("message");
    const auto& params = r.json.at("details").at("outputs").at(0).at("parameters");
    ASSERT_FALSE(params.empty()) << name;
    for (const auto& p : params) EXPECT_GT(p.at("std").get<double>(), 0.0) << name << " " << p.at("name");
    EXPECT_GT(r.json.at("fit_percent").get<double>(), 90.0) << name;
    const LtiModel model = ModelFromJson(r.json.at("model"));
    EXPECT_LT(testing::MaxPoleDistance(Poles(DiscretizeZoh(ToStateSpace(testing::PlantTf()), 0.2)),
                                       Poles(ToStateSpace(model))), 0.02) << name;
  }
}

TEST(SubspacePemMethods, AutoChoosesTheThirdOrderPlantAndSaysWhy) {
  const MethodReport r = RunMethod("auto", Seed001Record(2000, 0.01, 2), nlohmann::json::object());
  EXPECT_EQ(r.json.at("method"), "auto");
  EXPECT_EQ(r.json.at("selection").at("chosen").at("order"), 3);
  EXPECT_EQ(r.json.at("selection").at("candidates").size(), 30u);  // 5 candidates x orders 1..6
  EXPECT_NE(r.text.find("chosen: "), std::string::npos);
  EXPECT_THROW(RunMethod("auto", Seed001Record(2000, 0.01, 2), {{"candidates", {"nope"}}}), std::invalid_argument);
}

// A DaISy record (whitespace-separated columns), the first `nu` columns inputs, means of the
// first half removed unless `raw`; empty when ../shared/data is absent.
IoRecord Daisy(const std::string& file, int nu, double ts, bool raw = false) {
  std::ifstream in(std::string(IDRIG_SHARED_DIR) + "/data/daisy/" + file);
  std::vector<std::vector<double>> rows;
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    std::vector<double> row;
    for (double v; fields >> v;) row.push_back(v);
    if (!row.empty()) rows.push_back(row);
  }
  if (rows.empty()) return {};
  Eigen::MatrixXd all(rows.size(), rows[0].size());
  for (size_t r = 0; r < rows.size(); ++r)
    for (size_t c = 0; c < rows[0].size(); ++c) all(r, c) = rows[r][c];
  const Eigen::RowVectorXd mean = all.topRows(all.rows() / 2).colwise().mean();
  if (!raw) all.rowwise() -= mean;
  return MakeIoRecord(all.leftCols(nu), all.rightCols(all.cols() - nu), ts);
}

TEST(SubspacePemMethods, MimoDaisyRecordsGetAFitPerOutput) {
  const IoRecord cd = Daisy("CD_player_arm.dat", 2, 1.0), winding = Daisy("winding.dat", 5, 0.1);
  if (cd.NumSamples() == 0 || winding.NumSamples() == 0) GTEST_SKIP() << "../shared/data/daisy not found";
  for (const IoRecord* record : {&cd, &winding}) {
    const int half = record->NumSamples() / 2;
    const MethodReport r = RunMethod("n4sid", Slice(*record, 0, half), {{"order", 5}, {"feedthrough", true}});
    ASSERT_EQ(r.json.at("details").at("fit_percent_per_output").size(), static_cast<size_t>(record->NumOutputs()));
    const Eigen::MatrixXd sim = Simulate(ModelFromJson(r.json.at("model")), record->u, record->sample_time);
    const Eigen::VectorXd fit = FitPercent(record->y.bottomRows(record->NumSamples() - half),
                                           sim.bottomRows(record->NumSamples() - half));
    // Octave 7.3's n4sid (SLICOT) at order 5 on the same split: 69.7 % (CD player arm) and
    // 54.3 % (winding), mean over outputs (docs/subspace_pem.md); idrig within 3 points or above.
    const double octave = record == &cd ? 69.7 : 54.3;
    EXPECT_GT(fit.mean(), octave - 3.0) << (record == &cd ? "CD_player_arm" : "winding") << " fit " << fit.mean();
  }
}

}  // namespace
// DaISy's dryer (heater voltage → outlet air temperature, Ts = 0.08 s) as recorded, at its
// operating point (u ≈ 5 V, y ≈ 5, means not removed), first half: the best score
// on held-out folds goes to n4sid at order 6, whose refit on the whole half has a pole at
// z = -1.049 (unstable, at the Nyquist frequency) and comes back `failed`. auto used to return that
// failed model (and `idrig gap diagnose` then refused it); it must set it aside and return a
// stable model that simulates the second half. (offsets=none keeps the record as it is: by default
// auto now also fits about the record's means, and a model of the deviations wins there.)
TEST(SubspacePemMethods, AutoSetsAsideAWinnerWhoseRefitIsUnstable) {
  const IoRecord dryer = Daisy("dryer.dat", 1, 0.08, /*raw=*/true);
  if (dryer.NumSamples() == 0) GTEST_SKIP() << "../shared/data/daisy not found";
  const int half = dryer.NumSamples() / 2;
  const MethodReport r = RunMethod("auto", Slice(dryer, 0, half), {{"offsets", "none"}});
  EXPECT_NE(r.json.at("status"), "failed") << r.json.value("message", "");
  const LtiModel model = ModelFromJson(r.json.at("model"));
  EXPECT_LT(Poles(ToStateSpace(model)).cwiseAbs().maxCoeff(), 1.0);
  const Eigen::MatrixXd sim = Simulate(model, dryer.u, dryer.sample_time);
  const Eigen::VectorXd fit = FitPercent(dryer.y.bottomRows(dryer.NumSamples() - half),
                                         sim.bottomRows(dryer.NumSamples() - half));
  // With the means removed every method simulates the second half at 85.8 % (Octave's n4sid
  // too: docs/subspace_pem.md); at the operating point a usable model is still above 50 %.
  EXPECT_GT(fit(0), 50.0);
  ASSERT_TRUE(r.json.at("selection").contains("rejected"));
  for (const auto& row : r.json.at("selection").at("rejected"))
    EXPECT_NE(row.at("reason").get<std::string>().find("unstable"), std::string::npos);
}

}  // namespace idrig
