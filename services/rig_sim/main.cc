// idrig-rig-sim: see services/rig_sim/rig_sim.h. Config: deploy/config/rig_sim.json.
#include <CLI/CLI.hpp>
#include <iostream>

#include "core/transport/service_util.h"
#include "core/transport/transport.h"
#include "services/rig_sim/rig_sim.h"

int main(int argc, char** argv) {
  CLI::App app{"idrig-rig-sim: simulated rig (plant + noise) over LCM"};
  std::string config_file, url, rig, key_file, model_file;
  app.add_option("--config", config_file, "JSON config file");
  app.add_option("--url", url, "LCM URL");
  app.add_option("--rig", rig, "rig id");
  app.add_option("--key-file", key_file, "HMAC key file");
  app.add_option("--model", model_file, "plant model (idrig.model/1 JSON)");
  double loss = -1;
  app.add_option("--loss", loss,
                 "drop this fraction of received messages (tests of a lossy network)");
  CLI11_PARSE(app, argc, argv);
  try {
    nlohmann::json config = idrig::ReadJsonConfig(config_file);
    if (!rig.empty()) config["rig_id"] = rig;
    if (!key_file.empty()) config["key_file"] = key_file;
    if (!model_file.empty()) config["model_file"] = model_file;
    if (url.empty()) url = idrig::ConfigValue<std::string>(config, "lcm_url", "");
    auto transport = idrig::MakeServiceTransport(
        url, loss >= 0 ? loss : idrig::ConfigValue<double>(config, "receive_loss", 0.0));
    idrig::RigSim rig_sim(*transport, idrig::RigSimConfig::FromJson(config));
    idrig::InstallStopSignals();
    while (!idrig::StopRequested()) rig_sim.Poll(20);
  } catch (const std::exception& e) {
    std::cerr << "idrig-rig-sim: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
