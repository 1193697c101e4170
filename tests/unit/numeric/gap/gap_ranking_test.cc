// The validation-gain test of the gap diagnosis (Diebold–Mariano with a Newey–West standard
// error) under the null: squared-error differences of mean zero, autocorrelated as coloured
// noise makes them. Reference: the nominal level (1 % one-sided), and the closed form of the
// long-run variance of an AR(1) sequence, σ²(1 + ρ)/(1 − ρ).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/numeric/gap/gap_internal.h"

namespace idrig::gap_detail {
namespace {

// Rejection rate at 1 % of ValidationGainZ when d = (y − y_ref)² − (y − y_c)² is AR(1) with
// pole rho and mean zero (y = 0, y_ref² = c + d, y_c² = c).
double RejectionRate(double rho, bool automatic_lag) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> w(0.0, 1.0);
  const long n = 4000;
  const int replications = 400;
  const double z_crit = NormalUpperQuantile(0.01);
  int rejected = 0;
  for (int r = 0; r < replications; ++r) {
    Eigen::VectorXd y = Eigen::VectorXd::Zero(n), y_ref(n), y_c(n);
    double d = w(rng);
    for (long k = 0; k < n; ++k) {
      if (k > 0) d = rho * d + std::sqrt(1 - rho * rho) * w(rng);
      y_ref(k) = std::sqrt(std::max(0.0, 20.0 + d));
      y_c(k) = std::sqrt(20.0);
    }
    if (ValidationGainZ(y, y_ref, y_c, 0.0, automatic_lag) > z_crit) ++rejected;
  }
  return double(rejected) / replications;
}

TEST(GapValidationGainTest, TheAutomaticLagHoldsTheLevelUnderLongCorrelation) {
  // ρ = 0.9: long-run variance 19σ². The fixed Bartlett lag (9 at N = 4000) estimates about
  // 7.3σ², so z is 1.6 times too large and a 1 % test rejects about 7 % of the time; Andrews'
  // plug-in lag (81 here) brings it back near the level.
  const double fixed = RejectionRate(0.9, false), automatic = RejectionRate(0.9, true);
  std::printf("rejection at 1 %%, rho 0.9: fixed lag %.3f, automatic lag %.3f\n", fixed, automatic);
  EXPECT_GT(fixed, 0.04);
  EXPECT_LT(automatic, 0.035);
}

TEST(GapValidationGainTest, WhiteDifferencesKeepTheLevelEitherWay) {
  const double fixed = RejectionRate(0.0, false), automatic = RejectionRate(0.0, true);
  std::printf("rejection at 1 %%, white: fixed lag %.3f, automatic lag %.3f\n", fixed, automatic);
  EXPECT_LT(fixed, 0.035);
  EXPECT_LT(automatic, 0.035);
}

TEST(GapValidationBicTest, ADivergedSimulationRanksLastInsteadOfBreakingTheOrder) {
  // The closed form n ln(MSE·n/(n − k)) + p ln n_est for a finite MSE; +∞ for a simulation that
  // diverged (NaN or ∞), which std::sort can order, where NaN is unordered.
  const double finite = ValidationBic(100, 200, 0.5, 3, 0);
  EXPECT_NEAR(finite, 100 * std::log(0.5) + 3 * std::log(200.0), 1e-9);
  EXPECT_EQ(ValidationBic(100, 200, std::nan(""), 3, 0), std::numeric_limits<double>::infinity());
  EXPECT_EQ(ValidationBic(100, 200, std::numeric_limits<double>::infinity(), 3, 0),
            std::numeric_limits<double>::infinity());
  EXPECT_LT(finite, ValidationBic(100, 200, std::nan(""), 1, 0));
}

// Dynamics no record can show are set aside (not eligible, with a note), first or second in a
// pair: a mode above the Nyquist frequency π/ts, an actuator lag longer than the longest record.
// References: ts and the record's duration; a mode below Nyquist with a peak and a lag within
// the record stay.
TEST(GapMaskTest, DynamicsNoRecordCanShowAreSetAside) {
  Scales scales;
  scales.ts = 0.01;        // Nyquist 314 rad/s
  scales.duration = 40.0;  // 4000 samples
  auto candidate = [](std::vector<Effect> effects) {
    CandidateWork w;
    w.fit.effects = std::move(effects);
    w.fit.effects_std.assign(w.fit.effects.size(), std::vector<double>(2, 0.001));
    return w;
  };
  const Effect backlash{EffectKind::kBacklash, {0.3}};
  std::vector<CandidateWork> work = {
      candidate({{EffectKind::kUnmodelledResonance, {4928.0, 0.43}}, backlash}),  // above Nyquist, first
      candidate({backlash, {EffectKind::kUnmodelledResonance, {320.0, 0.3}}}),   // above Nyquist, second
      candidate({{EffectKind::kActuatorLag, {3.4e8}}}),                           // longer than the record
      candidate({{EffectKind::kUnmodelledResonance, {300.0, 0.3}}}),              // below Nyquist, a peak
      candidate({{EffectKind::kActuatorLag, {39.0}}, backlash}),                  // within the record
  };
  MaskImplausibleDynamics(scales, work);
  const bool expected[] = {true, true, true, false, false};
  for (size_t i = 0; i < work.size(); ++i) {
    EXPECT_EQ(work[i].masked, expected[i]) << "candidate " << i << ": " << work[i].fit.note;
    EXPECT_EQ(work[i].fit.note.empty(), !expected[i]) << "candidate " << i;
  }
}

}  // namespace
}  // namespace idrig::gap_detail

// The candidates' schedule (ParallelFor): every item runs once, in order of decreasing cost on
// one thread (the costliest fit starts first), on two threads as well, and an item that throws
// is named in the error. Reference: the order the costs give, and the item that threw.
namespace idrig::gap_detail {
namespace {

TEST(GapScheduleTest, TheCostliestItemsStartFirstAndEveryItemRunsOnce) {
  const std::vector<double> cost = {1.0, 4.0, 2.0, 0.0, 2.0};
  std::vector<size_t> order;
  ParallelFor(cost.size(), 1, [&](size_t i) { order.push_back(i); }, [](size_t) { return std::string(); },
              [&](size_t i) { return cost[i]; });
  EXPECT_EQ(order, (std::vector<size_t>{1, 2, 4, 0, 3}));  // ties in their given order

  std::vector<std::atomic<int>> runs(40);
  ParallelFor(runs.size(), 2, [&](size_t i) { ++runs[i]; }, [](size_t) { return std::string(); },
              [](size_t i) { return double(i % 7); });
  for (const auto& r : runs) EXPECT_EQ(r.load(), 1);

  try {
    ParallelFor(cost.size(), 2, [](size_t i) { if (i == 2) throw std::runtime_error("no fit"); },
                [](size_t i) { return "fitting item " + std::to_string(i); }, [&](size_t i) { return cost[i]; });
    ADD_FAILURE() << "the failing item was not reported";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fitting item 2 failed: no fit"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace idrig::gap_detail
