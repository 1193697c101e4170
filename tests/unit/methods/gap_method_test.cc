// gap-diagnose through the method registry, as a worker runs it: record split in time, sim
// model in the options, the idrig.gap/1 report under "details".
#include <gtest/gtest.h>

#include "core/io/model_json.h"
#include "core/methods/registry.h"
#include "core/numeric/gap/gap_bench.h"

namespace idrig {
namespace {

TEST(GapMethodTest, RunsThroughTheRegistryWithTheSimModelInTheOptions) {
  std::mt19937_64 rng(70);
  GapCaseOptions options;
  options.samples = 2000;
  options.excitation = "levels";
  const GapCase c = MakeGapCase(EffectKind::kOutputSaturation, rng, options);
  // One continuous experiment: both excitation realisations back to back through the rig.
  Eigen::VectorXd u(4000);
  u << c.estimation.u, c.validation.u;
  const Eigen::VectorXd y = SimulateRig(c.real, c.effect, u, c.estimation.sample_time, c.noise_sigma, rng);
  const IoRecord record = MakeIoRecord(u, y, c.estimation.sample_time);
  const MethodReport report = RunMethod("gap-diagnose", record, {{"sim", ModelToJson(c.sim)}});
  EXPECT_EQ(report.json.at("method"), "gap-diagnose");
  EXPECT_EQ(report.json.at("details").at("format"), "idrig.gap/1");
  EXPECT_EQ(report.json.at("details").at("verdict").at("effect"), "output_saturation");
  EXPECT_GT(report.json.at("fit_percent").get<double>(), 90.0);
  EXPECT_NO_THROW(ModelFromJson(report.json.at("model")));
  try {
    RunMethod("gap-diagnose", record, nlohmann::json::object());
    FAIL() << "no sim model accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("give the sim model"), std::string::npos);
  }
}

}  // namespace
}  // namespace idrig
