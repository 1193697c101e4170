#pragma once
// Identification methods by name, for the command line and the workers: a new method is one
// adapter file in core/methods/ plus one line in registry.cc, and every front end picks it up.
//
// A runner gets the data (a time record, or the path of a file it reads itself, e.g. an FRF)
// and its options as JSON, and returns a report:
//   {"method": name, "model": <idrig.model/1>, "fit_percent": …, "status": …, "message": …,
//    "details": {…method specific…}}
// plus a human-readable text. Runners throw std::invalid_argument for bad data or options.
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/numeric/io_record.h"

namespace idrig {

struct MethodInput {
  const IoRecord* record = nullptr;  // time-domain record, when the data is one
  std::string path;                  // the data file as given by the user
};

struct MethodReport {
  nlohmann::json json;
  std::string text;
  // For the plausibility checks RunMethod applies to every report (report_checks.h):
  bool expect_stable = true;       // false: the method identifies unstable plants on purpose
  double record_sample_time = 0.0; // Ts of the time record the model came from, when the
                                   // runner read one itself (RunMethod knows it otherwise)
};

struct MethodInfo {
  std::string name;
  std::string summary;
  bool needs_record = true;  // false: the runner reads `path` itself (e.g. FRF files)
  std::function<MethodReport(const MethodInput&, const nlohmann::json& options)> run;
};

const std::vector<MethodInfo>& Methods();
// Throws std::invalid_argument listing the known methods when `name` is unknown.
const MethodInfo& FindMethod(const std::string& name);
// Reads the record when the method needs one, runs it, adds "method" to the report, and checks
// the model (unstable, pole at Nyquist, poor fit: report_checks.h), which may lower "status"
// and adds "warnings". The option min_fit_percent (default 50) is taken by RunMethod itself,
// and so is "offsets" for every method that takes a time record: "none" (y = G u, as recorded;
// the default where the record's means do not stand out; arx, arx-oe, oe, n4sid, armax and bj
// given no offsets on a record whose means stand out choose among none, mean and initial on
// held-out data and report it under "offsets"), "mean" (a rig run about an operating point: the record's means (u0, y0) are
// removed, the method fits the deviations, and the model carries "operating_point", so that
// y = y0 + G(u − u0); model_json.h) or "initial" (the same about the rig at rest when the
// record starts: a step test from a set point; io_record.h InitialRest). The method auto also takes "auto", its default: both,
// chosen on its held-out folds when the record's means stand out (auto_method.h). So is
// "glitches" for those methods: "bridge" (the default: output samples far out of the signal, a
// sensor or acquisition fault, are bridged from their neighbours before the method runs, and
// listed under "glitches" and in "warnings"; core/numeric/signal/outliers.h) or "keep".
MethodReport RunMethod(const std::string& name, const std::string& data_path,
                       const nlohmann::json& options);
MethodReport RunMethod(const std::string& name, const IoRecord& record,
                       const nlohmann::json& options);

// A record value beyond this (in u or y) is refused by RunMethod: the methods' sums of squares
// and products of samples would overflow to Inf/NaN (tests/fuzz/fuzz_worker_logger found
// |u| ~ 1e295 reaching Eigen's matrix logarithm with NaN entries). Physical units never come close.
constexpr double kMaxRecordMagnitude = 1e100;
// Throws std::invalid_argument naming the value, its column and sample, and the limit.
void CheckRecordMagnitude(const IoRecord& record);

// Option helpers shared by adapters: typed lookup with a default, and a check that every
// given key is known (a misspelt option is an error, not silently ignored).
void CheckOptionKeys(const nlohmann::json& options, const std::vector<std::string>& known,
                     const std::string& method);

}  // namespace idrig
