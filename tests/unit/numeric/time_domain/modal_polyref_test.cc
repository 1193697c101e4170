// MIMO modal identification from impulse-response matrices, [Balda] (seed 002) section 5.
// Plant: 3-DOF chain m q'' + c q' + k q = B f, unit masses, springs 1000 N/m (ground–1, 1–2,
// 2–3), Rayleigh damping C = α M + β K; forces at masses 1 and 3 (n = 2), displacements of
// all three masses measured (m = 3). Reference values in closed form from the undamped
// eigenproblem K φ = ω² M φ: ω_i, ζ_i = α/(2ω_i) + β ω_i/2, shapes φ_i (real).
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "core/numeric/model/lti_model.h"
#include "core/numeric/time_domain/modal_polyref.h"

namespace idrig {
namespace {

constexpr double kAlpha = 0.5, kBeta = 5e-4;

struct Chain {
  Eigen::Matrix3d k;
  StateSpace ss;
  Eigen::Vector3d omega, zeta;
  Eigen::Matrix3d shapes;  // columns φ_i
};

Chain MakeChain() {
  Chain c;
  c.k << 2000, -1000, 0, -1000, 2000, -1000, 0, -1000, 1000;
  const Eigen::Matrix3d m = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d damping = kAlpha * m + kBeta * c.k;
  Eigen::MatrixXd bf = Eigen::MatrixXd::Zero(3, 2);
  bf(0, 0) = 1.0;
  bf(2, 1) = 1.0;
  c.ss.A = Eigen::MatrixXd::Zero(6, 6);
  c.ss.A.topRightCorner(3, 3).setIdentity();
  c.ss.A.bottomLeftCorner(3, 3) = -c.k;
  c.ss.A.bottomRightCorner(3, 3) = -damping;
  c.ss.B = Eigen::MatrixXd::Zero(6, 2);
  c.ss.B.bottomRows(3) = bf;
  c.ss.C = Eigen::MatrixXd::Zero(3, 6);
  c.ss.C.leftCols(3).setIdentity();
  c.ss.D = Eigen::MatrixXd::Zero(3, 2);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(c.k);  // M = I
  c.omega = eig.eigenvalues().cwiseSqrt();
  c.shapes = eig.eigenvectors();
  for (int i = 0; i < 3; ++i) c.zeta(i) = kAlpha / (2 * c.omega(i)) + kBeta * c.omega(i) / 2;
  return c;
}

struct Errors {
  double freq = 0, damp = 0, mac = 1;
};

Errors Compare(const Chain& c, const ModalPolyrefResult& r) {
  Errors e;
  for (int i = 0; i < 3; ++i) {
    const Mode& mode = r.modes[i];
    e.freq = std::max(e.freq, std::abs(mode.natural_frequency_rad_s - c.omega(i)) / c.omega(i));
    e.damp = std::max(e.damp, std::abs(mode.damping_ratio - c.zeta(i)) / c.zeta(i));
    e.mac = std::min(e.mac, Mac(mode.shape, c.shapes.col(i).cast<std::complex<double>>()));
    std::printf("  mode %d: f = %.5f Hz (true %.5f), zeta = %.5f (true %.5f), MAC %.6f, orders %d\n", i + 1,
                mode.natural_frequency_hz, c.omega(i) / (2 * M_PI), mode.damping_ratio, c.zeta(i),
                Mac(mode.shape, c.shapes.col(i).cast<std::complex<double>>()), mode.orders_found);
  }
  std::printf("  worst: frequency %.4f %%, damping %.3f %%, MAC %.6f\n", 100 * e.freq, 100 * e.damp, e.mac);
  return e;
}

TEST(ModalPolyref, NoiseFreeThreeDof) {
  const Chain c = MakeChain();
  const double ts = 0.01;
  const auto g = ImpulseResponse(c.ss, ts, 600);
  ModalPolyrefOptions o;
  o.modes = 3;
  const ModalPolyrefResult r = IdentifyModalPolyref(g, ts, o);
  std::printf("%s; p(42) = %d, impulse fit %.6f %%\n", r.message.c_str(), r.p_eq42, r.fit_percent_impulse);
  EXPECT_EQ(r.p_eq42, 3);
  ASSERT_EQ(r.modes.size(), 3u);
  const Errors e = Compare(c, r);
  EXPECT_LT(e.freq, 1e-3);
  EXPECT_LT(e.damp, 1e-2);
  EXPECT_GT(e.mac, 0.99);
  EXPECT_GT(r.fit_percent_impulse, 99.9);
  // Participation: force 1 acts on mass 1, force 2 on mass 3, so w_j ∝ (φ_j(1), φ_j(3)).
  for (int i = 0; i < 3; ++i) {
    Eigen::VectorXcd expected(2);
    expected << c.shapes(0, i), c.shapes(2, i);
    EXPECT_GT(Mac(r.modes[i].participation, expected), 0.99);
  }
  // Identified shapes of a proportionally damped chain are mutually orthogonal-ish: small MAC.
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(r.mac(i, j), i == j ? 1.0 : Mac(c.shapes.col(i).cast<std::complex<double>>(), c.shapes.col(j).cast<std::complex<double>>()), 1e-3);
  // Stabilisation diagram: the three modes are stable from p = 3 on.
  int stable_at_max = 0;
  for (const auto& pt : r.stabilisation) stable_at_max += (pt.p == r.p && pt.stable);
  EXPECT_GE(stable_at_max, 3);
  // At exactly p = 3 (42) the eigenproblem has 6 eigenvalues = the 3 pairs.
  ModalPolyrefOptions exact = o;
  exact.p = 3;
  exact.p_max = 6;
  const ModalPolyrefResult r3 = IdentifyModalPolyref(g, ts, exact);
  EXPECT_EQ(r3.eigenvalues_z.size(), 6);
  ASSERT_EQ(r3.modes.size(), 3u);
  EXPECT_LT(Compare(c, r3).freq, 1e-6);
}

TEST(ModalPolyref, OnePercentNoise) {
  const Chain c = MakeChain();
  const double ts = 0.01;
  auto g = ImpulseResponse(c.ss, ts, 600);
  double ms = 0.0;
  for (const auto& gk : g) ms += gk.squaredNorm();
  const double sigma = 0.01 * std::sqrt(ms / (g.size() * 6.0));  // 1 % of the RMS response
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, sigma);
  for (auto& gk : g)
    for (int i = 0; i < gk.size(); ++i) gk.data()[i] += noise(rng);
  ModalPolyrefOptions o;
  o.modes = 3;
  const ModalPolyrefResult r = IdentifyModalPolyref(g, ts, o);
  std::printf("%s; impulse fit %.3f %%\n", r.message.c_str(), r.fit_percent_impulse);
  ASSERT_EQ(r.modes.size(), 3u);
  const Errors e = Compare(c, r);
  EXPECT_LT(e.freq, 0.01);
  EXPECT_LT(e.damp, 0.10);
  EXPECT_GT(e.mac, 0.99);
  // Without telling the number of modes, the stabilisation diagram alone keeps the three.
  const ModalPolyrefResult blind = IdentifyModalPolyref(g, ts, ModalPolyrefOptions{});
  std::printf("without the number of modes: %s\n", blind.message.c_str());
  ASSERT_EQ(blind.modes.size(), 3u);
  EXPECT_LT(Compare(c, blind).freq, 0.01);
}

TEST(ModalPolyref, FromInputOutputRecordByFir) {
  const Chain c = MakeChain();
  const double ts = 0.02;
  const int n = 8000;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> white(0.0, 1.0);
  Eigen::MatrixXd u(n, 2);
  for (int k = 0; k < n; ++k) u.row(k) << white(rng), white(rng);
  Eigen::MatrixXd y = Simulate(c.ss, u, ts);
  const FirEstimate fir = EstimateImpulseResponseFir(MakeIoRecord(u, y, ts), 200);
  std::printf("%s; FIR fit %.3f %%\n", fir.method.c_str(), fir.fit_percent);
  ModalPolyrefOptions o;
  o.modes = 3;
  const ModalPolyrefResult r = IdentifyModalPolyref(fir.impulse_responses, ts, o);
  std::printf("%s\n", r.message.c_str());
  ASSERT_EQ(r.modes.size(), 3u);
  const Errors e = Compare(c, r);
  EXPECT_LT(e.freq, 0.01);
  EXPECT_LT(e.damp, 0.10);
  EXPECT_GT(e.mac, 0.99);
}

TEST(ModalPolyref, BadInputInconsistentSize) {
  const Chain c = MakeChain();
  auto g = ImpulseResponse(c.ss, 0.01, 100);
  g[17] = Eigen::MatrixXd::Zero(2, 2);
  try {
    IdentifyModalPolyref(g, 0.01);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("inconsistent impulse-response matrix size: G(17T) is 2x2"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(IdentifyModalPolyref({}, 0.01), std::invalid_argument);
  // Too few samples for the order asked.
  std::vector<Eigen::MatrixXd> short_g(g.begin(), g.begin() + 8);
  ModalPolyrefOptions o;
  o.p = 6;
  try {
    IdentifyModalPolyref(short_g, 0.01, o);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("too few samples for p = 6"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace idrig

namespace idrig {
namespace {
// The real modal realisation reproduces the impulse responses it was identified from.
TEST(ModalPolyref, ModalStateSpaceReproducesG) {
  const Chain c = MakeChain();
  const double ts = 0.01;
  const auto g = ImpulseResponse(c.ss, ts, 300);
  ModalPolyrefOptions o;
  o.modes = 3;
  const ModalPolyrefResult r = IdentifyModalPolyref(g, ts, o);
  const StateSpace ss = ModalStateSpace(r);
  const auto h = ImpulseResponse(ss, ts, 300);  // discrete: Markov parameters D, CB, CAB, …
  double err = 0.0, ref = 0.0;
  for (int k = 1; k < 300; ++k) {
    err = std::max(err, (h[k] - g[k]).cwiseAbs().maxCoeff());
    ref = std::max(ref, g[k].cwiseAbs().maxCoeff());
  }
  EXPECT_LT(err / ref, 1e-6);
}
}  // namespace
}  // namespace idrig
