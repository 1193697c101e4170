// The LCM handlers of the worker (identify requests, claims/grants/denials/done, result acks,
// measurement and replayed blocks, experiment status, replay done) and the logger (blocks,
// commands, experiment status, replay requests), both on one memq:// bus, so a job the fuzzer
// grants fetches its record from the logger's replay and runs the method on the blocks the
// fuzzer sent. Both services do their work on this thread, through their seams for tests
// (WorkerConfig::compute_inline: the method runs when the record is complete;
// LoggerConfig::writer_thread = false: Poll()/Flush() store what is queued), so a run repeats.
// The input is the framing of fuzz_bus.h: the target puts the fingerprint in front and signs
// each message with the deployment key of its role, as a holder of the key would (operator
// requests; the catalogue's re-offers, grants and acks with the service key; commands with the
// command key); blocks, status and replays are unsigned by design. The services are made afresh
// for every input (each input reproduces alone); the logger's store is SQLite :memory:, its
// .lcmlog goes to a per-process temp dir, removed and made again every 1000 inputs.
// A crash, a sanitizer report, an exception out of a handler (handler_errors) or out of Tick()
// is a finding.
#include <idrig/experiment_status_t.hpp>
#include <idrig/identify_claim_t.hpp>
#include <idrig/identify_request_t.hpp>
#include <idrig/measurement_block_t.hpp>
#include <idrig/replay_done_t.hpp>
#include <idrig/replay_request_t.hpp>
#include <idrig/result_ack_t.hpp>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "core/transport/auth.h"
#include "core/transport/channels.h"
#include "core/transport/transport.h"
#include "services/logger/logger_service.h"
#include "services/worker/worker_service.h"
#include "tests/fuzz/fuzz_bus.h"

namespace {
using namespace idrig;
using namespace idrig::fuzz;

const char* kRig = "sim1";
const char* kWorker = "worker-fuzz";

std::filesystem::path& TempDir() {
  static std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("fuzz_worker_logger." + std::to_string(getpid()));
  return dir;
}

struct Bus {
  std::unique_ptr<Transport> transport = MakeLcmTransport("memq://");
  std::unique_ptr<WorkerService> worker;
  std::unique_ptr<LoggerService> logger;
  Bus() {
    WorkerConfig w;
    w.worker_id = kWorker;
    w.keys.keys[kOperatorRole] = OperatorKey();
    w.keys.keys[kServiceRole] = ServiceKey();
    w.compute_inline = true;
    worker = std::make_unique<WorkerService>(*transport, w);
    LoggerConfig l;
    l.db_path = ":memory:";
    l.lcmlog_path = (TempDir() / "fuzz.lcmlog").string();
    l.writer_thread = false;
    l.recover_period_s = 0;  // Poll() (once an input, at its end) runs the recovery and summary
    logger = std::make_unique<LoggerService>(*transport, l);
  }
  // Delivers what is on the bus, lets both services act, and delivers their answers (the
  // worker's claims and replay requests are answered by the logger's replays, on which the
  // worker may run the method).
  void Pump() {
    transport->Handle(0);
    worker->Tick();
    logger->Flush();  // stores (and answers replay requests); the recovery is left to Poll()
    transport->Handle(0);
    worker->Tick();
  }
};

// The iterative methods (oe, armax, bj, auto, arx-oe: 0.3-1 s a job on 160 samples under ASan)
// and gap-diagnose (seconds) would make 10^6 inputs take days: a request for one of them runs
// arx (with the request's options) instead. The worker's path is the same for every method
// (Compute -> RunMethod); what the target leaves to the numerics' own tests is their iterations.
void CheapMethod(std::vector<uint8_t>* bytes) {
  identify_request_t request;
  if (!Decode(bytes->data(), bytes->size(), &request, nullptr)) return;
  static const std::set<std::string> slow = {"oe", "armax", "bj", "auto", "arx-oe", "gap-diagnose"};
  if (!slow.count(request.method)) return;
  request.method = "arx";
  bytes->resize(request.getEncodedSize());
  request.encode(bytes->data(), 0, static_cast<int>(bytes->size()));
}

void PublishRequest(Transport& t, EnvelopeSigner& signer, const uint8_t* payload, size_t size) {
  std::vector<uint8_t> bytes = WithFingerprint<identify_request_t>(payload, size);
  CheapMethod(&bytes);
  const std::string channel = Channel(kRig, ChannelKind::kIdentifyRequest);
  const std::vector<uint8_t> sealed = signer.SealBytes(channel, identify_request_t::getTypeName(), bytes);
  t.Publish(channel, sealed.data(), sealed.size());
}

EnvelopeSigner& OperatorSigner() {
  static EnvelopeSigner s(kOperatorRole, OperatorKey(), "cli:fuzz@host");
  return s;
}
EnvelopeSigner& CatalogSigner() {
  static EnvelopeSigner s(kServiceRole, ServiceKey(), "catalog-fuzz");
  return s;
}

void Dispatch(Bus& bus, uint8_t selector, const uint8_t* payload, size_t size) {
  Transport& t = *bus.transport;
  auto channel = [](ChannelKind kind) { return Channel(kRig, kind); };
  switch (selector % 12) {
    case 0:  // from the command line
      return PublishRequest(t, OperatorSigner(), payload, size);
    case 1:  // re-offered by the catalogue
      return PublishRequest(t, CatalogSigner(), payload, size);
    case 2:  // grants, denials, done (and other workers' claims)
      return PublishSigned<identify_claim_t>(t, CatalogSigner(), channel(ChannelKind::kClaim),
                                             payload, size);
    case 3:
      return PublishSigned<result_ack_t>(t, CatalogSigner(), channel(ChannelKind::kAck), payload,
                                         size);
    case 4:
      return PublishPlain<measurement_block_t>(t, channel(ChannelKind::kMeasurement), payload, size);
    case 5:
      return PublishPlain<measurement_block_t>(t, channel(ChannelKind::kReplay), payload, size);
    case 6:
      return PublishPlain<experiment_status_t>(t, channel(ChannelKind::kExperimentStatus), payload,
                                               size);
    case 7:
      return PublishPlain<replay_done_t>(t, channel(ChannelKind::kReplayDone), payload, size);
    case 8:
      return PublishCommand(t, channel(ChannelKind::kCommand), payload, size);
    case 9:
      return PublishPlain<replay_request_t>(t, channel(ChannelKind::kReplayRequest), payload, size);
    case 10:  // raw bytes, no key: what anyone on the bus can send
      t.Publish(channel(ChannelKind::kClaim), payload, size);
      return;
    default:
      t.Publish(channel(ChannelKind::kMeasurement), payload, size);
      return;
  }
}

// IDRIG_FUZZ_WRITE_SEEDS=DIR: writes the seed corpus (valid message chains) to DIR and exits.
// IDRIG_FUZZ_TRACE=1: prints, after each input, the jobs done and both services' details.
void WriteSeeds(const std::string& dir);

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  InitHandlerTarget(WriteSeeds);
  std::atexit([] {
    std::error_code ignored;
    std::filesystem::remove_all(TempDir(), ignored);
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  constexpr int kInputsPerLogFile = 1000;
  static int inputs = 0;
  if (inputs++ % kInputsPerLogFile == 0) {
    std::filesystem::remove_all(TempDir());
    std::filesystem::create_directories(TempDir());
  }
  Bus bus;
  ForEachMessage(data, size, [&](uint8_t selector, const uint8_t* payload, size_t length) {
    Dispatch(bus, selector, payload, length);
    bus.Pump();
  });
  bus.logger->Poll(0);  // the loss recovery and summary, on what the input left
  bus.Pump();
  static const bool trace = std::getenv("IDRIG_FUZZ_TRACE") != nullptr;
  if (trace)  // what an input did (to check that the seeds reach what they are meant to)
    std::fprintf(stderr, "jobs done %lld, logger blocks %lld; worker %s; logger %s\n",
                 static_cast<long long>(bus.worker->jobs_done()),
                 static_cast<long long>(bus.logger->stored_blocks()),
                 bus.worker->Details().dump().c_str(), bus.logger->Details().dump().c_str());
  AbortOnHandlerErrors(*bus.transport, 0);
  return 0;
}

namespace {

// A record of a first-order plant, y[k+1] = 0.8 y[k] + 0.5 u[k], under a ±1 input switching
// every 1..4 samples: enough for arx and n4sid to find a model in the seeds.
std::vector<measurement_block_t> Blocks(int64_t experiment, int blocks, int per_block) {
  std::vector<measurement_block_t> out;
  double y = 0, u = 1;
  uint32_t lfsr = 0xACE1u;
  for (int b = 0; b < blocks; ++b) {
    measurement_block_t m{};
    m.rig_id = kRig;
    m.experiment_id = experiment;
    m.seq = b;
    m.first_sample = static_cast<int64_t>(b) * per_block;
    m.sample_time_s = 0.01;
    m.n_samples = per_block;
    m.n_inputs = m.n_outputs = 1;
    for (int i = 0; i < per_block; ++i) {
      lfsr = (lfsr >> 1) ^ (-(lfsr & 1u) & 0xB400u);
      if (lfsr & 1u) u = -u;
      m.u.push_back({u});
      m.y.push_back({y});
      y = 0.8 * y + 0.5 * u;
    }
    out.push_back(m);
  }
  return out;
}

experiment_status_t RigStatus(int64_t experiment, int32_t state, int64_t blocks, int64_t samples) {
  return SeedRigStatus(kRig, experiment, state, blocks, samples, "samples 10..19 missing");
}

result_ack_t Ack(int64_t request) {
  result_ack_t a{};
  a.request_id = request;
  a.rig_id = kRig;
  a.model_id = 1;
  a.worker_id = kWorker;
  return a;
}

replay_request_t ReplayRequest(int64_t id, int64_t experiment, std::vector<int64_t> have) {
  replay_request_t r{};
  r.replay_id = id;
  r.requester = "worker-other";
  r.rig_id = kRig;
  r.experiment_id = experiment;
  r.have_seqs = std::move(have);
  r.n_have = static_cast<int32_t>(r.have_seqs.size());
  return r;
}

replay_done_t ReplayDone(int64_t experiment, bool ended, bool complete, int64_t blocks) {
  replay_done_t d{};
  d.replay_id = 1;
  d.requester = kWorker;
  d.rig_id = kRig;
  d.experiment_id = experiment;
  d.ended = ended;
  d.complete = complete;
  d.blocks_total = blocks;
  d.samples_total = blocks * 10;
  return d;
}

actuator_command_t Command(int64_t seq, int64_t experiment, int64_t first, int32_t flags, int n) {
  return SeedCommand(kRig, seq, experiment, first, flags, n,
                     [](int i) { return i % 3 ? 1.0 : -1.0; });
}

identify_claim_t Claim(int64_t request, int32_t kind, const std::string& worker) {
  return SeedClaim(kRig, request, kind, worker, 10);
}

void WriteSeeds(const std::string& dir) {
  const int32_t done = experiment_status_t::STATE_DONE;
  const int32_t grant = identify_claim_t::KIND_GRANT;
  const auto blocks = Blocks(7, 4, 10);  // 40 samples: a seed fits in the target's 1.5 KB
  // A job from request to acknowledged result, for three methods.
  for (const auto& [name, method, options] :
       std::vector<std::tuple<std::string, std::string, std::string>>{
           {"worker_job_arx", "arx", R"({"order":1})"},
           {"worker_job_n4sid", "n4sid", R"({"order":1})"},
           {"worker_job_step_prony", "step-prony", "{}"}}) {
    SeedWriter seed;
    for (const auto& b : blocks) seed.Add(4, b);
    seed.Add(6, RigStatus(7, done, 4, 40))
        .Add(0, SeedIdentify(kRig, 11, 7, method, options))
        .Add(2, Claim(11, grant, kWorker))
        .Add(3, Ack(11))
        .Save(dir + "/" + name);
  }
  {  // The record arrives after the grant: the worker asks the logger for a replay.
    SeedWriter seed;
    seed.Add(1, SeedIdentify(kRig, 12, 7, "arx", "{}")).Add(2, Claim(12, grant, kWorker));
    for (const auto& b : blocks) seed.Add(4, b);
    seed.Add(6, RigStatus(7, done, 4, 40)).Add(3, Ack(12)).Save(dir + "/worker_record_late");
  }
  {  // Blocks replayed to the worker alone, and the logger's answer named by replay_done.
    SeedWriter seed;
    seed.Add(0, SeedIdentify(kRig, 13, 7, "arx", R"({"order":2})")).Add(2, Claim(13, grant, kWorker));
    for (const auto& b : blocks) seed.Add(5, b);
    // (replay_done's replay_id is the worker's own, which the fuzzer does not know: ignored)
    seed.Add(7, ReplayDone(7, true, true, 4))
        .Add(6, RigStatus(7, done, 4, 40))
        .Add(3, Ack(13))
        .Save(dir + "/worker_replayed");
  }
  {  // An interrupted experiment: refused, then asked for the longest complete segment.
    SeedWriter seed;
    for (int i = 0; i < 2; ++i) seed.Add(4, blocks[i]);
    seed.Add(6, RigStatus(7, experiment_status_t::STATE_INTERRUPTED, 2, 20))
        .Add(0, SeedIdentify(kRig, 14, 7, "arx", "{}"))
        .Add(2, Claim(14, grant, kWorker))
        .Add(3, Ack(14))
        .Add(0, SeedIdentify(kRig, 15, 7, "arx", R"({"segment":"longest_complete","order":1})"))
        .Add(2, Claim(15, grant, kWorker))
        .Save(dir + "/worker_interrupted");
  }
  // Claims the worker must not act on: a denial, a grant to another worker, done elsewhere.
  SeedWriter()
      .Add(0, SeedIdentify(kRig, 16, 7, "arx", "{}"))
      .Add(2, Claim(16, identify_claim_t::KIND_DENY, "worker-other"))
      .Add(0, SeedIdentify(kRig, 17, 7, "arx", "{}"))
      .Add(2, Claim(17, grant, "worker-other"))
      .Add(0, SeedIdentify(kRig, 18, 7, "nonsense", "[]"))
      .Add(2, Claim(18, grant, kWorker))
      .Add(2, Claim(18, identify_claim_t::KIND_DONE, "worker-other"))
      .Add(3, Ack(18))
      .Save(dir + "/worker_claims");
  {  // The logger: commands and blocks with a gap, the rig's end, and a replay for someone else.
    SeedWriter seed;
    seed.Add(8, Command(1, 9, 0, 0, 10)).Add(8, Command(2, 9, 10, 0, 10));
    const auto b9 = Blocks(9, 3, 10);
    seed.Add(4, b9[0]).Add(4, b9[2]);
    seed.Add(8, Command(3, 9, 20, actuator_command_t::FLAG_FINAL, 10))
        .Add(6, RigStatus(9, done, 3, 30))
        .Add(9, ReplayRequest(5, 9, {0}))
        .Add(9, ReplayRequest(6, 9, {}))
        .Save(dir + "/logger_gap_replay");
  }
  {  // The logger: an excite status and a replay of an unknown experiment.
    experiment_status_t excite = RigStatus(10, experiment_status_t::STATE_RUNNING, 0, 0);
    excite.source = "excite";
    excite.signal_spec = "prbs:bits=10,amp=1";
    SeedWriter()
        .Add(6, excite)
        .Add(4, blocks[0])
        .Add(9, ReplayRequest(7, 99, {}))
        .Add(6, RigStatus(10, experiment_status_t::STATE_STOPPED, 1, 10))
        .Save(dir + "/logger_status_unknown_replay");
  }
}

}  // namespace
