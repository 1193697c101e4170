// Seed 001 section 1 ([Ivanovsky], Figs. 1–5): compact forms and the mutually inverse
// transforms. Reference values: shared/reference/PAPER_NUMBERS.md (printed and exact).
#include "core/numeric/model/realisation.h"

#include <gtest/gtest.h>

#include <unsupported/Eigen/MatrixFunctions>

#include "core/numeric/model/lti_model.h"

#include "tests/unit/numeric/seed001_plant.h"

namespace idrig {
namespace {

// Plant R1 of Figs. 3–5: W(p) = (0.5p + 1)/(p³ + 2.5p² + 4p + 1.5).
using testing::PlantA;
using testing::PlantB;
using testing::PlantH;

constexpr double kPrinted3 = 0.5e-3;  // three printed decimals
constexpr double kExact5 = 0.6e-5;    // five decimals of the "exact" column

TEST(CompactForm, PlantTransferFunctionFromR1) {
  // (1.3)–(1.5): a_I = C B1 gives the numerator 0·p² + 0.5p + 1.
  CompactForm form{PlantA(), PlantB(), PlantH()};
  Eigen::VectorXd num, den;
  CompactFormCoefficients(form, &num, &den);
  EXPECT_NEAR(num(0), 0.0, 1e-15);
  EXPECT_NEAR(num(1), 0.5, 1e-15);
  EXPECT_NEAR(num(2), 1.0, 1e-15);
  EXPECT_NEAR(den(1), 2.5, 1e-15);
  EXPECT_NEAR(den(2), 4.0, 1e-15);
  EXPECT_NEAR(den(3), 1.5, 1e-15);
  // And back: CompactObservableForm reproduces B1.
  const CompactForm again = CompactObservableForm(num, den);
  EXPECT_LT((again.B - PlantB()).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((again.A - PlantA()).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(CompactForm, ObservabilityMatrixOfR1IsIdentity) {
  // Property 1, Eq. (1.6).
  EXPECT_LT((ObservabilityMatrix(PlantA(), PlantH()) - Eigen::MatrixXd::Identity(3, 3)).norm(), 1e-15);
}

TEST(CompactForm, Figure2ChangeOfBasisGivesR1WithSameTransferFunction) {
  // Property 2, Eq. (1.7): any observable realisation → R1, same W(p).
  Eigen::MatrixXd a(2, 2);
  a << -1.0, 2.0, -3.0, -0.5;
  Eigen::VectorXd b(2);
  b << 1.0, -2.0;
  Eigen::RowVectorXd h(2);
  h << 0.7, 0.3;
  const CompactForm r1 = ToCompactForm(a, b, h);
  // Fig. 2 symbolic result: A1 = [[0, 1], [a2 a3 − a1 a4, a1 + a4]].
  EXPECT_NEAR(r1.A(1, 0), 2.0 * -3.0 - (-1.0) * (-0.5), 1e-12);
  EXPECT_NEAR(r1.A(1, 1), -1.0 + -0.5, 1e-12);
  EXPECT_NEAR(r1.B(0), 0.7 * 1.0 + 0.3 * -2.0, 1e-12);
  EXPECT_LT((ObservabilityMatrix(r1.A, r1.H) - Eigen::MatrixXd::Identity(2, 2)).norm(), 1e-12);
  StateSpace original{a, b, h, Eigen::MatrixXd::Zero(1, 1)};
  StateSpace compact{r1.A, r1.B, r1.H, Eigen::MatrixXd::Zero(1, 1)};
  for (double w : {0.1, 1.0, 7.0})
    EXPECT_LT(std::abs(FrequencyResponse(original, w)(0, 0) - FrequencyResponse(compact, w)(0, 0)), 1e-12);
}

TEST(CompactForm, UnobservableRealisationIsRejected) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Identity(2, 2);
  EXPECT_THROW(ToCompactForm(a, Eigen::Vector2d(1, 1), Eigen::RowVector2d(1, 0)), std::invalid_argument);
}

TEST(SeriesTransforms, Figure3DiscreteCompactFormAtT04) {
  const SeriesDiscretisation rd = DiscretiseBySeries(PlantA(), PlantB(), 0.4, 8);
  const CompactForm rd1 = ToCompactForm(rd.Phi, rd.Gamma, PlantH());  // Eq. (1.10)
  const Eigen::RowVector3d printed_row(0.368, -1.376, 1.951), exact_row(0.36788, -1.37597, 1.95053);
  const Eigen::Vector3d printed_gamma(0.036, 0.088, 0.106), exact_gamma(0.03616, 0.08778, 0.10642);
  EXPECT_LT((rd1.A.row(2) - printed_row).cwiseAbs().maxCoeff(), kPrinted3);
  EXPECT_LT((rd1.A.row(2) - exact_row).cwiseAbs().maxCoeff(), kExact5);
  EXPECT_LT((rd1.B - printed_gamma).cwiseAbs().maxCoeff(), kPrinted3);
  EXPECT_LT((rd1.B - exact_gamma).cwiseAbs().maxCoeff(), kExact5);
  // Property 3 (1.11): Nd1 = E.
  EXPECT_LT((ObservabilityMatrix(rd1.A, rd1.H) - Eigen::MatrixXd::Identity(3, 3)).norm(), 1e-12);
  // y(∞) by (1.15) and by W(z=1) and by −H A⁻¹ B: 2/3 (to the series' accuracy).
  const Eigen::MatrixXd e = Eigen::MatrixXd::Identity(3, 3);
  const double y_inf = (rd1.H * (e - rd1.A).inverse() * rd1.B)(0);
  EXPECT_NEAR(y_inf, 2.0 / 3.0, 1e-3);
  EXPECT_NEAR((-PlantH() * PlantA().inverse() * PlantB())(0), 2.0 / 3.0, 1e-15);
  // The seed's 8-term series against Eigen's matrix exponential: small but not zero at T = 0.4.
  EXPECT_GT(rd.truncation_error, 0.0);
  EXPECT_LT(rd.truncation_error, 1e-4);
}

TEST(SeriesTransforms, Figures4And5RoundTripAtT02) {
  const double t = 0.2;
  const SeriesDiscretisation rd = DiscretiseBySeries(PlantA(), PlantB(), t, 8);
  const CompactForm rd1 = ToCompactForm(rd.Phi, rd.Gamma, PlantH());
  EXPECT_LT((rd1.A.row(2) - Eigen::RowVector3d(0.607, -2.093, 2.477)).cwiseAbs().maxCoeff(), kPrinted3);
  EXPECT_LT((rd1.B - Eigen::Vector3d(0.00959, 0.0266, 0.0396)).cwiseAbs().maxCoeff(), 0.6e-4);
  // Back by (1.16) with the paper's 8 terms, then (1.7): L, K of Fig. 4/5.
  const SeriesLogarithm r_star = ContinuousFromDiscreteBySeries(rd1.A, rd1.B, t, 8);
  EXPECT_TRUE(r_star.converged);
  const CompactForm r1_star = ToCompactForm(r_star.A, r_star.B, rd1.H);
  EXPECT_LT((r1_star.A - PlantA()).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_LT((r1_star.B - PlantB()).cwiseAbs().maxCoeff(), 1e-7);  // paper: K(0) = −5.42e−10
  // Summed to machine precision and cross-checked against Eigen's matrix logarithm.
  const SeriesLogarithm full = ContinuousFromDiscreteBySeries(rd1.A, rd1.B, t, 0);
  EXPECT_LT(full.truncation_error, 1e-10);
  EXPECT_LT(full.truncation_error, r_star.truncation_error);
  // Exact discretisation (Eigen's exp) and back recovers the plant to ~1e-12.
  const Eigen::MatrixXd phi = (PlantA() * t).exp();
  const Eigen::VectorXd gamma = PlantA().inverse() * (phi - Eigen::MatrixXd::Identity(3, 3)) * PlantB();
  const SeriesLogarithm exact = ContinuousFromDiscreteBySeries(phi, gamma, t, 0);
  const CompactForm back = ToCompactForm(exact.A, exact.B, PlantH());
  EXPECT_LT((back.A - PlantA()).cwiseAbs().maxCoeff(), 1e-11);
  EXPECT_LT((back.B - PlantB()).cwiseAbs().maxCoeff(), 1e-11);
}

TEST(SeriesTransforms, LogSeriesReportsDivergenceForNegativeRealPole) {
  Eigen::MatrixXd phi(1, 1);
  phi << -0.5;  // no real logarithm: ρ(X) = 3
  const SeriesLogarithm out = ContinuousFromDiscreteBySeries(phi, Eigen::VectorXd::Ones(1), 0.1, 20);
  EXPECT_FALSE(out.converged);
  EXPECT_GT(out.spectral_radius_x, 1.0);
}

}  // namespace
}  // namespace idrig
