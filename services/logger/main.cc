// idrig-logger: see services/logger/logger_service.h. Config: deploy/config/logger.json.
#include "services/common/service_main.h"
#include "services/logger/logger_service.h"

int main(int argc, char** argv) {
  return idrig::RunServiceMain<idrig::LoggerService, idrig::LoggerConfig>(
      argc, argv, "idrig-logger", "experiment store with gap detection and replay",
      {{"--db", "db_path", "experiment store (SQLite file)"}}, 50);
}
