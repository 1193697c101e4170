// LTI model core: conversions, poles/zeros/residues, frequency response, exact ZOH simulation.
// References are closed forms.
#include "core/numeric/model/lti_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <vector>

namespace idrig {
namespace {

constexpr double kTight = 1e-10;

TEST(LtiModel, FirstOrderStepResponseIsExactUnderZoh) {
  // W(s) = 2/(3s + 1): y(kT) = 2(1 − e^{−kT/3}) for a unit step held from t = 0.
  TransferFunction tf{Eigen::VectorXd::Constant(1, 2.0), Eigen::Vector2d(3.0, 1.0)};
  const Eigen::MatrixXd y = StepResponse(ToStateSpace(tf), 0.1, 50);
  for (int k = 0; k < 50; ++k) EXPECT_NEAR(y(k, 0), 2.0 * (1.0 - std::exp(-k * 0.1 / 3.0)), kTight);
}

TEST(LtiModel, FractionalDelayIsExact) {
  // W(s) = e^{−0.25 s}/(s + 1) with Ts = 0.1: y(t) = 1 − e^{−(t − 0.25)} for t >= 0.25.
  TransferFunction tf{Eigen::VectorXd::Ones(1), Eigen::Vector2d(1.0, 1.0), 0.0, 0.25};
  const Eigen::MatrixXd y = StepResponse(ToStateSpace(tf), 0.1, 40);
  for (int k = 0; k < 40; ++k) {
    const double t = k * 0.1;
    EXPECT_NEAR(y(k, 0), t < 0.25 ? 0.0 : 1.0 - std::exp(-(t - 0.25)), kTight) << "k = " << k;
  }
}

TEST(LtiModel, TransferFunctionRoundTripAndPolesZerosResidues) {
  // W(s) = (s + 3)/((s + 1)(s + 2)) = 2/(s + 1) − 1/(s + 2).
  TransferFunction tf{Eigen::Vector2d(1.0, 3.0), Eigen::Vector3d(1.0, 3.0, 2.0)};
  const TransferFunction back = ToTransferFunction(ToStateSpace(tf));
  EXPECT_LT((back.num - tf.num).cwiseAbs().maxCoeff(), kTight);
  EXPECT_LT((back.den - tf.den).cwiseAbs().maxCoeff(), kTight);
  const PartialFractions pf = Residues(tf);
  for (int i = 0; i < 2; ++i) {
    const double p = pf.poles(i).real();
    EXPECT_NEAR(pf.residues(i).real(), std::abs(p + 1.0) < 1e-9 ? 2.0 : -1.0, kTight);
  }
  EXPECT_NEAR(Zeros(tf)(0).real(), -3.0, kTight);
  EXPECT_NEAR(DcGain(ToStateSpace(tf))(0, 0), 1.5, kTight);
  // H(jω) against the closed form.
  const std::complex<double> jw(0.0, 2.0);
  EXPECT_LT(std::abs(FrequencyResponse(tf, 2.0) - (jw + 3.0) / ((jw + 1.0) * (jw + 2.0))), kTight);
  EXPECT_LT(std::abs(FrequencyResponse(ToStateSpace(tf), 2.0)(0, 0) - FrequencyResponse(tf, 2.0)), kTight);
}

TEST(LtiModel, DiscreteImpulseIsMarkovParameters) {
  // y[k] = 0.5 y[k−1] + u[k−1]: impulse response 0, 1, 0.5, 0.25, …
  TransferFunction tf{Eigen::VectorXd::Ones(1), Eigen::Vector2d(1.0, -0.5), 0.1};
  const auto g = ImpulseResponse(ToStateSpace(tf), 0.1, 5);
  EXPECT_NEAR(g[0](0, 0), 0.0, kTight);
  for (int k = 1; k < 5; ++k) EXPECT_NEAR(g[k](0, 0), std::pow(0.5, k - 1), kTight);
  EXPECT_TRUE(IsStable(ToStateSpace(tf)));
}

TEST(LtiModel, ContinuousImpulseSamplesAreClosedForm) {
  TransferFunction tf{Eigen::VectorXd::Ones(1), Eigen::Vector3d(1.0, 0.4, 4.04)};  // poles −0.2 ± 2j
  const auto g = ImpulseResponse(ToStateSpace(tf), 0.05, 30);
  for (int k = 0; k < 30; ++k) {
    const double t = k * 0.05;
    EXPECT_NEAR(g[k](0, 0), std::exp(-0.2 * t) * std::sin(2.0 * t) / 2.0, kTight);
  }
}

TEST(LtiModel, PolynomialProductIsThePolynomialOfBothRootSets) {
  // (s + 2)(s² + 2s + 5) = s³ + 4s² + 9s + 10, by hand; and the product of two monic polynomials
  // built from roots is the one built from the union of the roots.
  const Eigen::VectorXd p = PolynomialProduct(Eigen::Vector2d(1, 2), Eigen::Vector3d(1, 2, 5));
  ASSERT_EQ(p.size(), 4);
  EXPECT_DOUBLE_EQ(p(0), 1);
  EXPECT_DOUBLE_EQ(p(1), 4);
  EXPECT_DOUBLE_EQ(p(2), 9);
  EXPECT_DOUBLE_EQ(p(3), 10);
  using C = std::complex<double>;
  Eigen::VectorXcd a(3), b(2), both(5);
  a << C(-1, 3), C(-1, -3), C(-0.5, 0);
  b << C(-7, 0), C(2, 0);
  both << a, b;
  const Eigen::VectorXd direct = PolynomialFromRoots(both);
  const Eigen::VectorXd product = PolynomialProduct(PolynomialFromRoots(a), PolynomialFromRoots(b));
  ASSERT_EQ(product.size(), direct.size());
  for (int i = 0; i < direct.size(); ++i) EXPECT_NEAR(product(i), direct(i), 1e-12 * (1 + std::abs(direct(i))));
  EXPECT_EQ(PolynomialProduct(Eigen::VectorXd(), Eigen::Vector2d(1, 1)).size(), 0);
}

TEST(LtiModel, ZohOfAHighOrderModelAtAHighSampleRateIsExact) {
  // Sixth order at 51.2 kHz (the Wiener–Hammerstein benchmark's rate): denominator
  // coefficients up to 1e25, where the matrix exponential of the companion realisation without
  // balancing came out Φ = 0. W(s) = Π(−p_i)/Π(s − p_i) (unit DC gain), step response
  // y(t) = 1 + Σ r_i/p_i e^{p_i t}, r_i = Π_j(−p_j)/Π_{j≠i}(p_i − p_j): a closed form.
  using C = std::complex<double>;
  const std::vector<C> p = {C(-5e4, 0), C(-9e3, 0), C(-6e3, 1e4), C(-6e3, -1e4), C(-2.5e3, 9e3), C(-2.5e3, -9e3)};
  Eigen::VectorXcd roots(6);
  C gain = 1;
  for (int i = 0; i < 6; ++i) roots(i) = p[i], gain *= -p[i];
  TransferFunction tf{Eigen::VectorXd::Constant(1, gain.real()), PolynomialFromRoots(roots)};
  ASSERT_GT(tf.den.maxCoeff(), 1e24);
  const double ts = 1.0 / 51200;
  const Eigen::MatrixXd y = StepResponse(ToStateSpace(tf), ts, 200);
  for (int k = 0; k < 200; ++k) {
    C exact = 1;
    for (int i = 0; i < 6; ++i) {
      C r = gain;
      for (int j = 0; j < 6; ++j)
        if (j != i) r /= p[i] - p[j];
      exact += r / p[i] * std::exp(p[i] * (k * ts));
    }
    EXPECT_NEAR(y(k, 0), exact.real(), 1e-8) << "sample " << k;
  }
}

TEST(LtiModel, TransferFunctionOfAHighOrderModelAtAHighSampleRateKeepsItsLeadingTerms) {
  // The poles above with five zeros (one in the right half plane), unit DC gain: the numerator's
  // s⁵ coefficient is ~3e5, the denominator's constant ~5e24. The realisation and back must give
  // every coefficient to its own relative precision; with one rounding scale for all (the
  // largest coefficient) the s⁵ term was dropped as noise.
  using C = std::complex<double>;
  Eigen::VectorXcd poles(6), zeros(5);
  poles << C(-5e4, 0), C(-9e3, 0), C(-6e3, 1e4), C(-6e3, -1e4), C(-2.5e3, 9e3), C(-2.5e3, -9e3);
  zeros << C(-2e4, 0), C(-3e3, 0), C(7e3, 0), C(-4e3, 5e3), C(-4e3, -5e3);
  const Eigen::VectorXd den = PolynomialFromRoots(poles);
  const Eigen::VectorXd monic_num = PolynomialFromRoots(zeros);
  const Eigen::VectorXd num = monic_num * (den(6) / monic_num(5));
  ASSERT_GT(std::abs(num(0)), 1e4);
  ASSERT_GT(den(6), 1e24);
  const TransferFunction back = Normalized(ToTransferFunction(ToStateSpace(TransferFunction{num, den})));
  ASSERT_EQ(back.num.size(), 6);
  ASSERT_EQ(back.den.size(), 7);
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(back.num(i) / num(i), 1.0, 1e-7) << "s^" << 5 - i;
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(back.den(i) / den(i), 1.0, 1e-9) << "s^" << 6 - i;
  // A numerator whose leading terms are zero stays of the lower degree: unit DC gain, no zeros.
  const TransferFunction all_pole =
      Normalized(ToTransferFunction(ToStateSpace(TransferFunction{Eigen::VectorXd::Constant(1, den(6)), den})));
  ASSERT_EQ(all_pole.num.size(), 1);
  EXPECT_NEAR(all_pole.num(0) / den(6), 1.0, 1e-9);
}

TEST(LtiModelBadInput, ClearErrors) {
  TransferFunction improper{Eigen::Vector3d(1, 2, 3), Eigen::Vector2d(1, 1)};
  EXPECT_THROW(Validate(improper), std::invalid_argument);
  TransferFunction nan_tf{Eigen::VectorXd::Constant(1, std::nan("")), Eigen::Vector2d(1, 1)};
  EXPECT_THROW(Validate(nan_tf), std::invalid_argument);
  TransferFunction bad_delay{Eigen::VectorXd::Ones(1), Eigen::Vector2d(1, -0.5), 0.1, 0.15};
  EXPECT_THROW(Validate(bad_delay), std::invalid_argument);
  StateSpace ss{Eigen::MatrixXd::Identity(2, 2), Eigen::MatrixXd::Ones(3, 1), Eigen::MatrixXd::Ones(1, 2),
                Eigen::MatrixXd::Zero(1, 1)};
  EXPECT_THROW(Validate(ss), std::invalid_argument);
  TransferFunction ok{Eigen::VectorXd::Ones(1), Eigen::Vector2d(1, 1)};
  EXPECT_THROW(Simulate(ToStateSpace(ok), Eigen::MatrixXd::Ones(5, 2), 0.1), std::invalid_argument);
}

}  // namespace
}  // namespace idrig
