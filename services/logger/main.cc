// idrig-logger: see services/logger/logger_service.h. Config: deploy/config/logger.json.
#include <CLI/CLI.hpp>
#include <iostream>

#include "core/transport/service_util.h"
#include "core/transport/transport.h"
#include "services/logger/logger_service.h"

int main(int argc, char** argv) {
  CLI::App app{"idrig-logger: experiment store with gap detection and replay"};
  std::string config_file, url, db;
  app.add_option("--config", config_file, "JSON config file");
  app.add_option("--url", url, "LCM URL");
  app.add_option("--db", db, "experiment store (SQLite file)");
  double loss = -1;
  app.add_option("--loss", loss,
                 "drop this fraction of received messages (tests of a lossy network)");
  CLI11_PARSE(app, argc, argv);
  try {
    nlohmann::json config = idrig::ReadJsonConfig(config_file);
    if (!db.empty()) config["db_path"] = db;
    if (url.empty()) url = idrig::ConfigValue<std::string>(config, "lcm_url", "");
    auto transport = idrig::MakeServiceTransport(
        url, loss >= 0 ? loss : idrig::ConfigValue<double>(config, "receive_loss", 0.0));
    idrig::LoggerService logger(*transport, idrig::LoggerConfig::FromJson(config));
    idrig::InstallStopSignals();
    while (!idrig::StopRequested()) logger.Poll(50);
  } catch (const std::exception& e) {
    std::cerr << "idrig-logger: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
