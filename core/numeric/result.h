#pragma once
// Common fields of every identification result (DESIGN.md convention 1).
#include <string>

namespace idrig {

enum class SolverStatus {
  kOk,               // solved / converged
  kIllConditioned,   // solved, but the problem is numerically ill-conditioned: read `message`
  kNotConverged,     // iteration limit reached before the stopping rule was met
  kFailed,           // no usable answer: read `message`
  // Set by the plausibility checks of the model (core/numeric/model/model_checks.h):
  kUnstable,         // a pole outside the stability region for a method that should give a stable model
  kNyquistPole,      // a pole at (≥ 90 % of) the Nyquist frequency of the record
  kPoorFit,          // the fit is below the threshold (50 % by default)
};

const char* ToString(SolverStatus status);
// The inverse of ToString; false when `text` names no status.
bool ParseSolverStatus(const std::string& text, SolverStatus* status);

struct ResultBase {
  SolverStatus status = SolverStatus::kFailed;
  std::string message;      // what happened, in words a user can act on
  int iterations = 0;       // iterations of the method (1 for direct solves)
  double final_cost = 0.0;  // the method's own cost at the solution
  double fit_percent = 0.0; // simulation fit 100·(1 − NRMSE) on the estimation data
  bool ok() const { return status == SolverStatus::kOk; }
};

}  // namespace idrig
