// idrig identify --data FILE --method NAME [--order N] [--option key=value]...
//   [--frequencies w1,w2,...] [--json]
#include <cmath>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "core/io/csv.h"
#include "core/io/mat_io.h"
#include "core/methods/registry.h"
#include "tools/idrig/commands.h"

namespace idrig {

namespace {
nlohmann::json ParseOptionValue(const std::string& text) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error&) {
    return text;  // a bare word is a string option
  }
}

// Methods that take a list of test frequencies as their `frequencies` option.
bool TakesFrequencies(const std::string& method) { return method == "finite-frequency"; }

// "0.2,1,5" -> [0.2, 1, 5] (rad/s); every item a positive finite number.
nlohmann::json ParseFrequencies(const std::string& text) {
  nlohmann::json list = nlohmann::json::array();
  size_t start = 0;
  while (true) {
    const size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos
                                                                           : comma - start);
    size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (item.empty() || used != item.size() || !std::isfinite(value) || !(value > 0.0))
      throw std::invalid_argument("--frequencies expects positive numbers (rad/s) separated by "
                                  "commas, e.g. 0.2,1,5; got '" + item + "' in '" + text + "'");
    list.push_back(value);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return list;
}
}  // namespace

void RegisterIdentifyCommand(CLI::App& app) {
  struct Args {
    std::string data, method = "auto", options_json, frequencies, u_names, y_names, offsets, time_name, glitches;
    int order = 0;
    double ts = 0.0;
    std::vector<std::string> options;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  std::string methods_help = "identification method:";
  for (const auto& m : Methods()) methods_help += "\n  " + m.name + ": " + m.summary;
  auto* cmd = app.add_subcommand("identify", "identify a model from a record (CSV t,u,y or t,u1,..,y1,..)");
  cmd->add_option("--data", args->data, "data file: CSV record or FRF table, or MATLAB .mat (with --u, --y)")->required();
  cmd->add_option("--u", args->u_names, "the input variable(s) of a .mat file, or the input column(s) of a CSV "
                  "record with its own names, comma-separated (CSV default: columns u… are inputs)");
  cmd->add_option("--y", args->y_names, "the output variable(s) or column(s), comma-separated (CSV default: y…)");
  cmd->add_option("--time", args->time_name, "CSV: the time column (default: t or time)");
  cmd->add_option("--ts", args->ts, ".mat files: sample time [s] (default: the file's Ts, or its time vector t)");
  cmd->add_option("--method", args->method, methods_help + "\n(default: auto)");
  cmd->add_option("--order", args->order, "model order (0 or absent: chosen automatically)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--option", args->options, "method option key=value (value is JSON or a word); repeatable");
  cmd->add_option("--options-json", args->options_json, "method options as one JSON object");
  CLI::Option* frequencies = cmd->add_option("--frequencies", args->frequencies,
                  "test frequencies w1,w2,... [rad/s] (methods that take them: finite-frequency); "
                  "the same as --option \"frequencies=[w1,w2,...]\"");
  cmd->add_option("--offsets", args->offsets,
                  "operating point: none (the record as it is), mean (fit the deviations about the record's means; "
                  "the model carries them as \"operating_point\"), initial (about the rig at rest when the record "
                  "starts: a step test from a set point), auto (method auto only, its default: none and mean, "
                  "chosen on held-out data when the means stand out). Not given: arx, arx-oe, oe, n4sid, armax "
                  "and bj choose among none, mean and initial on held-out data when the means stand out "
                  "(\"offsets\" in the report); other methods take the record as it is")
      ->check(CLI::IsMember({"none", "mean", "initial", "auto"}));
  cmd->add_option("--glitches", args->glitches,
                  "bridge (default: output samples far out of the signal, a sensor or acquisition glitch, are "
                  "bridged from their neighbours before fitting and listed under \"glitches\") or keep")
      ->check(CLI::IsMember({"bridge", "keep"}));
  cmd->add_flag("--json", args->json, "print the model as idrig.model/1 JSON (with an \"identification\" report)");
  cmd->callback([args, frequencies] {
    nlohmann::json options = args->options_json.empty()
                                 ? nlohmann::json::object()
                                 : nlohmann::json::parse(args->options_json, nullptr, false);
    if (!options.is_object())
      throw std::invalid_argument("--options-json must be a JSON object, got '" +
                                  args->options_json + "'");
    if (args->order > 0) options["order"] = args->order;
    if (!args->offsets.empty()) options["offsets"] = args->offsets;
    if (!args->glitches.empty()) options["glitches"] = args->glitches;
    for (const auto& kv : args->options) {
      const auto eq = kv.find('=');
      if (eq == std::string::npos || eq == 0)
        throw std::invalid_argument("--option expects key=value, got '" + kv + "'");
      options[kv.substr(0, eq)] = ParseOptionValue(kv.substr(eq + 1));
    }
    if (frequencies->count() > 0) {
      FindMethod(args->method);  // an unknown method is reported as such
      if (!TakesFrequencies(args->method))
        throw std::invalid_argument("--frequencies is for methods that take test frequencies "
                                    "(finite-frequency); method '" + args->method +
                                    "' does not");
      if (options.contains("frequencies"))
        throw std::invalid_argument("test frequencies given twice: use either --frequencies or "
                                    "--option frequencies=[...]");
      options["frequencies"] = ParseFrequencies(args->frequencies);
    }
    const bool mat = args->data.size() > 4 && args->data.compare(args->data.size() - 4, 4, ".mat") == 0;
    if (!mat && args->ts != 0.0)
      throw std::invalid_argument("--ts is for MATLAB .mat data; '" + args->data +
                                  "' is read as CSV, whose time column gives the sample time");
    if (mat && !args->time_name.empty())
      throw std::invalid_argument("--time names a CSV column; for .mat data give --ts");
    if (mat && (args->u_names.empty() || args->y_names.empty()))
      throw std::invalid_argument(args->data + ": name the input and output variables: --u NAME --y NAME (variables: " +
                                  [&] { std::string l; for (const auto& n : MatVariableNames(args->data)) l += (l.empty() ? "" : ", ") + n; return l; }() + ")");
    const bool named = !args->u_names.empty() || !args->y_names.empty() || !args->time_name.empty();
    if (!mat && named && (args->u_names.empty() || args->y_names.empty()))
      throw std::invalid_argument("a CSV record's own column names need both --u and --y (and --time when the "
                                  "time column is not t or time)");
    if (!mat && named && !FindMethod(args->method).needs_record)
      throw std::invalid_argument("--u, --y and --time choose the columns of a time record; method '" +
                                  args->method + "' reads its file itself");
    const MethodReport report =
        mat     ? RunMethod(args->method, ReadMatRecord(args->data, args->u_names, args->y_names, args->ts), options)
        : named ? RunMethod(args->method,
                            ReadIoRecordCsv(args->data, {SplitColumnNames(args->u_names, "--u"),
                                                         SplitColumnNames(args->y_names, "--y"), args->time_name}),
                            options)
                : RunMethod(args->method, args->data, options);
    if (args->json) {
      nlohmann::json model = report.json.at("model");
      nlohmann::json identification = report.json;
      identification.erase("model");
      identification["data"] = args->data;
      model["identification"] = identification;
      std::cout << model.dump(2) << "\n";
    } else {
      std::cout << report.text;
    }
  });
}

}  // namespace idrig
