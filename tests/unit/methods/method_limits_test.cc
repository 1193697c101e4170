// Limits found by tests/fuzz/fuzz_worker_logger (the worker runs the method a signed identify
// request names, with its options, on the blocks it heard): each refused at once with a message
// naming the limit, instead of Eigen reading past a buffer or one request holding a worker for
// hours.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/methods/registry.h"
#include "core/numeric/model/realisation.h"
#include "core/numeric/time_domain/arx.h"

namespace idrig {
namespace {

// y[k+1] = 0.8 y[k] + 0.5 u[k] under a ±1 input that switches every 1..3 samples, times `scale`.
IoRecord FirstOrder(int n, double scale) {
  Eigen::MatrixXd u(n, 1), y(n, 1);
  double x = 0;
  for (int k = 0; k < n; ++k) {
    u(k, 0) = ((k * 7 + k / 3) % 5 < 2 ? 1.0 : -1.0) * scale;
    y(k, 0) = x;
    x = 0.8 * x + 0.5 * u(k, 0);
  }
  return MakeIoRecord(u, y, 0.01);
}

void ExpectRefusal(const std::function<void()>& run, const std::string& words) {
  try {
    run();
    ADD_FAILURE() << "no refusal (expected one naming '" << words << "')";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

// fuzz_worker_logger crash-2db499b3: a block with u ~ 2e295. The least-squares sums overflowed,
// Φ of the ARX model was NaN, and Eigen's matrix logarithm (ComplexSchur) read past its buffer.
TEST(MethodLimits, RecordValuesBeyondTheMagnitudeLimitAreRefused) {
  const IoRecord huge = FirstOrder(160, 2e295);
  ExpectRefusal([&] { RunMethod("arx", huge, {{"order", 1}}); }, "|u| = 2e+295 in column 0 at sample 0");
  ExpectRefusal([&] { RunMethod("n4sid", huge, {{"order", 1}}); }, "rescale the record");
  // The same record in large but physical units is identified: the pole 0.8 is found.
  const MethodReport ok = RunMethod("arx", FirstOrder(160, 1e6), {{"order", 1}});
  const auto& den = ok.json["details"]["discrete_tf"]["den"];
  EXPECT_NEAR(den[1].get<double>(), -0.8, 1e-9) << ok.json.dump();
}

// The numerics themselves, called without RunMethod: a clear error, not a heap overflow.
TEST(MethodLimits, ArxRefusesANonFiniteLeastSquaresSolution) {
  ArxOptions options;
  options.order = 1;
  ExpectRefusal([&] { IdentifyArx(FirstOrder(160, 2e295), options); }, "not finite");
  Eigen::MatrixXd phi = Eigen::MatrixXd::Identity(2, 2) * 0.5;
  phi(0, 1) = std::numeric_limits<double>::quiet_NaN();
  ExpectRefusal([&] { ContinuousFromDiscreteBySeries(phi, Eigen::VectorXd::Ones(2), 0.1, 0); },
                "NaN or Inf");
}

// fuzz_worker_logger timeout-351249dd: an ARX model whose Phi is singular (the series diverges,
// rho(X) = 1). The cross-check against Eigen's matrix logarithm never returned (its square-root
// loop), holding the worker. Now the cross-check runs only where the series converged.
TEST(MethodLimits, TheSeriesLogarithmOfASingularPhiReturns) {
  Eigen::MatrixXd phi(2, 2);
  phi << 0.0, 1.0, 0.0, 0.0;  // nilpotent: both eigenvalues 0
  const SeriesLogarithm s = ContinuousFromDiscreteBySeries(phi, Eigen::VectorXd::Ones(2), 0.1, 0);
  EXPECT_FALSE(s.converged);
  EXPECT_NEAR(s.spectral_radius_x, 1.0, 1e-12);  // X = (Phi - E)(Phi + E)^-1 has eigenvalue -1
  EXPECT_TRUE(std::isinf(s.truncation_error));
  EXPECT_EQ(s.terms, 1);  // a divergent series is not summed to 10 000 terms
  // A convergent case keeps its cross-check: Phi = e^{-T} I, log Phi / T = -I exactly.
  const Eigen::MatrixXd decay = std::exp(-0.1) * Eigen::MatrixXd::Identity(2, 2);
  const SeriesLogarithm c = ContinuousFromDiscreteBySeries(decay, Eigen::VectorXd::Ones(2), 0.1, 0);
  EXPECT_TRUE(c.converged);
  EXPECT_NEAR(c.A(0, 0), -1.0, 1e-12);
  EXPECT_LT(c.truncation_error, 1e-12);
}

// Options without an upper bound: 2^31 - 1 terms of the logarithmic series (one matrix product
// each) or output-error fits held the worker for hours on one request.
TEST(MethodLimits, ArxIterationCountsAreBounded) {
  const IoRecord record = FirstOrder(160, 1.0);
  ExpectRefusal([&] { RunMethod("arx", record, {{"order", 1}, {"log_series_terms", 2147483647}}); },
                "'log_series_terms' must be <= 10000 (got 2147483647)");
  ExpectRefusal([&] { RunMethod("arx-oe", record, {{"order", 1}, {"oe_iterations", 100000000}}); },
                "'oe_iterations' must be <= 1000");
  // At the limits, they run.
  EXPECT_NO_THROW(RunMethod("arx", record, {{"order", 1}, {"log_series_terms", 10000}}));
  EXPECT_NO_THROW(RunMethod("arx-oe", record, {{"order", 1}, {"oe_iterations", 1000}}));
}

}  // namespace
}  // namespace idrig
