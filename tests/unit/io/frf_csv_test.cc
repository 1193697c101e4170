// FRF CSV tables (core/io/frf_csv.h): SISO and MIMO layouts, Hz → rad/s, errors with lines.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "core/io/frf_csv.h"

namespace idrig {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(FrfCsv, SisoInHz) {
  const Frf f = ParseFrfCsv("f_hz,re,im\n1,0.5,-0.25\n2,0.1,0.2\n");
  ASSERT_EQ(f.NumLines(), 2);
  EXPECT_NEAR(f.omega(0), 2 * kPi, 1e-12);
  EXPECT_EQ(f.h[1](0, 0), std::complex<double>(0.1, 0.2));
}

TEST(FrfCsv, MimoPairsAnyOrderAndRadPerSecond) {
  const Frf f = ParseFrfCsv("w_rad_s,re_1_2,im_1_2,re_1_1,im_1_1,re_2_1,im_2_1,re_2_2,im_2_2\n3,12,0.12,11,0.11,21,0.21,22,0.22\n");
  ASSERT_EQ(f.NumOutputs(), 2);
  ASSERT_EQ(f.NumInputs(), 2);
  EXPECT_EQ(f.omega(0), 3.0);
  EXPECT_EQ(f.h[0](0, 1), std::complex<double>(12, 0.12));
  EXPECT_EQ(f.h[0](1, 0), std::complex<double>(21, 0.21));
}

TEST(FrfCsv, RoundTrip) {
  Frf f;
  f.omega = Eigen::Vector2d(1.0, 2.0);
  f.h = {Eigen::MatrixXcd::Constant(2, 1, {1.0, -1.0}), Eigen::MatrixXcd::Constant(2, 1, {0.5, 0.25})};
  const std::string path = ::testing::TempDir() + "/frf_roundtrip.csv";
  WriteFrfCsv(f, path);
  const Frf g = ReadFrfCsv(path);
  EXPECT_NEAR((g.omega - f.omega).norm(), 0.0, 1e-14);
  EXPECT_EQ(g.h[1], f.h[1]);
  EXPECT_FALSE(IsTimeRecordCsv(path));
  std::remove(path.c_str());
}

// A noise sigma per line (issue 15): sigma / sigma_<o>_<i> columns become the variance σ².
TEST(FrfCsv, SigmaColumnsGiveTheVariance) {
  const Frf f = ParseFrfCsv("f_hz,re,im,sigma\n1,0.5,-0.25,0.01\n2,0.1,0.2,0.002\n");
  ASSERT_EQ(f.variance.rows(), 2);
  EXPECT_DOUBLE_EQ(f.variance(0, 0), 1e-4);
  EXPECT_DOUBLE_EQ(f.variance(1, 0), 4e-6);
  const Frf m = ParseFrfCsv("w_rad_s,re_1_1,im_1_1,sigma_1_1,re_2_1,im_2_1,sigma_2_1\n3,1,0,0.1,2,0,0.2\n");
  ASSERT_EQ(m.variance.cols(), 2);
  EXPECT_DOUBLE_EQ(m.variance(0, 1), 0.04);  // column out + ny·in
  const std::string path = ::testing::TempDir() + "/frf_sigma.csv";
  WriteFrfCsv(f, path);
  const Frf g = ReadFrfCsv(path);
  EXPECT_NEAR((g.variance - f.variance).norm(), 0.0, 1e-18);
  std::remove(path.c_str());
  EXPECT_EQ(ParseFrfCsv("f_hz,re,im\n1,1,1\n").variance.size(), 0);
}

void ExpectError(const std::string& text, const std::string& fragment) {
  try {
    ParseFrfCsv(text, "x.csv");
    ADD_FAILURE() << "accepted: " << text;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(FrfCsv, BadInput) {
  ExpectError("", "empty file");
  ExpectError("freq,re,im\n1,1,1\n", "first column must be f_hz");
  ExpectError("f_hz,re\n1,1\n", "missing re/im column pair");
  ExpectError("f_hz,re,im,re\n1,1,1,1\n", "duplicate column");
  ExpectError("f_hz,re,im,mag\n1,1,1,1\n", "neither re");
  ExpectError("f_hz,re,im\n1,1\n", "x.csv:2: 2 fields");
  ExpectError("f_hz,re,im\n1,1,abc\n", "'abc' is not a number");
  ExpectError("f_hz,re,im\n1,1,nan\n", "NaN");
  ExpectError("f_hz,re_1_1,im_1_1,re_2_2,im_2_2\n1,1,1,1,1\n", "output 1, input 2");
  ExpectError("f_hz,re,im\n", "no data rows");
  ExpectError("f_hz,re,im,sigma\n1,1,1,0\n", "x.csv:2: field 4 (sigma) must be > 0");
  ExpectError("f_hz,re,im,sigma,sigma\n1,1,1,1,1\n", "duplicate column 'sigma'");
  ExpectError("f_hz,re_1_1,im_1_1,sigma_1_1,re_2_1,im_2_1\n1,1,1,1,1,1\n", "no sigma column for output 2, input 1");
  ExpectError("f_hz,re,im,sigma_x\n1,1,1,1\n", "must be named sigma_<output>_<input>");
  EXPECT_THROW(ReadFrfCsv("/nonexistent/frf.csv"), std::invalid_argument);
}

}  // namespace
}  // namespace idrig
