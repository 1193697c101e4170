// idrig-worker: see services/worker/worker_service.h. Config: deploy/config/worker.json.
#include <CLI/CLI.hpp>
#include <iostream>

#include "core/transport/service_util.h"
#include "core/transport/transport.h"
#include "services/worker/worker_service.h"

int main(int argc, char** argv) {
  CLI::App app{"idrig-worker: claims identification jobs, runs them, publishes results"};
  std::string config_file, url, id;
  double debug_delay = -1;
  app.add_option("--config", config_file, "JSON config file");
  app.add_option("--url", url, "LCM URL");
  app.add_option("--id", id, "worker id (default worker-<host>-<pid>)");
  app.add_option("--debug-delay", debug_delay, "extra seconds per job (failure tests)");
  double loss = -1;
  app.add_option("--loss", loss,
                 "drop this fraction of received messages (tests of a lossy network)");
  CLI11_PARSE(app, argc, argv);
  try {
    nlohmann::json config = idrig::ReadJsonConfig(config_file);
    if (!id.empty()) config["worker_id"] = id;
    if (debug_delay >= 0) config["debug_delay_s"] = debug_delay;
    if (url.empty()) url = idrig::ConfigValue<std::string>(config, "lcm_url", "");
    auto transport = idrig::MakeServiceTransport(
        url, loss >= 0 ? loss : idrig::ConfigValue<double>(config, "receive_loss", 0.0));
    idrig::WorkerService worker(*transport, idrig::WorkerConfig::FromJson(config));
    idrig::InstallStopSignals();
    while (!idrig::StopRequested()) worker.Poll(20);
  } catch (const std::exception& e) {
    std::cerr << "idrig-worker: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
