#pragma once
// The one main() every service shares: --config FILE (JSON), --url, --loss, plus flags that
// override single config keys; builds the LCM transport, constructs the service from its config,
// and polls until SIGINT/SIGTERM. Errors (bad config, no plant, …) print one line and exit 1.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <iostream>
#include <string>
#include <vector>

#include "core/transport/service_util.h"
#include "core/transport/transport.h"

namespace idrig {

struct ConfigFlag {
  std::string flag;  // e.g. "--rig"
  std::string key;   // config key it overrides, e.g. "rig_id"
  std::string help;
  bool number = false;  // the value is a number (else a string, even "42")
};

// Service must be constructible as Service(Transport&, Config) and have Poll(int timeout_ms).
template <class Service, class Config>
int RunServiceMain(int argc, char** argv, const std::string& name, const std::string& summary,
                   const std::vector<ConfigFlag>& flags, int poll_ms) {
  CLI::App app{name + ": " + summary};
  std::string config_file, url, log_file;
  double loss = -1;
  app.add_option("--config", config_file, "JSON config file");
  app.add_option("--url", url, "LCM URL (default: config 'lcm_url', else LCM_DEFAULT_URL)");
  app.add_option("--log-file", log_file, "also append the log to this file (config 'log_file')");
  app.add_option("--loss", loss, "drop this fraction of received messages (tests of a lossy network)");
  std::vector<std::string> values(flags.size());
  for (size_t i = 0; i < flags.size(); ++i)
    app.add_option(flags[i].flag, values[i], flags[i].help + " (config '" + flags[i].key + "')");
  CLI11_PARSE(app, argc, argv);
  bool logging = false;
  try {
    nlohmann::json config = ReadJsonConfig(config_file);
    for (size_t i = 0; i < flags.size(); ++i) {
      if (values[i].empty()) continue;
      if (!flags[i].number) {
        config[flags[i].key] = values[i];
        continue;
      }
      const nlohmann::json parsed = nlohmann::json::parse(values[i], nullptr, false);
      if (!parsed.is_number())
        throw std::invalid_argument(flags[i].flag + " expects a number, got '" + values[i] + "'");
      config[flags[i].key] = parsed;
    }
    if (log_file.empty()) log_file = ConfigValue<std::string>(config, "log_file", "");
    SetUpServiceLog(name, log_file);
    logging = true;
    if (url.empty()) url = ConfigValue<std::string>(config, "lcm_url", "");
    auto transport = MakeServiceTransport(
        url, loss >= 0 ? loss : ConfigValue<double>(config, "receive_loss", 0.0));
    Service service(*transport, Config::FromJson(config));
    InstallStopSignals();
    spdlog::info("started (pid {}, url {})", getpid(), url.empty() ? "LCM default" : url);
    while (!StopRequested()) service.Poll(poll_ms);
    spdlog::info("stopping on a signal");
  } catch (const std::exception& e) {
    if (logging)
      spdlog::critical("{}", e.what());
    else
      std::cerr << name << ": " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace idrig
