// idrig identify --data FILE --method NAME [--order N] [--option key=value]... [--json]
#include <iostream>
#include <memory>
#include <string>
#include <vector>

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
}  // namespace

void RegisterIdentifyCommand(CLI::App& app) {
  struct Args {
    std::string data, method = "arx", options_json;
    int order = 0;
    std::vector<std::string> options;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  std::string methods_help = "identification method:";
  for (const auto& m : Methods()) methods_help += "\n  " + m.name + ": " + m.summary;
  auto* cmd = app.add_subcommand("identify", "identify a model from a record (CSV t,u,y or t,u1,..,y1,..)");
  cmd->add_option("--data", args->data, "data file")->required();
  cmd->add_option("--method", args->method, methods_help);
  cmd->add_option("--order", args->order, "model order (0 or absent: chosen automatically)");
  cmd->add_option("--option", args->options, "method option key=value (value is JSON or a word); repeatable");
  cmd->add_option("--options-json", args->options_json, "method options as one JSON object");
  cmd->add_flag("--json", args->json, "print the model as idrig.model/1 JSON (with an \"identification\" report)");
  cmd->callback([args] {
    nlohmann::json options = args->options_json.empty() ? nlohmann::json::object()
                                                        : nlohmann::json::parse(args->options_json);
    if (args->order > 0) options["order"] = args->order;
    for (const auto& kv : args->options) {
      const auto eq = kv.find('=');
      if (eq == std::string::npos || eq == 0)
        throw std::invalid_argument("--option expects key=value, got '" + kv + "'");
      options[kv.substr(0, eq)] = ParseOptionValue(kv.substr(eq + 1));
    }
    const MethodReport report = RunMethod(args->method, args->data, options);
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
