// idrig-rig-sim: see services/rig_sim/rig_sim.h. Config: deploy/config/rig_sim.json.
#include "services/common/service_main.h"
#include "services/rig_sim/rig_sim.h"

int main(int argc, char** argv) {
  return idrig::RunServiceMain<idrig::RigSim, idrig::RigSimConfig>(
      argc, argv, "idrig-rig-sim", "simulated rig (plant + effect + noise) over LCM",
      {{"--rig", "rig_id", "rig id"},
       {"--key-file", "key_file", "HMAC key file"},
       {"--model", "model_file", "plant model (idrig.model/1 JSON)"}},
      20);
}
