#include "core/methods/report_checks.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/io/model_json.h"
#include "core/numeric/model/model_checks.h"

namespace idrig {

double TakeMinFitOption(nlohmann::json* options) {
  if (!options->is_object() || !options->contains("min_fit_percent")) return kDefaultMinFitPercent;
  const nlohmann::json v = (*options)["min_fit_percent"];
  options->erase("min_fit_percent");
  if (v.is_null()) return std::numeric_limits<double>::quiet_NaN();
  if (!v.is_number() || !std::isfinite(v.get<double>()))
    throw std::invalid_argument("option 'min_fit_percent' must be a number (percent) or null (no fit check)");
  return v.get<double>();
}

void ApplyModelChecks(MethodReport* report, double min_fit_percent) {
  nlohmann::json& j = report->json;
  if (!j.contains("warnings") || !j["warnings"].is_array()) j["warnings"] = nlohmann::json::array();
  SolverStatus status = SolverStatus::kFailed;
  if (!j.contains("status") || !j["status"].is_string() || !ParseSolverStatus(j["status"].get<std::string>(), &status))
    return;  // a report without a known status is left as the method wrote it
  if (!j.contains("model")) return;
  LtiModel model;
  try {
    model = ModelFromJson(j["model"]);
  } catch (const std::invalid_argument&) {
    return;  // not an LTI model (nothing to check)
  }
  ModelCheckOptions options;
  options.expect_stable = report->expect_stable;
  options.sample_time = report->record_sample_time;
  options.min_fit_percent = min_fit_percent;
  const double fit = j.contains("fit_percent") && j["fit_percent"].is_number() ? j["fit_percent"].get<double>()
                                                                              : std::numeric_limits<double>::quiet_NaN();
  const std::vector<ModelIssue> issues = CheckModel(model, fit, options);
  j["checks"] = {{"min_fit_percent", std::isnan(min_fit_percent) ? nlohmann::json(nullptr) : nlohmann::json(min_fit_percent)},
                 {"expect_stable", options.expect_stable},
                 {"record_sample_time", options.sample_time},
                 {"nyquist_fraction", options.nyquist_fraction}};
  std::string head, message = j.contains("message") && j["message"].is_string() ? j["message"].get<std::string>() : "";
  if (status != SolverStatus::kOk) {  // the method's own finding leads, in its own words
    const std::string warning = std::string(ToString(status)) + ": " + message;
    j["warnings"].insert(j["warnings"].begin(), warning);
    head += "warning: " + warning + "\n";
  }
  for (const ModelIssue& issue : issues) {
    status = WorseStatus(status, issue.status);
    j["warnings"].push_back(issue.warning);
    message += (message.empty() ? "" : "; ") + issue.warning;
    head += "warning: " + issue.warning + "\n";
  }
  if (head.empty()) return;
  j["status"] = ToString(status);
  j["message"] = message;
  report->text = head + "status: " + ToString(status) + "\n" + report->text;
}

}  // namespace idrig
