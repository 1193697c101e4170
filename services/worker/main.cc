// idrig-worker: see services/worker/worker_service.h. Config: deploy/config/worker.json.
#include "services/common/service_main.h"
#include "services/worker/worker_service.h"

int main(int argc, char** argv) {
  return idrig::RunServiceMain<idrig::WorkerService, idrig::WorkerConfig>(
      argc, argv, "idrig-worker", "claims identification jobs, runs them, publishes results",
      {{"--id", "worker_id", "worker id (default worker-<host>-<pid>)"},
       {"--debug-delay", "debug_delay_s", "extra seconds per job (failure tests)", true}},
      20);
}
