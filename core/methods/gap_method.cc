// `gap-diagnose`: the sim-to-real gap diagnosis as a registry method, so that workers run
// diagnosis jobs like identification jobs and the catalogue keeps the report with its lineage.
// The record is split in time (estimation first half, validation second half); the sim model
// comes in the options, as an idrig.model/1 object ("sim") or a file path ("sim_path").
// Report: {"model": the adjusted linear part, "fit_percent": 100(1 − NRMSE after),
//          "status", "message", "details": the idrig.gap/1 report}.
#include <cmath>

#include "core/io/gap_json.h"
#include "core/io/model_json.h"
#include "core/methods/registry.h"
#include "core/numeric/gap/gap_diagnosis.h"

namespace idrig {
namespace {

TransferFunction SimModelFrom(const nlohmann::json& options) {
  LtiModel model;
  if (options.contains("sim")) {
    model = ModelFromJson(options.at("sim"));
  } else if (options.contains("sim_path")) {
    if (!options.at("sim_path").is_string())
      throw std::invalid_argument("gap-diagnose: option 'sim_path' must be a file path");
    model = ReadModelFile(options.at("sim_path").get<std::string>());
  } else {
    throw std::invalid_argument(
        "gap-diagnose: give the sim model as option 'sim' (an idrig.model/1 object) or 'sim_path'");
  }
  return SimModelTransferFunction(model);
}

MethodReport RunGapDiagnosis(const MethodInput& input, const nlohmann::json& options) {
  CheckOptionKeys(options, {"sim", "sim_path", "substeps", "significance"}, "gap-diagnose");
  GapOptions gap;
  if (options.contains("substeps")) gap.substeps = options.at("substeps").get<int>();
  if (options.contains("significance")) gap.significance = options.at("significance").get<double>();
  const GapReport report = DiagnoseGap(SimModelFrom(options), {ToGapRecord(*input.record)}, {}, gap);
  MethodReport out;
  out.json["model"] = ModelToJson(report.verdict.plant);
  out.json["fit_percent"] = 100.0 * (1.0 - report.verdict.nrmse_after);
  out.json["status"] = "ok";
  out.json["message"] = report.verdict.effect + ": " + report.verdict.explanation;
  out.json["details"] = GapReportToJson(report);
  out.text = GapReportText(report);
  return out;
}

}  // namespace

std::vector<MethodInfo> GapMethods() {
  return {{"gap-diagnose",
           "sim-to-real gap diagnosis against option sim (model JSON) or sim_path; the record is "
           "split in time for held-out validation (docs/gap.md)",
           true, RunGapDiagnosis}};
}

}  // namespace idrig
