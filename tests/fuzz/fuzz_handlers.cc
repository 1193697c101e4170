// The LCM handlers of the most exposed services, driven through a real memq:// transport: the
// catalogue (identify requests, claims, results, experiment status), excite (experiment
// requests, rig status) and the simulated rig (actuator commands), all three on one bus, so a
// request the fuzzer makes starts real commands, blocks, replies and claims among them.
// The input is a sequence of messages, each [selector][length, 2 bytes big-endian][payload]:
// the payload is an LCM encoding without its 8-byte fingerprint (the target puts the right one
// in front), and the target signs it with the deployment's key for its role, as a holder of the
// key would (the envelope itself is fuzzed by fuzz_messages). So the fuzzer reaches what an
// authenticated but malformed or hostile message does to a handler. After each message the bus
// is drained and every service ticks. The services (the catalogue in SQLite :memory:) are made
// afresh every 500 inputs (see LLVMFuzzerTestOneInput).
// A crash, a sanitizer report, or an exception out of a handler (counted in handler_errors:
// DESIGN.md says handlers never throw) is a finding.
#include <idrig/actuator_command_t.hpp>
#include <idrig/experiment_request_t.hpp>
#include <idrig/experiment_status_t.hpp>
#include <idrig/identify_claim_t.hpp>
#include <idrig/identify_request_t.hpp>
#include <idrig/model_result_t.hpp>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "core/io/model_json.h"
#include "core/transport/auth.h"
#include "core/transport/channels.h"
#include "core/transport/signing.h"
#include "core/transport/transport.h"
#include "services/catalog/catalog_service.h"
#include "services/excite/excite_service.h"
#include "services/rig_sim/rig_sim.h"
#include "tests/fuzz/fuzz_bus.h"

namespace {
using namespace idrig;
using namespace idrig::fuzz;

const char* kRig = "sim1";
const char* kWorker = "worker-fuzz";

struct Bus {
  std::unique_ptr<Transport> transport = MakeLcmTransport("memq://");
  std::unique_ptr<CatalogService> catalog;
  std::unique_ptr<ExciteService> excite;
  std::unique_ptr<RigSim> rig;
  Bus() {
    CatalogConfig c;
    c.db_path = ":memory:";
    c.keys.keys[kOperatorRole] = OperatorKey();
    c.keys.keys[kServiceRole] = ServiceKey();
    catalog = std::make_unique<CatalogService>(*transport, c);
    ExciteConfig e;  // deploy/config/excite.json's limits
    e.rig_id = kRig;
    e.key = CommandKey();
    e.keys.keys[kOperatorRole] = OperatorKey();
    e.max_speed = 1.0;
    excite = std::make_unique<ExciteService>(*transport, e);
    RigSimConfig r;
    r.rig_id = kRig;
    r.keys[1] = CommandKey();
    r.plant = ModelFromJson(nlohmann::json::parse(
        R"({"format":"idrig.model/1","kind":"tf","domain":"continuous","num":[1.0],"den":[1.0,0.4,1.0]})"));
    r.noise_std = 0.01;
    rig = std::make_unique<RigSim>(*transport, r);
  }
  void Pump() {
    for (int i = 0; i < 4 && transport->Handle(0) > 0; ++i) {
    }
    catalog->Tick();
    excite->Tick();
    rig->Tick();
    transport->Handle(0);
  }
};

EnvelopeSigner& OperatorSigner() {
  static EnvelopeSigner s(kOperatorRole, OperatorKey(), "cli:fuzz@host");
  return s;
}
EnvelopeSigner& ServiceSigner() {
  static EnvelopeSigner s(kServiceRole, ServiceKey(), kWorker);
  return s;
}

template <class T>
void PublishSigned(Bus& bus, EnvelopeSigner& signer, ChannelKind kind, const uint8_t* payload,
                   size_t size) {
  fuzz::PublishSigned<T>(*bus.transport, signer, Channel(kRig, kind), payload, size);
}

void PublishCommand(Bus& bus, const uint8_t* payload, size_t size) {
  fuzz::PublishCommand(*bus.transport, Channel(kRig, ChannelKind::kCommand), payload, size);
}

void Dispatch(Bus& bus, uint8_t selector, const uint8_t* payload, size_t size) {
  switch (selector % 8) {
    case 0:
      return PublishSigned<identify_request_t>(bus, OperatorSigner(), ChannelKind::kIdentifyRequest,
                                               payload, size);
    case 1:
      return PublishSigned<identify_claim_t>(bus, ServiceSigner(), ChannelKind::kClaim, payload,
                                             size);
    case 2:
      return PublishSigned<model_result_t>(bus, ServiceSigner(), ChannelKind::kResult, payload,
                                           size);
    case 3:  // unsigned by design (status is a snapshot anyone may read)
      return PublishPlain<experiment_status_t>(*bus.transport,
                                               Channel(kRig, ChannelKind::kExperimentStatus),
                                               payload, size);
    case 4:
      return PublishSigned<experiment_request_t>(bus, OperatorSigner(),
                                                 ChannelKind::kExperimentRequest, payload, size);
    case 5:
      return PublishCommand(bus, payload, size);
    case 6:  // raw bytes, no key: what anyone on the bus can send
      bus.transport->Publish(Channel(kRig, ChannelKind::kIdentifyRequest), payload, size);
      return;
    default:
      bus.transport->Publish(Channel(kRig, ChannelKind::kExperimentRequest), payload, size);
      return;
  }
}

// IDRIG_FUZZ_WRITE_SEEDS=DIR: writes the seed corpus (valid message chains) to DIR and exits.
void WriteSeeds(const std::string& dir);

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  InitHandlerTarget(WriteSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // Making the three services (SQLite schema, LCM, subscriptions) costs ~40 times an input under
  // ASan: they live for kInputsPerBus inputs, so an input may meet state earlier ones left (a
  // crash is reproduced by running the inputs since the last renewal, which libFuzzer's
  // -runs/-seed replay does; most reproduce alone).
  constexpr int kInputsPerBus = 500;
  static std::unique_ptr<Bus> shared;
  static int inputs = 0;
  if (!shared || inputs++ % kInputsPerBus == 0) {
    shared.reset();
    shared = std::make_unique<Bus>();
  }
  Bus& bus = *shared;
  const int64_t errors_before = bus.transport->counters().handler_errors;
  ForEachMessage(data, size, [&](uint8_t selector, const uint8_t* payload, size_t length) {
    Dispatch(bus, selector, payload, length);
    bus.Pump();
  });
  AbortOnHandlerErrors(*bus.transport, errors_before);
  return 0;
}

namespace {

experiment_status_t RigStatus(int64_t experiment, int32_t state) {
  return SeedRigStatus(kRig, experiment, state, 8, 800, "samples 300..399 missing");
}

model_result_t Result(int64_t request, int64_t experiment, const std::string& method, bool ok,
                      const std::string& report) {
  model_result_t m{};
  m.request_id = request;
  m.rig_id = kRig;
  m.experiment_id = experiment;
  m.worker_id = kWorker;
  m.attempt = 1;
  m.ok = ok;
  m.method = method;
  m.options_json = "{}";
  m.data_hash = std::string(64, 'a');
  m.n_samples = 800;
  m.sample_time_s = 0.01;
  m.software_version = "fuzz";
  m.compute_s = 0.1;
  m.message = ok ? "" : "too few samples for the order";
  m.report_json = report;
  return m;
}

experiment_request_t Experiment(int64_t request, int64_t experiment, int32_t action,
                                const std::string& spec, double fs, double duration_s) {
  experiment_request_t r{};
  r.request_id = request;
  r.rig_id = kRig;
  r.experiment_id = experiment;
  r.action = action;
  r.signal_spec = spec;
  r.sample_rate_hz = fs;
  r.duration_s = duration_s;
  r.speed = 1;
  r.requested_by = "fuzz";
  return r;
}

actuator_command_t Command(int64_t seq, int64_t experiment, int64_t first, int32_t flags, int n) {
  return SeedCommand(kRig, seq, experiment, first, flags, n,
                     [](int i) { return 0.5 * ((i / 3) % 2 ? 1 : -1); });
}

identify_claim_t Claim(int64_t request) {
  return SeedClaim(kRig, request, identify_claim_t::KIND_CLAIM, kWorker);
}

void WriteSeeds(const std::string& dir) {
  const std::string tf =
      R"({"format":"idrig.model/1","kind":"tf","domain":"continuous","Ts":0,"num":[1.0],"den":[1.0,0.4,1.0],"delay_s":0})";
  const std::string report = R"({"status":"ok","fit_percent":97.5,"model":)" + tf + "}";
  const int32_t done = experiment_status_t::STATE_DONE;
  experiment_status_t from_excite = RigStatus(7, experiment_status_t::STATE_RUNNING);
  from_excite.source = "excite";
  from_excite.signal_spec = "prbs:bits=10,amp=1";
  SeedWriter()
      .Add(3, RigStatus(7, done))
      .Add(3, from_excite)
      .Add(0, SeedIdentify(kRig, 11, 7, "arx", "{}"))
      .Add(1, Claim(11))
      .Add(2, Result(11, 7, "arx", true, report))
      .Add(1, Claim(11))
      .Save(dir + "/catalog_job_stored");
  SeedWriter()
      .Add(3, RigStatus(7, done))
      .Add(0, SeedIdentify(kRig, 12, 7, "n4sid", R"({"order":2})"))
      .Add(1, Claim(12))
      .Add(2, Result(12, 7, "n4sid", false, "{}"))
      .Save(dir + "/catalog_job_failed");
  SeedWriter()
      .Add(3, RigStatus(8, experiment_status_t::STATE_INTERRUPTED))
      .Add(0, SeedIdentify(kRig, 13, 8, "arx", "{}"))
      .Add(0, SeedIdentify(kRig, 14, 8, "arx", R"({"segment":"longest_complete"})"))
      .Add(1, Claim(14))
      .Save(dir + "/catalog_interrupted");
  const std::string gap =
      R"({"status":"ok","model":)" + tf +
      R"(,"details":{"format":"idrig.gap/1","effects":[{"effect":"backlash","params":{"r":0.1}}]}})";
  SeedWriter()
      .Add(3, RigStatus(9, done))
      .Add(0, SeedIdentify(kRig, 15, 9, "gap-diagnose", "{}"))
      .Add(1, Claim(15))
      .Add(2, Result(15, 9, "gap-diagnose", true, gap))
      .Save(dir + "/catalog_gap_report");
  SeedWriter()
      .Add(0, SeedIdentify(kRig, 16, 99, "nonsense", "[]"))
      .Add(2, Result(17, 7, "arx", true, report))
      .Save(dir + "/catalog_refusals");
  const int32_t start = experiment_request_t::ACTION_START, stop = experiment_request_t::ACTION_STOP;
  SeedWriter()
      .Add(4, Experiment(21, 3, start, "prbs:bits=10,amp=1", 100, 2))
      .Add(4, Experiment(21, 3, start, "prbs:bits=10,amp=1", 100, 2))
      .Add(4, Experiment(22, 3, stop, "", 0, 0))
      .Save(dir + "/excite_start_stop");
  SeedWriter()
      .Add(4, Experiment(23, 4, start, "multisine:f0=0.1,lines=1-20,set=odd,phase=schroeder,amp=1",
                         200, 10))
      .Add(3, [] {
        experiment_status_t s = RigStatus(4, experiment_status_t::STATE_FAILED);
        s.message = "|u| above the limit";
        return s;
      }())
      .Save(dir + "/excite_ended_by_rig");
  SeedWriter()
      .Add(4, Experiment(24, 5, start, "chirp:f0=0.1,f1=5,amp=20", 1000, 1e9))
      .Add(4, Experiment(25, 5, start, "step:amp=2,at=1", 1e-6, 1))
      .Add(4, Experiment(26, 5, 7, "diagnose:T=60,f1=2,amp=1", 100, 60))
      .Save(dir + "/excite_refusals");
  SeedWriter()
      .Add(5, Command(1, 31, 0, 0, 10))
      .Add(5, Command(2, 31, 10, 0, 10))
      .Add(5, Command(3, 31, 20, actuator_command_t::FLAG_FINAL, 10))
      .Save(dir + "/rig_commands");
  SeedWriter()
      .Add(5, Command(5, 32, 0, 0, 10))
      .Add(5, Command(5, 32, 10, 0, 10))
      .Add(5, Command(6, 32, 500, 0, 10))
      .Add(5, Command(7, 32, 20, actuator_command_t::FLAG_STOP, 0))
      .Save(dir + "/rig_replay_gap_stop");
}

}  // namespace
