// `idrig identify --method finite-frequency` through the method registry.
#include <gtest/gtest.h>

#include <stdexcept>

#include "core/methods/registry.h"
#include "core/numeric/finite_frequency/finite_frequency.h"
#include "core/numeric/finite_frequency/sine_experiment.h"

namespace idrig {
namespace {

constexpr double kNoiseFree = 1e-4;  // relative, noise-free record after settling

TEST(FiniteFrequencyMethodTest, IdentifiesPlant40FromARecord) {
  TransferFunction plant;
  plant.num = Eigen::Vector2d(-0.4, 1.0);
  plant.den = Eigen::Vector4d(0.2, 1.24, 5.24, 1.0);
  const FiniteFrequencySignal signal = ChooseTestFrequencies(0.2, 5.0, 3, 1.0);  // 0.2, 1, 5
  const int per_period = 1000;
  const double h = signal.BasePeriod() / per_period;
  SineExperimentSetup setup;
  setup.plant = plant;
  for (int i = 0; i < 3; ++i) setup.lines.push_back({signal.Omegas()[i], 0.7, 0.0});
  const auto sim = SimulateSineExperiment(setup, h, 12 * per_period + 1);
  const IoRecord record = MakeIoRecord(sim.u, sim.y, h);
  nlohmann::json options = {{"order", 3},         {"numerator_degree", 1},
                            {"base_omega", 0.2},   {"frequencies", {0.2, 1.0, 5.0}},
                            {"skip_base_periods", 4}, {"filter_time", 8 * signal.BasePeriod()}};
  const MethodReport report = RunMethod("finite-frequency", record, options);
  EXPECT_EQ(report.json["status"], "ok") << report.json["message"];
  const std::vector<double> d = report.json["details"]["d"], k = report.json["details"]["k"];
  EXPECT_NEAR(d[0] / 5.24, 1.0, kNoiseFree);
  EXPECT_NEAR(d[1] / 1.24, 1.0, kNoiseFree);
  EXPECT_NEAR(d[2] / 0.2, 1.0, kNoiseFree);
  EXPECT_NEAR(k[0] / 1.0, 1.0, kNoiseFree);
  EXPECT_NEAR(k[1] / -0.4, 1.0, kNoiseFree);
  // Amplitudes measured from the input when not given.
  const std::vector<double> rho = report.json["details"]["amplitudes"];
  for (double r : rho) EXPECT_NEAR(r, 0.7, 1e-9);
  EXPECT_EQ(report.json["details"]["base_periods"], 8);

  nlohmann::json bad = options;
  bad["frequencies"] = {0.2, 1.0, 5.1};
  EXPECT_THROW(RunMethod("finite-frequency", record, bad), std::invalid_argument);
  bad = options;
  bad["frequency"] = 1;
  EXPECT_THROW(RunMethod("finite-frequency", record, bad), std::invalid_argument);
}

}  // namespace
}  // namespace idrig
