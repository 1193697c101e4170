#include "core/numeric/result.h"

namespace idrig {

const char* ToString(SolverStatus status) {
  switch (status) {
    case SolverStatus::kOk: return "ok";
    case SolverStatus::kIllConditioned: return "ill_conditioned";
    case SolverStatus::kNotConverged: return "not_converged";
    case SolverStatus::kFailed: return "failed";
    case SolverStatus::kUnstable: return "unstable";
    case SolverStatus::kNyquistPole: return "nyquist_pole";
    case SolverStatus::kPoorFit: return "poor_fit";
  }
  return "unknown";
}

bool ParseSolverStatus(const std::string& text, SolverStatus* status) {
  for (SolverStatus s : {SolverStatus::kOk, SolverStatus::kIllConditioned, SolverStatus::kNotConverged,
                         SolverStatus::kFailed, SolverStatus::kUnstable, SolverStatus::kNyquistPole,
                         SolverStatus::kPoorFit})
    if (text == ToString(s)) {
      *status = s;
      return true;
    }
  return false;
}

}  // namespace idrig
