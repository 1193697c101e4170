#include "core/numeric/io_record.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace idrig {

IoRecord MakeIoRecord(const Eigen::MatrixXd& u, const Eigen::MatrixXd& y, double sample_time) {
  if (!(sample_time > 0.0)) throw std::invalid_argument("record: sample time must be positive");
  IoRecord record;
  record.u = u;
  record.y = y;
  record.sample_time = sample_time;
  record.t = Eigen::VectorXd::LinSpaced(u.rows(), 0.0, sample_time * (u.rows() - 1));
  for (int i = 0; i < u.cols(); ++i) record.input_names.push_back(u.cols() == 1 ? "u" : "u" + std::to_string(i + 1));
  for (int i = 0; i < y.cols(); ++i) record.output_names.push_back(y.cols() == 1 ? "y" : "y" + std::to_string(i + 1));
  return record;
}

void ValidateIoRecord(const IoRecord& record, int min_samples) {
  const long n = record.u.rows();
  if (record.y.rows() != n || record.t.size() != n)
    throw std::invalid_argument("record: columns have different lengths (t " +
                                std::to_string(record.t.size()) + ", u " + std::to_string(n) +
                                ", y " + std::to_string(record.y.rows()) + ")");
  if (record.u.cols() == 0) throw std::invalid_argument("record: no input column");
  if (record.y.cols() == 0) throw std::invalid_argument("record: no output column");
  if (n < min_samples)
    throw std::invalid_argument("record: " + std::to_string(n) + " samples, at least " +
                                std::to_string(min_samples) + " needed");
  auto check_finite = [&](const Eigen::MatrixXd& m, const std::vector<std::string>& names,
                          const char* kind) {
    for (long r = 0; r < m.rows(); ++r)
      for (long c = 0; c < m.cols(); ++c)
        if (!std::isfinite(m(r, c)))
          throw std::invalid_argument(
              std::string("record: ") + (std::isnan(m(r, c)) ? "NaN" : "Inf") + " in " + kind +
              " column '" + (c < static_cast<long>(names.size()) ? names[c] : std::to_string(c)) +
              "' at sample " + std::to_string(r));
  };
  check_finite(record.t, {"t"}, "time");
  check_finite(record.u, record.input_names, "input");
  check_finite(record.y, record.output_names, "output");
  if (n >= 2) {
    const double ts = record.sample_time;
    if (!(ts > 0.0)) throw std::invalid_argument("record: sample time must be positive");
    for (long k = 1; k < n; ++k)
      if (!(record.t(k) > record.t(k - 1)))
        throw std::invalid_argument("record: time column is not increasing at sample " +
                                    std::to_string(k) + " (t = " + std::to_string(record.t(k)) + ")");
    // A quarter step, per step and against the grid t0 + k·Ts: a missing or repeated sample
    // is caught, while times printed with few digits (e.g. "%.4f" at Ts = 1/300 s, ±1.5 % per
    // value) are still read as the uniform grid they are.
    bool uniform = true;
    for (long k = 1; k < n && uniform; ++k) {
      const double dt = record.t(k) - record.t(k - 1);
      const double off_grid = record.t(k) - record.t(0) - k * ts;
      uniform = std::abs(dt - ts) <= 0.25 * ts && std::abs(off_grid) <= 0.25 * ts;
    }
    if (!uniform) {
      // Name the fault against the record's own step (the median one), not against the mean
      // step, which a single jump distorts: a gap in the time stamps is where samples are
      // missing or two records were spliced.
      std::vector<double> steps(static_cast<size_t>(n - 1));
      for (long k = 1; k < n; ++k) steps[static_cast<size_t>(k - 1)] = record.t(k) - record.t(k - 1);
      std::vector<double> sorted = steps;
      std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
      const double step = sorted[sorted.size() / 2];
      auto fmt = [](double v) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.6g", v);
        return std::string(buf);
      };
      long jumps = 0, first = -1;
      for (long k = 1; k < n; ++k)
        if (std::abs(steps[static_cast<size_t>(k - 1)] - step) > 0.25 * step) {
          ++jumps;
          if (first < 0) first = k;
        }
      if (first < 0)
        throw std::invalid_argument("record: time column drifts off a uniform grid (step " + fmt(step) +
                                    " s, but t ends at " + fmt(record.t(n - 1)) + " s where " +
                                    fmt(record.t(0) + (n - 1) * step) + " s was due)");
      const double dt = steps[static_cast<size_t>(first - 1)];
      const std::string what =
          dt > step ? "about " + std::to_string(std::lround(dt / step) - 1) +
                          " samples missing or two records spliced there"
                    : "a sample repeated or the rate changed there";
      throw std::invalid_argument("record: time column is not uniform at sample " + std::to_string(first) +
                                  ": t jumps from " + fmt(record.t(first - 1)) + " to " +
                                  fmt(record.t(first)) + " s where the record's step is " + fmt(step) +
                                  " s (" + what + "; " + std::to_string(jumps) +
                                  (jumps == 1 ? " such step" : " such steps") +
                                  "); split the record there or give each part separately");
    }
  }
}

IoRecord Slice(const IoRecord& record, int begin, int end) {
  if (begin < 0 || end > record.NumSamples() || begin >= end)
    throw std::invalid_argument("record slice [" + std::to_string(begin) + ", " +
                                std::to_string(end) + ") is outside 0.." +
                                std::to_string(record.NumSamples()));
  IoRecord out = record;
  out.t = record.t.segment(begin, end - begin);
  out.u = record.u.middleRows(begin, end - begin);
  out.y = record.y.middleRows(begin, end - begin);
  return out;
}

OperatingPoint RecordMeans(const IoRecord& record) {
  OperatingPoint op;
  op.u = record.u.colwise().mean().transpose();
  op.y = record.y.colwise().mean().transpose();
  return op;
}

OperatingPoint InitialRest(const IoRecord& record) {
  OperatingPoint op;
  const long n = record.u.rows();
  if (n == 0) throw std::invalid_argument("operating point: the record has no samples");
  op.u = record.u.row(0).transpose();
  long rest = 1;  // samples 0..rest-1 have the first input values
  while (rest < n && (record.u.row(rest) - record.u.row(0)).cwiseAbs().maxCoeff() == 0.0) ++rest;
  op.y = record.y.topRows(rest).colwise().mean().transpose();
  return op;
}

IoRecord Deviations(const IoRecord& record, const OperatingPoint& op) {
  if (op.u.size() != record.NumInputs() || op.y.size() != record.NumOutputs())
    throw std::invalid_argument("operating point: " + std::to_string(op.u.size()) + " input and " +
                                std::to_string(op.y.size()) + " output values for a record with " +
                                std::to_string(record.NumInputs()) + " inputs and " +
                                std::to_string(record.NumOutputs()) + " outputs");
  IoRecord out = record;
  out.u.rowwise() -= op.u.transpose();
  out.y.rowwise() -= op.y.transpose();
  return out;
}

}  // namespace idrig
