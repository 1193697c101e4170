#include "core/methods/registry.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/io/csv.h"
#include "core/io/model_json.h"
#include "core/methods/auto_method.h"
#include "core/methods/report_checks.h"
#include "core/numeric/signal/outliers.h"
#include "core/numeric/validation.h"

namespace idrig {

// One line per method family; each adapter lives in its own file here.
std::vector<MethodInfo> ArxMethods();
std::vector<MethodInfo> FiniteFrequencyMethods();  // finite_frequency_method.cc
std::vector<MethodInfo> StepModalMethods();        // step_modal_method.cc
std::vector<MethodInfo> FrequencyMethods();        // frequency_method.cc
std::vector<MethodInfo> GapMethods();              // gap_method.cc
std::vector<MethodInfo> SubspacePemMethods();      // subspace_pem_method.cc (n4sid, oe, armax, bj, auto)

const std::vector<MethodInfo>& Methods() {
  static const std::vector<MethodInfo> methods = [] {
    std::vector<MethodInfo> all;
    for (auto family : {ArxMethods, FiniteFrequencyMethods, StepModalMethods, FrequencyMethods,
                        GapMethods}) {
      auto some = family();
      all.insert(all.end(), some.begin(), some.end());
    }
    for (auto& m : SubspacePemMethods()) all.push_back(std::move(m));
    return all;
  }();
  return methods;
}

const MethodInfo& FindMethod(const std::string& name) {
  for (const auto& m : Methods())
    if (m.name == name) return m;
  std::string known;
  for (const auto& m : Methods()) known += (known.empty() ? "" : ", ") + m.name;
  throw std::invalid_argument("unknown method '" + name + "'; known methods: " + known);
}

void CheckRecordMagnitude(const IoRecord& record) {
  auto check = [](const Eigen::MatrixXd& m, const char* kind) {
    for (long c = 0; c < m.cols(); ++c)
      for (long r = 0; r < m.rows(); ++r)
        if (std::abs(m(r, c)) > kMaxRecordMagnitude) {
          std::ostringstream s;
          s << "record: |" << kind << "| = " << std::abs(m(r, c)) << " in column " << c
            << " at sample " << r << "; the methods need |values| <= " << kMaxRecordMagnitude
            << " (their sums of squares overflow): rescale the record";
          throw std::invalid_argument(s.str());
        }
  };
  check(record.u, "u");
  check(record.y, "y");
}

namespace {
MethodReport Finish(const MethodInfo& info, MethodReport report, double sample_time, double min_fit) {
  report.json["method"] = info.name;
  if (sample_time > 0.0 && !(report.record_sample_time > 0.0)) report.record_sample_time = sample_time;
  ApplyModelChecks(&report, min_fit);
  return report;
}


// The common option "offsets" (see registry.h): removed from the options of every method but
// auto, which chooses between the treatments itself.
std::string TakeOffsetsOption(const MethodInfo& info, nlohmann::json* options) {
  if (!options->is_object() || !options->contains("offsets")) return "none";
  const nlohmann::json v = (*options)["offsets"];
  const bool chooses = info.name == "auto";
  if (!v.is_string() || (v != "none" && v != "mean" && v != "initial" && !(chooses && v == "auto")))
    throw std::invalid_argument("option 'offsets' must be " + std::string(chooses ? "'auto', " : "") +
                                "'none', 'mean' (the record's means as the operating point) or 'initial' (the rig "
                                "at rest at it when the record starts), got " + v.dump() +
                                (v == "auto" ? ": 'auto' (chosen on held-out data) is for the method auto" : ""));
  if (chooses) return "none";  // auto reads it from its options
  options->erase("offsets");
  return v.get<std::string>();
}

// Runs the method on the record's deviations about an operating point (the record's means, or
// the rig at rest when it starts); the model carries the point, y = y0 + G(u − u0). The fits
// the method reports are those of the record itself when the point is the means (a fit is
// normalised by the spread about the mean).
MethodReport RunAboutOperatingPoint(const MethodInfo& info, const IoRecord& record, const nlohmann::json& options,
                                    const std::string& offsets) {
  const bool initial = offsets == "initial";
  const OperatingPoint op = initial ? InitialRest(record) : RecordMeans(record);
  const IoRecord deviations = Deviations(record, op);
  MethodInput input;
  input.record = &deviations;
  MethodReport report = info.run(input, options);
  const nlohmann::json point = OperatingPointToJson(op);
  if (report.json.contains("model") && report.json["model"].is_object()) report.json["model"]["operating_point"] = point;
  report.json["operating_point"] = point;
  report.json["operating_point"]["source"] = initial ? "initial rest" : "record means";
  std::ostringstream t;
  t << "Operating point (" << (initial ? "the rig at rest when the record starts" : "the record's means")
    << ") removed first; the model maps deviations, y = y0 + G(u - u0): u0 =";
  for (int i = 0; i < op.u.size(); ++i) t << " " << op.u(i);
  t << ", y0 =";
  for (int i = 0; i < op.y.size(); ++i) t << " " << op.y(i);
  report.text = t.str() + "\n" + report.text;
  return report;
}

// The common option "glitches" (see registry.h): "bridge" (the default) or "keep".
bool TakeGlitchesOption(nlohmann::json* options) {
  if (!options->is_object() || !options->contains("glitches")) return true;
  const nlohmann::json v = (*options)["glitches"];
  if (v != "bridge" && v != "keep")
    throw std::invalid_argument("option 'glitches' must be 'bridge' (output samples far out of the signal, "
                                "a sensor or acquisition fault, bridged from their neighbours) or 'keep', got " +
                                v.dump());
  options->erase("glitches");
  return v == "bridge";
}

// Bridges the output glitches of every output column (core/numeric/signal/outliers.h); returns
// them as JSON (empty when none) and says so in `note`.
nlohmann::json BridgeRecordGlitches(IoRecord* record, std::string* note) {
  nlohmann::json list = nlohmann::json::array();
  std::ostringstream text;
  for (long c = 0; c < record->y.cols(); ++c) {
    Eigen::VectorXd y = record->y.col(c);
    const GlitchScan scan = BridgeOutputGlitches(y, record->u);
    if (scan.glitches.empty()) continue;
    record->y.col(c) = y;
    const std::string name =
        c < static_cast<long>(record->output_names.size()) ? record->output_names[static_cast<size_t>(c)] : "y";
    text << (list.empty() ? "" : "; ") << name << ": " << scan.glitches.size() << " at sample";
    int shown = 0;
    for (const auto& g : scan.glitches) {
      list.push_back({{"output", name}, {"sample", g.sample}, {"value", g.value}, {"replaced_by", g.replaced_by}});
      if (shown++ < 8) text << " " << g.sample;
    }
  }
  if (!list.empty())
    *note = "output samples far out of the signal (a sensor or acquisition glitch) bridged from their "
            "neighbours before fitting (option glitches=keep fits them as measured): " + text.str();
  return list;
}

// The black-box methods a rig engineer names explicitly (those auto chooses among).
bool ChoosesItsOperatingPoint(const MethodInfo& info) {
  for (const char* name : {"arx", "arx-oe", "n4sid", "oe", "armax", "bj"})
    if (info.name == name) return true;
  return false;
}

MethodReport RunOnRecord(const MethodInfo& info, const IoRecord& measured, const nlohmann::json& options);

// An explicit black-box method given no offsets, on a record whose means stand out of its range
// (auto_method.h OffsetsStandOut: a rig run at an operating point, or a step test): fitted as
// recorded, about its means and about its initial rest on the first 2/3 of the record's input
// energy (auto_method.h InputEnergySplit), each model simulates the whole record from rest
// (about its point), and the treatment whose simulation fits the held-out rest best is refitted
// on the whole record. Without it a model from rest about zero must make the operating point out
// of its DC gain and its start: on DaISy's exchanger record (outlet temperature about 50 °C, a
// swing of a few degrees) oe simulated the second half at −6310 % (docs/subspace_pem.md). The
// report says which was chosen and the held-out fits.
MethodReport RunChoosingOperatingPoint(const MethodInfo& info, const IoRecord& record, const nlohmann::json& options) {
  const int samples = record.NumSamples();
  const int split = InputEnergySplit(record.u, 2.0 / 3.0, samples / 2, std::max(10, samples / 10));
  const IoRecord head = Slice(record, 0, split);
  nlohmann::json fits = nlohmann::json::object(), notes = nlohmann::json::object();
  double best = -std::numeric_limits<double>::infinity();
  std::string chosen = "none";
  for (const char* treatment : {"none", "mean", "initial"}) {
    nlohmann::json o = options;
    o["offsets"] = treatment;
    fits[treatment] = nullptr;
    try {
      const MethodReport r = RunOnRecord(info, head, o);
      const std::string status = r.json.value("status", std::string("failed"));
      if (status == "failed") {
        notes[treatment] = r.json.value("message", std::string("failed"));
        continue;
      }
      const Eigen::MatrixXd sim = SimulateModelJson(r.json.at("model"), record.u, record.sample_time);
      const Eigen::VectorXd fit = FitPercent(record.y.bottomRows(samples - split), sim.bottomRows(samples - split));
      if (!fit.allFinite()) {
        notes[treatment] = "the simulation diverges";
        continue;
      }
      fits[treatment] = fit.mean();
      if (fit.mean() > best) {
        best = fit.mean();
        chosen = treatment;
      }
    } catch (const std::invalid_argument& e) {
      notes[treatment] = e.what();
    }
  }
  nlohmann::json o = options;
  o["offsets"] = chosen;
  MethodReport report = RunOnRecord(info, record, o);
  report.json["offsets"] = {
      {"chosen", chosen},
      {"validation_fit_percent", fits},
      {"split", split},
      {"rule", "the record's means stand out of its range and no offsets were given: fitted as recorded (none), "
               "about its means (mean) and about its initial rest (initial) on the samples before the split, each "
               "scored on the samples after it (simulated from rest), the best refitted on the whole record"}};
  if (!notes.empty()) report.json["offsets"]["notes"] = notes;
  std::ostringstream t;
  t << "Operating point: the record's means stand out; offsets " << chosen << " chosen on held-out data (fit after sample "
    << split << ":";
  for (auto it = fits.begin(); it != fits.end(); ++it)
    t << " " << it.key() << " " << (it.value().is_number() ? std::to_string(it.value().get<double>()) + " %" : "-");
  t << "; --offsets none|mean|initial fixes it)\n";
  // After the warnings, which lead the text.
  size_t at = 0;
  while (report.text.compare(at, 8, "warning:") == 0) {
    const size_t end = report.text.find('\n', at);
    if (end == std::string::npos) break;
    at = end + 1;
  }
  report.text.insert(at, t.str());
  return report;
}

MethodReport RunOnRecord(const MethodInfo& info, const IoRecord& measured, const nlohmann::json& options) {
  nlohmann::json method_options = options;
  IoRecord record = measured;
  std::string glitch_note;
  const nlohmann::json glitches =
      TakeGlitchesOption(&method_options) ? BridgeRecordGlitches(&record, &glitch_note) : nlohmann::json::array();
  MethodReport report;
  // (Records too short for a held-out split are taken as they are; the method says what it needs.)
  if (ChoosesItsOperatingPoint(info) && (!options.is_object() || !options.contains("offsets")) &&
      record.NumSamples() >= 40 && OffsetsStandOut(record)) {
    // The treatments are fitted and scored on the record bridged once, here.
    nlohmann::json bridged_options = options.is_object() ? options : nlohmann::json::object();
    bridged_options["glitches"] = "keep";
    report = RunChoosingOperatingPoint(info, record, bridged_options);
  } else {
    const double min_fit = TakeMinFitOption(&method_options);
    const std::string offsets = TakeOffsetsOption(info, &method_options);
    MethodInput input;
    input.record = &record;
    report = offsets != "none" ? RunAboutOperatingPoint(info, record, method_options, offsets)
                               : info.run(input, method_options);
    report = Finish(info, std::move(report), record.sample_time, min_fit);
  }
  if (!glitches.empty()) {
    report.json["glitches"] = glitches;
    report.json["warnings"].push_back(glitch_note);
    report.text = "Glitches: " + glitch_note + "\n" + report.text;
  }
  return report;
}
}  // namespace

MethodReport RunMethod(const std::string& name, const std::string& data_path,
                       const nlohmann::json& options) {
  const MethodInfo& info = FindMethod(name);
  if (info.needs_record) {
    const IoRecord record = ReadIoRecordCsv(data_path);
    CheckRecordMagnitude(record);
    return RunOnRecord(info, record, options);
  }
  nlohmann::json method_options = options;
  const double min_fit = TakeMinFitOption(&method_options);
  for (const char* key : {"offsets", "glitches"})
    if (method_options.is_object() && method_options.contains(key))
      throw std::invalid_argument("option '" + std::string(key) + "' is for methods that take a time record; '" +
                                  name + "' reads " + data_path + " itself");
  MethodInput input;
  input.path = data_path;
  return Finish(info, info.run(input, method_options), 0.0, min_fit);
}

MethodReport RunMethod(const std::string& name, const IoRecord& record,
                       const nlohmann::json& options) {
  const MethodInfo& info = FindMethod(name);
  if (!info.needs_record)
    throw std::invalid_argument("method '" + name + "' reads its data from a file, not a time record");
  ValidateIoRecord(record);
  CheckRecordMagnitude(record);
  return RunOnRecord(info, record, options);
}

void CheckOptionKeys(const nlohmann::json& options, const std::vector<std::string>& known,
                     const std::string& method) {
  if (options.is_null()) return;
  if (!options.is_object()) throw std::invalid_argument(method + ": options must be a JSON object");
  for (auto it = options.begin(); it != options.end(); ++it) {
    bool found = false;
    for (const auto& k : known) found |= (k == it.key());
    if (!found) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      throw std::invalid_argument(method + ": unknown option '" + it.key() + "' (known: " + list + ")");
    }
  }
}

}  // namespace idrig
