// Inputs found by tests/fuzz/fuzz_handlers and fuzz_worker_logger, kept as regression tests: the
// services' classes over memq://, fed the authenticated but hostile messages the fuzzer made.
#include <gtest/gtest.h>

#include <cmath>

#include <idrig/experiment_request_t.hpp>
#include <idrig/experiment_status_t.hpp>
#include <idrig/identify_claim_t.hpp>
#include <idrig/identify_request_t.hpp>
#include <idrig/measurement_block_t.hpp>
#include <idrig/model_result_t.hpp>
#include <idrig/replay_done_t.hpp>
#include <idrig/replay_request_t.hpp>

#include "core/transport/auth.h"
#include "core/transport/channels.h"
#include "core/transport/transport.h"
#include "services/catalog/catalog_service.h"
#include "services/excite/excite_service.h"
#include "services/logger/logger_service.h"
#include "services/worker/worker_service.h"

namespace idrig {
namespace {

HmacKey Key(uint8_t salt) {
  HmacKey key(32);
  for (size_t i = 0; i < key.size(); ++i) key[i] = static_cast<uint8_t>(i * 37 + salt * 101 + 11);
  return key;
}

KeyRing Keys() {
  KeyRing ring;
  ring.keys[kOperatorRole] = Key(2);
  ring.keys[kServiceRole] = Key(3);
  return ring;
}

// crash-803fd990: a signed claim on IDRIG/sim1/CLAIM naming rig "si`1". The catalogue answered
// on Channel("si`1"), which throws: an exception out of the handler (handler_errors 1). Now the
// claim is ignored like any claim whose rig is not its channel's, and a good claim still works.
// (The claim must be for a job the catalogue holds: only a grant is answered on the rig's channel.)
TEST(HandlerRegression, CatalogIgnoresAClaimForAnotherOrUnusableRig) {
  auto transport = MakeLcmTransport("memq://");
  CatalogConfig config;
  config.db_path = ":memory:";
  config.keys = Keys();
  CatalogService catalog(*transport, config);
  EnvelopeSigner worker(kServiceRole, Key(3), "worker-1");
  EnvelopeSigner operator_cli(kOperatorRole, Key(2), "cli:test");
  // Job 12 on experiment 7 of sim1 (the rig's status makes the experiment known).
  experiment_status_t status{};
  status.source = "rig";
  status.rig_id = "sim1";
  status.experiment_id = 7;
  status.state = experiment_status_t::STATE_DONE;
  status.samples_total = 800;
  status.blocks_total = 8;
  transport->PublishMessage(Channel("sim1", ChannelKind::kExperimentStatus), status);
  identify_request_t request{};
  request.request_id = 12;
  request.rig_id = "sim1";
  request.experiment_id = 7;
  request.method = "arx";
  request.options_json = "{}";
  operator_cli.Publish(*transport, Channel("sim1", ChannelKind::kIdentifyRequest), request);
  catalog.Poll(0);
  catalog.Poll(0);
  ASSERT_TRUE(catalog.catalog().Job(12).has_value());
  int grants_on_sim1 = 0;
  transport->Subscribe(Channel("sim1", ChannelKind::kClaim),
                       [&](const std::string&, const uint8_t*, size_t) { ++grants_on_sim1; });
  for (const char* rig : {"si`1", "sim2", "sim1"}) {
    identify_claim_t claim{};
    claim.request_id = 12;
    claim.rig_id = rig;
    claim.kind = identify_claim_t::KIND_CLAIM;
    claim.worker_id = "worker-1";
    worker.Publish(*transport, Channel("sim1", ChannelKind::kClaim), claim);
    catalog.Poll(0);
    catalog.Poll(0);
  }
  EXPECT_EQ(transport->counters().handler_errors, 0);
  // The three claims themselves, and one grant: to the claim that named its channel's rig.
  EXPECT_EQ(grants_on_sim1, 4);
  EXPECT_EQ(catalog.catalog().Job(12)->worker_id, "worker-1");
}

// crash-417cbf93: an (unsigned) experiment status from excite with sample_rate_hz NaN failed the
// catalogue's insert (NOT NULL constraint) inside the handler. Now it is dropped with a log line,
// the experiment already recorded keeps its rate, and a sound status is still stored.
TEST(HandlerRegression, CatalogDropsAnExperimentStatusWithANonFiniteRate) {
  auto transport = MakeLcmTransport("memq://");
  CatalogConfig config;
  config.db_path = ":memory:";
  config.keys = Keys();
  CatalogService catalog(*transport, config);
  experiment_status_t status{};
  status.source = "excite";
  status.rig_id = "sim1";
  status.experiment_id = 9;
  status.state = experiment_status_t::STATE_RUNNING;
  status.signal_spec = "prbs:bits=10";
  status.sample_rate_hz = 100;
  status.samples_total = 800;
  transport->PublishMessage(Channel("sim1", ChannelKind::kExperimentStatus), status);
  catalog.Poll(0);
  for (double bad : {std::nan(""), -5.0, HUGE_VAL}) {
    status.sample_rate_hz = bad;
    status.samples_total = 801;  // a change, so that it is not skipped as a repeat
    transport->PublishMessage(Channel("sim1", ChannelKind::kExperimentStatus), status);
    catalog.Poll(0);
  }
  EXPECT_EQ(transport->counters().handler_errors, 0);
  const auto recorded = catalog.catalog().Experiments("sim1");
  ASSERT_EQ(recorded.size(), 1u);
  EXPECT_EQ(recorded[0].experiment_id, 9);
  EXPECT_EQ(recorded[0].sample_rate_hz, 100);
  EXPECT_EQ(recorded[0].samples_planned, 800);
}

// The same rig id in an identify request made the worker's Tick() throw when it claimed the job:
// outside any handler, so the exception stopped the worker process (RunServiceMain exits 1).
TEST(HandlerRegression, WorkerIgnoresARequestForAnUnusableRig) {
  auto transport = MakeLcmTransport("memq://");
  WorkerConfig config;
  config.worker_id = "worker-1";
  config.keys = Keys();
  WorkerService worker(*transport, config);
  EnvelopeSigner catalog(kServiceRole, Key(3), "catalog-1");
  identify_request_t request{};
  request.request_id = 12;
  request.rig_id = "si`1";
  request.experiment_id = 7;
  request.method = "arx";
  request.options_json = "{}";
  catalog.Publish(*transport, Channel("sim1", ChannelKind::kIdentifyRequest), request);
  for (int i = 0; i < 5; ++i) EXPECT_NO_THROW(worker.Poll(1));
  EXPECT_EQ(transport->counters().handler_errors, 0);
  EXPECT_FALSE(worker.busy());
}

// crash-be3fbecd: a signed experiment request whose SPEC is not UTF-8 is refused (unknown kind),
// and the refusal, quoting the SPEC, goes into excite's status details; nlohmann's dump() threw
// type_error 316 on it at the next status report, in Tick(): excite stopped. Now the bytes are
// replaced in the status text and excite keeps running.
TEST(HandlerRegression, ExciteSurvivesARequestThatIsNotUtf8) {
  auto transport = MakeLcmTransport("memq://");
  ExciteConfig config;
  config.rig_id = "sim1";
  config.key = Key(1);
  config.keys = Keys();
  ExciteService excite(*transport, config);
  EnvelopeSigner operator_cli(kOperatorRole, Key(2), "cli:test");
  experiment_request_t request{};
  request.request_id = 21;
  request.rig_id = "sim1";
  request.experiment_id = 3;
  request.action = experiment_request_t::ACTION_START;
  request.signal_spec = "pr\xff\xfe" "bs:bits=10";
  request.sample_rate_hz = 100;
  request.duration_s = 2;
  request.speed = 1;
  operator_cli.Publish(*transport, Channel("sim1", ChannelKind::kExperimentRequest), request);
  std::string status;
  transport->Subscribe("IDRIG/STATUS/.*", [&](const std::string&, const uint8_t* d, size_t n) {
    status.assign(reinterpret_cast<const char*>(d), n);
  });
  // The service status is due within its period (about a second).
  const int64_t end = NowMicros() + 2500000;
  while (status.find("refus") == std::string::npos && NowMicros() < end)
    ASSERT_NO_THROW(excite.Poll(20));
  EXPECT_FALSE(excite.busy());
  EXPECT_EQ(transport->counters().handler_errors, 0);
  EXPECT_NE(status.find("unknown signal kind"), std::string::npos);
}


// --- fuzz_worker_logger: the worker's and the logger's handlers ---

measurement_block_t Block(const std::string& rig, int64_t experiment, int64_t seq, int n,
                          double u_scale) {
  measurement_block_t b{};
  b.rig_id = rig;
  b.experiment_id = experiment;
  b.seq = seq;
  b.first_sample = seq * n;
  b.sample_time_s = 0.01;
  b.n_samples = n;
  b.n_inputs = b.n_outputs = 1;
  for (int i = 0; i < n; ++i) {
    b.u.push_back({((seq * n + i) % 3 ? 1.0 : -1.0) * u_scale});
    b.y.push_back({0.1 * i});
  }
  return b;
}

experiment_status_t RigEnd(const std::string& rig, int64_t experiment, int64_t blocks,
                           double rate = 100) {
  experiment_status_t s{};
  s.source = "rig";
  s.rig_id = rig;
  s.experiment_id = experiment;
  s.state = experiment_status_t::STATE_DONE;
  s.sample_rate_hz = rate;
  s.blocks_total = blocks;
  s.samples_total = blocks * 40;
  s.samples_done = s.samples_total;
  return s;
}

// crash-2db499b3: a granted job on blocks with u ~ 2e295. ARX's least-squares sums overflowed,
// and Eigen's matrix logarithm read past its buffer on the NaN model (ASan: heap-buffer-overflow
// in the worker). Now the job fails, and the result says why.
TEST(HandlerRegression, WorkerFailsAJobOnARecordBeyondTheMagnitudeLimit) {
  auto transport = MakeLcmTransport("memq://");
  WorkerConfig config;
  config.worker_id = "worker-1";
  config.keys = Keys();
  config.compute_inline = true;
  WorkerService worker(*transport, config);
  EnvelopeSigner catalog(kServiceRole, Key(3), "catalog-1");
  EnvelopeVerifier results(Keys(), "", 300, "test");
  std::vector<model_result_t> got;
  transport->Subscribe(Channel("sim1", ChannelKind::kResult),
                       [&](const std::string& c, const uint8_t* d, size_t n) {
                         model_result_t r;
                         if (results.Open(c, d, n, {kServiceRole}, &r, nullptr, nullptr))
                           got.push_back(r);
                       });
  for (int seq = 0; seq < 4; ++seq)
    transport->PublishMessage(Channel("sim1", ChannelKind::kMeasurement), Block("sim1", 7, seq, 40, 2e295));
  transport->PublishMessage(Channel("sim1", ChannelKind::kExperimentStatus), RigEnd("sim1", 7, 4));
  identify_request_t request{};
  request.request_id = 11;
  request.rig_id = "sim1";
  request.experiment_id = 7;
  request.method = "arx";
  request.options_json = R"({"order":2})";
  catalog.Publish(*transport, Channel("sim1", ChannelKind::kIdentifyRequest), request);
  worker.Poll(0);  // hears the offer and claims it
  identify_claim_t grant{};
  grant.request_id = 11;
  grant.rig_id = "sim1";
  grant.kind = identify_claim_t::KIND_GRANT;
  grant.worker_id = "worker-1";
  grant.attempt = 1;
  catalog.Publish(*transport, Channel("sim1", ChannelKind::kClaim), grant);
  worker.Poll(0);  // the grant: the record is complete, the method runs here
  worker.Poll(0);  // publishes the result
  EXPECT_EQ(transport->counters().handler_errors, 0);
  ASSERT_FALSE(got.empty());
  EXPECT_FALSE(got.back().ok);
  EXPECT_NE(got.back().message.find("|u| = 2e+295"), std::string::npos) << got.back().message;
  EXPECT_NE(got.back().message.find("rescale the record"), std::string::npos) << got.back().message;
}

struct InlineLogger {
  std::unique_ptr<Transport> transport = MakeLcmTransport("memq://");
  std::unique_ptr<LoggerService> logger;
  std::vector<replay_request_t> recoveries;
  std::vector<replay_done_t> dones;
  InlineLogger() {
    LoggerConfig config;
    config.db_path = ":memory:";
    config.writer_thread = false;
    config.recover_period_s = 0;
    logger = std::make_unique<LoggerService>(*transport, config);
    transport->Subscribe(Channel("sim1", ChannelKind::kRigReplayRequest),
                         [&](const std::string&, const uint8_t* d, size_t n) {
                           replay_request_t r;
                           if (Decode(d, n, &r, nullptr)) recoveries.push_back(r);
                         });
    transport->Subscribe(Channel("sim1", ChannelKind::kReplayDone),
                         [&](const std::string&, const uint8_t* d, size_t n) {
                           replay_done_t r;
                           if (Decode(d, n, &r, nullptr)) dones.push_back(r);
                         });
  }
  template <class T>
  void Send(ChannelKind kind, const T& message) {
    transport->PublishMessage(Channel("sim1", kind), message);
  }
  void Poll() {
    logger->Poll(0);
    transport->Handle(0);
  }
};

replay_request_t ReplayOf(const std::string& rig, int64_t experiment, int64_t id) {
  replay_request_t r{};
  r.replay_id = id;
  r.requester = "worker-1";
  r.rig_id = rig;
  r.experiment_id = experiment;
  return r;
}

// crash-b2725de8: an (unsigned) rig status on sim1's channel naming rig "sim\xff". The logger
// stored the experiment under that rig, and its loss recovery threw on Channel("sim\xff") every
// period (handler_errors; the experiments after it in the list were never recovered). A replay
// request naming such a rig threw the same way and lost the batch's other replays. Now both are
// ignored (counted as wrong_rig), and the real experiment's recovery and replays still run.
TEST(HandlerRegression, LoggerIgnoresMessagesNamingAnUnusableRig) {
  InlineLogger bus;
  bus.Send(ChannelKind::kExperimentStatus, RigEnd("sim\xff", 7, 2));
  bus.Send(ChannelKind::kMeasurement, Block("sim1", 8, 0, 40, 1.0));
  bus.Send(ChannelKind::kExperimentStatus, RigEnd("sim1", 8, 2));  // block 1 lost
  bus.Send(ChannelKind::kReplayRequest, ReplayOf("si`1", 8, 1));
  bus.Send(ChannelKind::kReplayRequest, ReplayOf("sim1", 8, 2));
  bus.transport->Handle(0);
  bus.Poll();
  EXPECT_EQ(bus.transport->counters().handler_errors, 0);
  EXPECT_EQ(bus.logger->Details()["wrong_rig"], 2);
  ASSERT_EQ(bus.recoveries.size(), 1u);
  EXPECT_EQ(bus.recoveries[0].experiment_id, 8);
  EXPECT_EQ(bus.recoveries[0].have_seqs, std::vector<int64_t>{0});
  ASSERT_EQ(bus.dones.size(), 1u);
  EXPECT_EQ(bus.dones[0].replay_id, 2);
  EXPECT_EQ(bus.dones[0].missing_seqs, std::vector<int64_t>{1});
}

// crash-bfd01bbe: a rig status with sample_rate_hz NaN. SQLite bound NaN as NULL, the insert
// failed, and with it the rest of the writer's batch: the blocks received after it were lost.
// Now the status is dropped with a log line and the blocks are stored.
TEST(HandlerRegression, LoggerDropsAStatusWithANonFiniteRateAndKeepsTheBatch) {
  InlineLogger bus;
  bus.Send(ChannelKind::kMeasurement, Block("sim1", 8, 0, 40, 1.0));
  bus.Send(ChannelKind::kExperimentStatus, RigEnd("sim1", 8, 2, std::nan("")));
  bus.Send(ChannelKind::kMeasurement, Block("sim1", 8, 1, 40, 1.0));
  bus.transport->Handle(0);
  bus.Poll();
  EXPECT_EQ(bus.transport->counters().handler_errors, 0);
  EXPECT_EQ(bus.logger->stored_blocks(), 2);
  // The status was dropped (no experiment row: blocks alone do not make one); the next good one
  // is stored.
  EXPECT_TRUE(bus.logger->Details()["experiments"].empty());
  bus.Send(ChannelKind::kExperimentStatus, RigEnd("sim1", 8, 2));
  bus.transport->Handle(0);
  bus.Poll();
  const auto experiments = bus.logger->Details()["experiments"];
  ASSERT_EQ(experiments.size(), 1u);
  EXPECT_EQ(experiments[0]["blocks"], 2);
  EXPECT_EQ(experiments[0]["complete"], true);
}

// oom-f7675171: a rig status claiming 2^62 blocks. The logger's summary listed every missing
// seq (out of memory, or minutes in the writer thread). Now they are counted, and 50 listed.
TEST(HandlerRegression, LoggerCountsAHugeBlockTotalWithoutListingIt) {
  InlineLogger bus;
  bus.Send(ChannelKind::kMeasurement, Block("sim1", 8, 0, 40, 1.0));
  bus.Send(ChannelKind::kExperimentStatus, RigEnd("sim1", 8, int64_t{1} << 62));
  bus.Send(ChannelKind::kReplayRequest, ReplayOf("sim1", 8, 3));
  bus.transport->Handle(0);
  bus.Poll();
  EXPECT_EQ(bus.transport->counters().handler_errors, 0);
  const auto experiments = bus.logger->Details()["experiments"];
  ASSERT_EQ(experiments.size(), 1u);
  EXPECT_EQ(experiments[0]["missing_count"].get<int64_t>(), (int64_t{1} << 62) - 1);
  EXPECT_EQ(experiments[0]["missing"].size(), 50u);
  ASSERT_EQ(bus.dones.size(), 1u);
  EXPECT_EQ(bus.dones[0].n_missing, 4000);
  EXPECT_FALSE(bus.dones[0].complete);
}

}  // namespace
}  // namespace idrig
