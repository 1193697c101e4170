// idrig-catalog: see services/catalog/catalog_service.h. Config: deploy/config/catalog.json.
#include <CLI/CLI.hpp>
#include <iostream>

#include "core/transport/service_util.h"
#include "core/transport/transport.h"
#include "services/catalog/catalog_service.h"

int main(int argc, char** argv) {
  CLI::App app{"idrig-catalog: stores identified models idempotently and acknowledges them"};
  std::string config_file, url, db;
  app.add_option("--config", config_file, "JSON config file");
  app.add_option("--url", url, "LCM URL");
  app.add_option("--db", db, "catalogue (SQLite file)");
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
    idrig::CatalogService service(*transport, idrig::CatalogConfig::FromJson(config));
    idrig::InstallStopSignals();
    while (!idrig::StopRequested()) service.Poll(50);
  } catch (const std::exception& e) {
    std::cerr << "idrig-catalog: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
