#pragma once
// The plausibility checks RunMethod applies to every method's report (issue 15: a status that
// tells the truth). The model in report.json["model"] is checked by CheckModel
// (core/numeric/model/model_checks.h): unstable, a pole at the Nyquist frequency of the
// record, a fit below min_fit_percent. Each finding
//   - lowers report.json["status"] to the worst of the method's own status and the findings
//     (failed > unstable > not_converged > nyquist_pole > poor_fit > ill_conditioned > ok),
//   - adds a sentence to report.json["warnings"] (an array, always present) and to "message",
//   - puts "warning: …" and the status at the top of report.text.
// The catalogue stores the status and the report as they leave here.
#include <nlohmann/json.hpp>

#include "core/methods/registry.h"

namespace idrig {

inline constexpr double kDefaultMinFitPercent = 50.0;

// Removes the common option "min_fit_percent" (a number; null disables the fit check) from
// `options` and returns it (kDefaultMinFitPercent when absent; NaN when disabled). Throws
// std::invalid_argument when it is not a number.
double TakeMinFitOption(nlohmann::json* options);

void ApplyModelChecks(MethodReport* report, double min_fit_percent);

}  // namespace idrig
