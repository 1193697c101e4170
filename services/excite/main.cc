// idrig-excite: see services/excite/excite_service.h. Config: deploy/config/excite.json.
#include "services/common/service_main.h"
#include "services/excite/excite_service.h"

int main(int argc, char** argv) {
  return idrig::RunServiceMain<idrig::ExciteService, idrig::ExciteConfig>(
      argc, argv, "idrig-excite", "experiment requests -> signed actuator commands",
      {{"--rig", "rig_id", "rig id"}, {"--key-file", "key_file", "HMAC key file"}}, 5);
}
