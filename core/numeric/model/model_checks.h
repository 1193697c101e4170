#pragma once
// Plausibility checks of an identified model, so that a result's status tells the truth
// (issue 15): a method that returns a model with a pole outside the stability region, a pole
// at the Nyquist frequency of the record it came from, or a fit far below what any usable
// model gives, must not say "ok".
//
//   unstable      discrete |z| ≥ 1, continuous Re s ≥ 0 (a marginal pole counts as unstable)
//   nyquist_pole  a pole whose discrete angle |arg z| ≥ nyquist_fraction·π (continuous: |Im s|
//                 ≥ nyquist_fraction·π/Ts of the record), with a magnitude |z| (or e^{Re s·Ts})
//                 ≥ nyquist_min_magnitude (0.5: a mode that at least halves every sample is
//                 left out): an oscillation at the sampling limit is what noise, aliasing or
//                 the estimator make, not a property of the plant
//   poor_fit      fit < min_fit_percent (100·(1 − NRMSE) on the estimation data)
//
// The order of severity (worst first) is failed, unstable, not_converged, nyquist_pole,
// poor_fit, ill_conditioned, ok: a result takes the worst of its own status and these.
#include <string>
#include <vector>

#include "core/numeric/model/lti_model.h"
#include "core/numeric/result.h"

namespace idrig {

struct ModelCheckOptions {
  bool expect_stable = true;      // false for methods that identify unstable plants on purpose
  double sample_time = 0.0;       // Ts of the record the model came from [s]; 0: no Nyquist check
                                  // for a continuous model (a discrete one carries its own Ts)
  double nyquist_fraction = 0.9;  // a pole above 0.9 × the Nyquist frequency is "at" it
  double nyquist_min_magnitude = 0.5;
  double min_fit_percent = 50.0;  // NaN: no fit check (e.g. a method without a fit)
};

struct ModelIssue {
  SolverStatus status = SolverStatus::kOk;  // kUnstable, kNyquistPole or kPoorFit
  std::string warning;                       // what was found, with the numbers
};

// Issues of `model` with the given fit (NaN: not known). Empty: nothing found.
std::vector<ModelIssue> CheckModel(const LtiModel& model, double fit_percent, const ModelCheckOptions& options);

// 0 for ok up to 6 for failed, in the order above.
int Severity(SolverStatus status);
// The worse of two statuses.
SolverStatus WorseStatus(SolverStatus a, SolverStatus b);

}  // namespace idrig
