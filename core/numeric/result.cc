#include "core/numeric/result.h"

namespace idrig {

const char* ToString(SolverStatus status) {
  switch (status) {
    case SolverStatus::kOk: return "ok";
    case SolverStatus::kIllConditioned: return "ill_conditioned";
    case SolverStatus::kNotConverged: return "not_converged";
    case SolverStatus::kFailed: return "failed";
  }
  return "unknown";
}

}  // namespace idrig
