#pragma once
// A sampled input/output record: N samples of nu inputs and ny outputs on a uniform grid.
#include <Eigen/Dense>
#include <string>
#include <vector>

namespace idrig {

struct IoRecord {
  Eigen::VectorXd t;         // N sample times [s], uniform and increasing
  Eigen::MatrixXd u;         // N×nu inputs
  Eigen::MatrixXd y;         // N×ny outputs
  double sample_time = 0.0;  // Ts [s]
  std::vector<std::string> input_names, output_names;

  int NumSamples() const { return static_cast<int>(u.rows()); }
  int NumInputs() const { return static_cast<int>(u.cols()); }
  int NumOutputs() const { return static_cast<int>(y.cols()); }
};

// Builds a record on t_k = k·Ts from input and output matrices (N×nu, N×ny).
IoRecord MakeIoRecord(const Eigen::MatrixXd& u, const Eigen::MatrixXd& y, double sample_time);

// Throws std::invalid_argument naming the first problem: mismatched lengths, NaN/Inf (with
// row and column), a time column that is not increasing or not uniform, fewer than
// `min_samples` samples.
void ValidateIoRecord(const IoRecord& record, int min_samples = 2);

// Samples [begin, end) as a new record (times kept).
IoRecord Slice(const IoRecord& record, int begin, int end);

// The operating point (u0, y0) of a record, one value per channel: a linear model of the
// deviations, y − y0 = G(u − u0), is identified from a rig that runs about a set point with
// actuator and sensor offsets (`identify --offsets mean`). Empty vectors: no operating point.
struct OperatingPoint {
  Eigen::VectorXd u, y;
  bool empty() const { return u.size() == 0 && y.size() == 0; }
};
// The record's means per channel (the least-squares operating point of a record whose
// deviations average out: MATLAB's detrend(data, 0)).
OperatingPoint RecordMeans(const IoRecord& record);
// The rig at rest at its operating point when the record starts (a step test from a set point):
// u0 = the inputs' first values, y0 = the outputs' mean over the samples before any input first
// changes (the first sample when one changes at once).
OperatingPoint InitialRest(const IoRecord& record);
// The record with u0 and y0 subtracted. Throws std::invalid_argument when the sizes differ.
IoRecord Deviations(const IoRecord& record, const OperatingPoint& op);

}  // namespace idrig
