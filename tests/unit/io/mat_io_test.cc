// MATLAB .mat files through libmatio: records and models written and read back, the level-5
// header of the published format (MathWorks, "MAT-File Format", level 5: 116 bytes of text,
// 8 bytes subsystem offset, version 0x0100, endian indicator "IM" on little-endian), and every
// bad input named.
#include "core/io/mat_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <iterator>

namespace idrig {
namespace {

std::string TempPath(const std::string& name) {
  return "/tmp/idrig_mat_test_" + std::to_string(getpid()) + "_" + name;
}

std::string Message(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no exception)";
}

IoRecord Example(int n, double ts) {
  Eigen::MatrixXd u(n, 1), y(n, 2);
  for (int k = 0; k < n; ++k) {
    u(k, 0) = std::sin(0.1 * k);
    y(k, 0) = 0.5 * k;
    y(k, 1) = -1.0 / (k + 1);
  }
  return MakeIoRecord(u, y, ts);
}

TEST(MatIo, RecordRoundTripAndLevel5Header) {
  const std::string path = TempPath("record.mat");
  const IoRecord r = Example(50, 0.02);
  WriteMatRecord(r, path, {{"rig_id", "sim1"}});
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 128u);
  EXPECT_EQ(bytes.substr(0, 10), "MATLAB 5.0");
  EXPECT_EQ(static_cast<unsigned char>(bytes[124]) | (static_cast<unsigned char>(bytes[125]) << 8), 0x0100);
  EXPECT_EQ(bytes.substr(126, 2), "IM");

  const auto names = MatVariableNames(path);
  EXPECT_EQ(names, (std::vector<std::string>{"t", "u", "y", "Ts", "rig_id"}));
  const IoRecord back = ReadMatRecord(path, "u", "y");  // Ts from the file
  EXPECT_DOUBLE_EQ(back.sample_time, 0.02);
  EXPECT_EQ(back.u, r.u);
  EXPECT_EQ(back.y, r.y);
  EXPECT_EQ(back.t, r.t);
  // Channels picked from columns of several variables, Ts overridden.
  const Eigen::MatrixXd y = ReadMatMatrix(path, "y");
  EXPECT_EQ(y.rows(), 50);
  EXPECT_EQ(y.cols(), 2);
  EXPECT_DOUBLE_EQ(y(3, 0), 1.5);
  const IoRecord two = ReadMatRecord(path, "u,t", "y", 0.5);
  EXPECT_EQ(two.NumInputs(), 2);
  EXPECT_DOUBLE_EQ(two.sample_time, 0.5);
  std::remove(path.c_str());
}

TEST(MatIo, ModelFileHasMatlabVariablesAndLineage) {
  const std::string path = TempPath("model.mat");
  TransferFunction tf;
  tf.num = Eigen::Vector2d(0.5, 1.0);
  tf.den = Eigen::Vector4d(1.0, 2.5, 4.0, 1.5);
  tf.sample_time = 0.1;
  tf.delay_s = 0.2;
  WriteMatModel(tf, path, {{"method", "arx"}, {"n_samples", 300}, {"options", {{"order", 3}}}});
  EXPECT_EQ(ReadMatMatrix(path, "num"), Eigen::RowVector2d(0.5, 1.0));
  EXPECT_EQ(ReadMatMatrix(path, "den"), Eigen::RowVector4d(1.0, 2.5, 4.0, 1.5));
  EXPECT_DOUBLE_EQ(ReadMatMatrix(path, "Ts")(0, 0), 0.1);
  EXPECT_DOUBLE_EQ(ReadMatMatrix(path, "delay")(0, 0), 2.0);  // samples (discrete InputDelay)
  EXPECT_DOUBLE_EQ(ReadMatMatrix(path, "delay_s")(0, 0), 0.2);
  const auto names = MatVariableNames(path);
  EXPECT_NE(std::find(names.begin(), names.end(), "lineage"), names.end());
  EXPECT_NE(Message([&] { ReadMatMatrix(path, "lineage"); }).find("is a struct"), std::string::npos);
  EXPECT_NE(Message([&] { ReadMatMatrix(path, "kind"); }).find("is text (char)"), std::string::npos);

  EXPECT_EQ(std::find(names.begin(), names.end(), "y0"), names.end());  // no operating point

  StateSpace ss = ToStateSpace(TransferFunction{tf.num, tf.den});
  WriteMatModel(ss, path, nlohmann::json::object(), OperatingPoint{Eigen::VectorXd::Constant(1, 0.7), Eigen::VectorXd::Constant(1, 5.0)});
  EXPECT_DOUBLE_EQ(ReadMatMatrix(path, "u0")(0, 0), 0.7);
  EXPECT_DOUBLE_EQ(ReadMatMatrix(path, "y0")(0, 0), 5.0);
  EXPECT_EQ(ReadMatMatrix(path, "A"), ss.A);
  EXPECT_EQ(ReadMatMatrix(path, "D"), ss.D);
  EXPECT_DOUBLE_EQ(ReadMatMatrix(path, "Ts")(0, 0), 0.0);
  std::remove(path.c_str());
}

TEST(MatIo, BadInputIsNamed) {
  const std::string path = TempPath("bad.mat");
  WriteMatRecord(Example(20, 0.1), path);
  EXPECT_NE(Message([&] { ReadMatRecord(path, "u", "speed"); })
                .find("variable 'speed' not found (the file has: t, u, y, Ts)"),
            std::string::npos);
  EXPECT_NE(Message([&] { ReadMatRecord(path, "", "y"); }).find("no u variable"), std::string::npos);
  EXPECT_NE(Message([&] { ReadMatRecord(path, "u", "y", -1); }).find("--ts"), std::string::npos);
  EXPECT_NE(Message([] { ReadMatRecord("/nonexistent/x.mat", "u", "y"); }).find("cannot be opened"),
            std::string::npos);
  {
    std::ofstream text(path);
    text << "t,u,y\n0,1,2\n";
  }
  EXPECT_NE(Message([&] { MatVariableNames(path); }).find("not MAT level 5"), std::string::npos);

  // Lengths that differ, and a file without any sample time.
  {
    std::remove(path.c_str());
    IoRecord r = Example(20, 0.1);
    WriteMatRecord(r, path);
  }
  const std::string other = TempPath("other.mat");
  WriteMatModel(TransferFunction{Eigen::VectorXd::Ones(1), Eigen::Vector2d(1, 2)}, other);
  EXPECT_NE(Message([&] { ReadMatRecord(other, "num", "den", 1.0); }).find("samples"), std::string::npos);
  std::remove(path.c_str());
  std::remove(other.c_str());
  EXPECT_THROW(WriteMatRecord(Example(5, 0.1), "/nonexistent/dir/x.mat"), std::runtime_error);
}

}  // namespace
}  // namespace idrig
