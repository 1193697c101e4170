// Subspace identification ([VODM], [Verhaegen]): exact recovery on noise-free MIMO data
// (closed form: the true system), the seed-001 plant under noise, and every bad input.
#include "core/numeric/time_domain/subspace.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/unit/numeric/seed001_plant.h"
#include "tests/unit/numeric/time_domain/identification_test_util.h"

namespace idrig {
namespace {

// A stable 2-input 2-output system of order 4 with a complex pair (0.6 ± 0.5j) and real poles
// 0.9, −0.4.
StateSpace TrueMimo() {
  StateSpace s;
  s.A = Eigen::MatrixXd::Zero(4, 4);
  s.A << 0.6, 0.5, 0, 0, -0.5, 0.6, 0, 0, 0, 0, 0.9, 0, 0, 0, 0, -0.4;
  s.B.resize(4, 2);
  s.B << 1, 0, 0.5, 1, 0, 1, 1, -0.5;
  s.C.resize(2, 4);
  s.C << 1, 0, 1, 0.5, 0, 1, -0.5, 1;
  s.D = Eigen::MatrixXd::Zero(2, 2);
  s.sample_time = 0.1;
  return s;
}

// Sorted-by-matching distance between two pole sets.
double PoleError(const Eigen::VectorXcd& truth, const Eigen::VectorXcd& est) {
  return std::max(testing::MaxPoleDistance(truth, est), testing::MaxPoleDistance(est, truth));
}

TEST(Subspace, RecoversANoiseFreeMimoSystemWithEveryWeighting) {
  const StateSpace truth = TrueMimo();
  const Eigen::MatrixXd u = testing::RandomBinary(2000, 2, 1, 7);
  Eigen::VectorXd x0(4);
  x0 << 1, -1, 0.5, 2;
  const Eigen::MatrixXd y = SimulateFrom(truth, u, x0);
  const IoRecord record = MakeIoRecord(u, y, 0.1);
  for (auto w : {SubspaceWeighting::kMoesp, SubspaceWeighting::kN4sid, SubspaceWeighting::kCva}) {
    SubspaceOptions options;
    options.weighting = w;
    options.max_order = 8;
    const SubspaceResult r = IdentifySubspace(record, options);
    ASSERT_TRUE(r.ok()) << ToString(w) << ": " << r.message;
    EXPECT_EQ(r.order, 4) << ToString(w);
    EXPECT_GT(r.gap, 100.0) << ToString(w);  // CVA: canonical correlations 1 vs the jitter floor
    EXPECT_LT(PoleError(Poles(truth), Poles(r.model)), 1e-6) << ToString(w);
    // Markov parameters C A^k B are invariant under the state basis.
    Eigen::MatrixXd ak = Eigen::MatrixXd::Identity(4, 4), ak_hat = ak;
    for (int k = 0; k < 6; ++k) {
      EXPECT_LT((truth.C * ak * truth.B - r.model.C * ak_hat * r.model.B).norm(), 1e-6) << ToString(w) << " k=" << k;
      ak = ak * truth.A;
      ak_hat = ak_hat * r.model.A;
    }
    // The initial state's free response is recovered too: the fit is exact from x0.
    EXPECT_GT(r.fit_per_output.minCoeff(), 99.9999) << ToString(w);
  }
}

TEST(Subspace, FeedthroughIsEstimatedWhenAsked) {
  StateSpace truth = TrueMimo();
  truth.D << 0.3, 0, -0.2, 0.1;
  const Eigen::MatrixXd u = testing::RandomBinary(1500, 2, 1, 3);
  const IoRecord record = MakeIoRecord(u, SimulateFrom(truth, u, Eigen::VectorXd::Zero(4)), 0.1);
  SubspaceOptions options;
  options.order = 4;
  options.feedthrough = true;
  const SubspaceResult r = IdentifySubspace(record, options);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_LT((r.model.D - truth.D).norm(), 1e-8);
  options.feedthrough = false;
  EXPECT_TRUE(IdentifySubspace(record, options).model.D.isZero());
}

TEST(Subspace, Seed001PlantUnderNoiseHasOrderThreeAndItsPoles) {
  const TransferFunction plant = testing::PlantTf();
  const StateSpace discrete = DiscretizeZoh(ToStateSpace(plant), 0.2);
  const Eigen::MatrixXd u = testing::RandomBinary(2000, 1, 4, 11);
  Eigen::MatrixXd y = SimulateFrom(discrete, u, Eigen::VectorXd::Zero(3));
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (int k = 0; k < y.rows(); ++k) y(k, 0) += noise(rng);
  SubspaceOptions options;
  options.max_order = 8;
  const SubspaceResult r = IdentifySubspace(MakeIoRecord(u, y, 0.2), options);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.order, 3) << r.message;
  // Poles within 0.01 in z of the ZOH poles e^{pTs} (noise σ = 0.01 on a unit-gain-ish plant).
  EXPECT_LT(PoleError(Poles(discrete), Poles(r.model)), 0.01);
  EXPECT_GT(r.fit_percent, 95.0);
}

TEST(Subspace, StabilityIsEnforcedOnRequest) {
  // A slowly growing mode (pole 1.02): the estimate is unstable and says so; with
  // enforce_stability its eigenvalue is reflected to about 1/1.02.
  StateSpace s;
  s.A = Eigen::MatrixXd::Constant(1, 1, 1.02);
  s.B = Eigen::MatrixXd::Constant(1, 1, 1.0);
  s.C = Eigen::MatrixXd::Constant(1, 1, 1.0);
  s.D = Eigen::MatrixXd::Zero(1, 1);
  s.sample_time = 1.0;
  const Eigen::MatrixXd u = testing::RandomBinary(300, 1, 1, 2);
  const IoRecord record = MakeIoRecord(u, SimulateFrom(s, u, Eigen::VectorXd::Zero(1)), 1.0);
  SubspaceOptions options;
  options.order = 1;
  options.block_rows = 5;
  const SubspaceResult unstable = IdentifySubspace(record, options);
  EXPECT_FALSE(unstable.ok());
  EXPECT_NEAR(unstable.spectral_radius, 1.02, 1e-6);
  options.enforce_stability = true;
  const SubspaceResult stable = IdentifySubspace(record, options);
  EXPECT_TRUE(stable.ok()) << stable.message;
  EXPECT_TRUE(stable.stabilised);
  EXPECT_NEAR(stable.spectral_radius, 1.0 / 1.02, 1e-6);
}

TEST(Subspace, BadInputIsRejectedWithAMessage) {
  const Eigen::MatrixXd u = testing::RandomBinary(200, 2, 1, 1);
  const Eigen::MatrixXd y = SimulateFrom(TrueMimo(), u, Eigen::VectorXd::Zero(4));
  auto message_of = [](const IoRecord& record, const SubspaceOptions& options) {
    return testing::InvalidArgumentMessage([&] { IdentifySubspace(record, options); });
  };
  // Too few samples for the block rows: i = 20 with 4 channels needs N >= 200.
  SubspaceOptions twenty;
  twenty.block_rows = 20;
  EXPECT_NE(message_of(MakeIoRecord(u.topRows(150), y.topRows(150), 0.1), twenty).find("too few samples"),
            std::string::npos);
  // A constant input.
  Eigen::MatrixXd constant = u;
  constant.col(1).setConstant(0.5);
  EXPECT_NE(message_of(MakeIoRecord(constant, y, 0.1), {}).find("input 2 is constant"), std::string::npos);
  // Two identical inputs.
  Eigen::MatrixXd twins = u;
  twins.col(1) = twins.col(0);
  EXPECT_NE(message_of(MakeIoRecord(twins, y, 0.1), {}).find("linearly dependent"), std::string::npos);
  // A record with no output columns (columns that do not split into inputs and outputs).
  EXPECT_NE(message_of(MakeIoRecord(u, Eigen::MatrixXd(200, 0), 0.1), {}).find("no output"), std::string::npos);
  // A single sine is persistently exciting of order 2 only: a result, but not an ok one.
  Eigen::MatrixXd sine(400, 1);
  for (int k = 0; k < 400; ++k) sine(k, 0) = std::sin(0.3 * k);
  SubspaceOptions small;
  small.max_order = 2;
  const SubspaceResult weak = IdentifySubspace(MakeIoRecord(sine, sine, 0.1), small);
  EXPECT_FALSE(weak.ok());
  ASSERT_FALSE(weak.warnings.empty());
  EXPECT_NE(weak.warnings[0].find("not persistently exciting"), std::string::npos);
  // Order above what the block rows allow.
  SubspaceOptions high;
  high.order = 12;
  high.block_rows = 4;
  EXPECT_NE(message_of(MakeIoRecord(u, y, 0.1), high).find("too small for order"), std::string::npos);
}

}  // namespace
}  // namespace idrig
