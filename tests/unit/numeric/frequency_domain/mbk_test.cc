// M, B, K from a receptance FRF matrix: product (16)–(19) and difference (20)–(22) methods.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "core/numeric/frequency_domain/mbk.h"

namespace idrig {
namespace {

using Complex = std::complex<double>;

struct System {
  Eigen::Matrix3d M, B, K;
};

System ThreeDof() {
  System s;
  s.M = Eigen::Vector3d(2.0, 1.0, 1.5).asDiagonal();
  s.K << 300, -100, 0, -100, 250, -150, 0, -150, 150;
  // Non-proportional damping: a dashpot between mass 1 and ground only.
  s.B = 0.002 * s.K;
  s.B(0, 0) += 0.8;
  return s;
}

Frf Receptance(const System& s, const Eigen::VectorXd& omega, double noise, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  Frf frf;
  frf.omega = omega;
  for (int k = 0; k < omega.size(); ++k) {
    const Complex p(0.0, omega(k));
    Eigen::Matrix3cd z = p * p * s.M.cast<Complex>() + p * s.B.cast<Complex>() + s.K.cast<Complex>();
    Eigen::Matrix3cd g = z.inverse();  // Eq. (15)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        g(i, j) += noise * std::abs(g(i, j)) * Complex(n01(rng), n01(rng)) / std::sqrt(2.0);
    frf.h.push_back(g);
  }
  return frf;
}

double Rel(const Eigen::MatrixXd& est, const Eigen::MatrixXd& truth) { return (est - truth).norm() / truth.norm(); }

TEST(Mbk, NoiseFreeIsExact) {
  const System s = ThreeDof();
  const Frf frf = Receptance(s, Eigen::VectorXd::LinSpaced(200, 1.0, 40.0), 0.0, 1);
  for (auto method : {MbkMethod::kProduct, MbkMethod::kDifference}) {
    const MbkResult r = IdentifyMbk(frf, method);
    ASSERT_TRUE(r.ok()) << r.message;
    EXPECT_LT(Rel(r.mass, s.M), 1e-8);
    EXPECT_LT(Rel(r.damping, s.B), 1e-8);
    EXPECT_LT(Rel(r.stiffness, s.K), 1e-8);
  }
}

TEST(Mbk, BiasWithOnePercentNoise) {
  // 1 % relative complex noise on every element; mean estimates over 20 seeds.
  const System s = ThreeDof();
  const Eigen::VectorXd omega = Eigen::VectorXd::LinSpaced(200, 1.0, 40.0);
  for (auto method : {MbkMethod::kProduct, MbkMethod::kDifference}) {
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero(), b = m, k = m;
    const int runs = 20;
    for (int seed = 1; seed <= runs; ++seed) {
      const MbkResult r = IdentifyMbk(Receptance(s, omega, 0.01, seed), method);
      m += r.mass / runs;
      b += r.damping / runs;
      k += r.stiffness / runs;
    }
    std::printf("%s method, 1 %% noise, mean of %d runs: relative bias M %.2e, B %.2e, K %.2e\n",
                method == MbkMethod::kProduct ? "product" : "difference", runs, Rel(m, s.M), Rel(b, s.B),
                Rel(k, s.K));
    // Both stay usable (a few % at most); the figures are printed for docs/frequency.md.
    EXPECT_LT(Rel(m, s.M), 0.05);
    EXPECT_LT(Rel(k, s.K), 0.05);
  }
}

TEST(Mbk, BadInput) {
  const System s = ThreeDof();
  Frf frf = Receptance(s, Eigen::VectorXd::LinSpaced(10, 1.0, 40.0), 0.0, 1);
  Frf one_line = frf;
  one_line.omega = one_line.omega.head(1).eval();
  one_line.h.resize(1);
  EXPECT_THROW(IdentifyMbk(one_line, MbkMethod::kProduct), std::invalid_argument);
  Frf rect = frf;
  for (auto& g : rect.h) g = g.leftCols(2).eval();
  EXPECT_THROW(IdentifyMbk(rect, MbkMethod::kProduct), std::invalid_argument);
  Frf nan = frf;
  nan.h[3](1, 1) = Complex(NAN, 0.0);
  EXPECT_THROW(IdentifyMbk(nan, MbkMethod::kDifference), std::invalid_argument);
  Frf singular = frf;
  singular.h[2].setZero();
  EXPECT_THROW(IdentifyMbk(singular, MbkMethod::kDifference), std::invalid_argument);
  Frf mismatched = frf;
  mismatched.h.pop_back();
  EXPECT_THROW(IdentifyMbk(mismatched, MbkMethod::kProduct), std::invalid_argument);
  Frf negative = frf;
  negative.omega(0) = -1.0;
  EXPECT_THROW(IdentifyMbk(negative, MbkMethod::kProduct), std::invalid_argument);
}

}  // namespace
}  // namespace idrig
