// Sensor steps (core/numeric/signal/level_shifts.h): a reading that jumps to a new level and
// stays there is found where it is, against the sim model's output; the bench's rig records,
// whatever the effect the sim model lacks, the excitation or the plant family, have none.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/numeric/gap/effects.h"
#include "core/numeric/gap/gap_bench.h"
#include "core/numeric/signal/level_shifts.h"

namespace idrig {
namespace {

Eigen::VectorXd SimModelOutput(const GapCase& c, const GapRecord& r) {
  EffectSimulationOptions options;
  options.substeps = 1;
  return SimulateWithEffect(c.sim, Effect{}, r.u, r.sample_time, options);
}

// Every effect (13) and pair, every excitation, the plant families, offsets on: a cut on any of
// these records would split a rig's own behaviour (a gap the diagnosis must see) into records.
TEST(SensorSteps, NoneOnTheBenchsRigRecords) {
  struct Family {
    std::string excitation, plants;
    bool integrating;
    double zeta_min, zeta_max, combos;
  };
  const std::vector<Family> families = {
      {"levels", "", false, 0.15, 0.8, 0.0},     {"prbs", "", false, 0.15, 0.8, 0.0},
      {"rbs", "zeros", false, 0.15, 0.8, 0.0},   {"steps", "two-mass", false, 0.02, 0.1, 0.0},
      {"chirp", "", true, 0.15, 0.8, 0.0},       {"multisine", "", true, 0.15, 0.8, 0.0},
      {"noise", "two-mass", false, 0.15, 0.8, 0.0}, {"levels", "zeros", false, 0.15, 0.8, 1.0},
      {"rbs", "", false, 0.02, 0.1, 1.0}};
  int records = 0;
  for (size_t f = 0; f < families.size(); ++f)
    for (int index = 0; index < 13; ++index) {
      std::mt19937_64 rng(BenchCaseSeed(900 + f, index));
      GapCaseOptions options;
      options.offsets = true;
      options.excitation = families[f].excitation;
      options.plants = families[f].plants;
      options.integrating = families[f].integrating;
      options.zeta_min = families[f].zeta_min;
      options.zeta_max = families[f].zeta_max;
      options.samples = 3000;
      const GapCase c = MakeGapCase(BenchCaseTruth(index, families[f].combos), rng, options);
      for (const GapRecord* r : {&c.estimation, &c.validation}) {
        const auto steps = FindSensorSteps(r->y, SimModelOutput(c, *r));
        EXPECT_TRUE(steps.empty()) << "family " << f << " case " << index << " (" << EffectName(c.truth)
                                   << "): a step of " << steps.front().size << " at sample " << steps.front().sample;
        ++records;
      }
    }
  EXPECT_EQ(records, 2 * 13 * static_cast<int>(families.size()));
}

// A sensor re-zeroed: 8 noise sigmas at a random sample of a record the sim model explains up to
// its offsets (the bench's `none` cases, every excitation): found at that sample, its size within
// two noise sigmas. A dropout that ends (200 samples at another level) and a delay's pulses are
// not steps.
TEST(SensorSteps, AReZeroedSensorIsFoundWhereItSteps) {
  int found = 0, cases = 0;
  for (const std::string excitation : {"levels", "prbs", "rbs", "noise", "chirp"}) {
    for (uint64_t seed = 1; seed <= 3; ++seed) {
      std::mt19937_64 rng(seed * 31 + excitation.size());
      GapCaseOptions options;
      options.offsets = true;
      options.excitation = excitation;
      GapCase c = MakeGapCase(EffectKind::kNone, rng, options);
      std::uniform_int_distribution<long> at_dist(600, c.estimation.y.size() - 600);
      const long at = at_dist(rng);
      const double size = (seed % 2 ? 8 : -8) * c.noise_sigma;
      Eigen::VectorXd y = c.estimation.y;
      y.tail(y.size() - at).array() += size;
      const auto steps = FindSensorSteps(y, SimModelOutput(c, c.estimation));
      ++cases;
      ASSERT_EQ(steps.size(), 1u) << excitation << " seed " << seed << ": step at " << at;
      EXPECT_NEAR(steps[0].sample, at, 1) << excitation << " seed " << seed;
      EXPECT_NEAR(steps[0].size, size, 2 * c.noise_sigma) << excitation << " seed " << seed;
      ++found;
      // The same jump, back after 200 samples: a dropout to another level, not a step.
      Eigen::VectorXd z = c.estimation.y;
      z.segment(at, 200).array() += size;
      EXPECT_TRUE(FindSensorSteps(z, SimModelOutput(c, c.estimation)).empty()) << excitation << " seed " << seed;
    }
  }
  EXPECT_EQ(found, cases);
}

}  // namespace
}  // namespace idrig
