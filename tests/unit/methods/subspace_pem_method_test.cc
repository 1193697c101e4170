// n4sid, oe, armax, bj and auto through the method registry, as the workers run them.
#include <gtest/gtest.h>

#include <random>

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

}  // namespace
}  // namespace idrig
