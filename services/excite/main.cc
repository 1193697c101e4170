// idrig-excite: see services/excite/excite_service.h. Config: deploy/config/excite.json.
#include <CLI/CLI.hpp>
#include <iostream>

#include "core/transport/service_util.h"
#include "core/transport/transport.h"
#include "services/excite/excite_service.h"

int main(int argc, char** argv) {
  CLI::App app{"idrig-excite: experiment requests -> signed actuator commands"};
  std::string config_file, url, rig, key_file;
  app.add_option("--config", config_file, "JSON config file");
  app.add_option("--url", url, "LCM URL (default: config 'lcm_url', else LCM_DEFAULT_URL)");
  app.add_option("--rig", rig, "rig id (overrides the config)");
  app.add_option("--key-file", key_file, "HMAC key file (overrides the config)");
  double loss = -1;
  app.add_option("--loss", loss,
                 "drop this fraction of received messages (tests of a lossy network)");
  CLI11_PARSE(app, argc, argv);
  try {
    nlohmann::json config = idrig::ReadJsonConfig(config_file);
    if (!rig.empty()) config["rig_id"] = rig;
    if (!key_file.empty()) config["key_file"] = key_file;
    if (url.empty()) url = idrig::ConfigValue<std::string>(config, "lcm_url", "");
    auto transport = idrig::MakeServiceTransport(
        url, loss >= 0 ? loss : idrig::ConfigValue<double>(config, "receive_loss", 0.0));
    idrig::ExciteService service(*transport, idrig::ExciteConfig::FromJson(config));
    idrig::InstallStopSignals();
    while (!idrig::StopRequested()) service.Poll(5);
  } catch (const std::exception& e) {
    std::cerr << "idrig-excite: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
