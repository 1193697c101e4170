// Inputs found by tests/fuzz/fuzz_handlers, kept as regression tests: the services' classes over
// memq://, fed the authenticated but hostile messages the fuzzer made.
#include <gtest/gtest.h>

#include <cmath>

#include <idrig/experiment_request_t.hpp>
#include <idrig/experiment_status_t.hpp>
#include <idrig/identify_claim_t.hpp>
#include <idrig/identify_request_t.hpp>

#include "core/transport/auth.h"
#include "core/transport/channels.h"
#include "core/transport/transport.h"
#include "services/catalog/catalog_service.h"
#include "services/excite/excite_service.h"
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
  request.signal_spec = "pr\xff\xfebs:bits=10";
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

}  // namespace
}  // namespace idrig
