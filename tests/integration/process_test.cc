// The services as separate processes over udpm (ttl=0) inside a private network namespace
// (the test enters one itself: unshare(CLONE_NEWNET), lo with multicast; needs root, else the
// tests are skipped). kill -9 of a worker mid-job, and of the catalogue during a burst of writes.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sched.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <idrig/experiment_request_t.hpp>
#include <idrig/experiment_status_t.hpp>
#include <idrig/identify_request_t.hpp>
#include <idrig/model_result_t.hpp>
#include <idrig/result_ack_t.hpp>
#include <idrig/service_status_t.hpp>
#include <set>
#include <thread>

#include "core/catalog/catalog.h"
#include "core/transport/channels.h"
#include "core/transport/signing.h"
#include "core/transport/transport.h"
#include "tests/integration/process_harness.h"

namespace idrig {
namespace {

using namespace harness;
const auto* const kEnvironment = ::testing::AddGlobalTestEnvironment(new NetnsEnvironment);

const std::string kUrl = PrivateUdpmUrl(7711, 0);

void Start(Child* child, const std::string& program, std::vector<std::string> args,
           const std::string& log) {
  harness::Start(child, program, std::move(args), log, kUrl);
}

model_result_t Result(int64_t request_id) {
  model_result_t r{};
  r.utime = NowMicros();
  r.request_id = request_id;
  r.rig_id = "rig-k";
  r.experiment_id = 1;
  r.worker_id = "burst";
  r.attempt = 1;
  r.ok = true;
  r.method = "arx";
  r.options_json = "{}";
  r.data_hash = std::string(64, 'a');
  r.n_samples = 100;
  r.sample_time_s = 0.1;
  r.software_version = IDRIG_VERSION;
  const double pole = -1.0 - 0.001 * static_cast<double>(request_id);
  r.report_json = nlohmann::json({{"fit_percent", 90.0},
                                  {"model",
                                   {{"format", "idrig.model/1"},
                                    {"kind", "tf"},
                                    {"domain", "continuous"},
                                    {"Ts", 0.0},
                                    {"num", {1.0}},
                                    {"den", {1.0, -pole}}}}})
                      .dump();
  return r;
}

TEST(Processes, CatalogKilledDuringABurstKeepsEveryAcknowledgedResultOnce) {
  if (!NetnsReady()) GTEST_SKIP() << "needs root for a private network namespace";
  const std::string dir = Dir("catalog_kill");
  const std::string db = dir + "/catalog.db";
  const Keys keys(dir);
  nlohmann::json config = keys.Roles();
  config["db_path"] = db;
  config["lease_s"] = 600.0;
  WriteFile(dir + "/catalog.json", config.dump());
  const int64_t kResults = 300;
  {
    // The jobs, leased to the worker "burst" (the catalogue stores results only from the
    // worker holding a job's lease).
    Catalog setup(db);
    for (int64_t id = 1; id <= kResults; ++id) {
      JobRecord job;
      job.request_id = id;
      job.rig_id = "rig-k";
      job.experiment_id = 1;
      job.method = "arx";
      job.options_json = "{}";
      job.created_utime = NowMicros();
      setup.AddJob(job);
      setup.Claim(id, "burst", NowMicros(), 600000000, &job);
    }
  }
  EnvelopeSigner worker(kServiceRole, keys.Service(), "burst");
  KeyRing ring;
  ring.keys[kServiceRole] = keys.Service();
  EnvelopeVerifier verifier(ring, "", 300, "test");
  auto t = MakeLcmTransport(kUrl);
  std::set<int64_t> acked;
  bool catalog_up = false;
  t->Subscribe(
      "IDRIG/rig-k/ACK",
      [&](const std::string& c, const uint8_t* d, size_t n) {
        result_ack_t a;
        if (verifier.Open(c, d, n, {kServiceRole}, &a, nullptr, nullptr)) acked.insert(a.request_id);
      },
      10000);
  t->Subscribe("IDRIG/STATUS/catalog",
               [&](const std::string&, const uint8_t*, size_t) { catalog_up = true; });
  Child catalog;
  Start(&catalog, "idrig-catalog", {"--config", dir + "/catalog.json"}, dir + "/catalog.log");
  ASSERT_TRUE(Until(
      *t, [&] { return catalog_up; }, 10.0))
      << "idrig-catalog did not start";

  std::set<int64_t> acked_before_kill;
  bool killed = false, restarted = false;
  auto killed_at = std::chrono::steady_clock::now();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (static_cast<int64_t>(acked.size()) < kResults &&
         std::chrono::steady_clock::now() < deadline) {
    // A burst: every unacknowledged result, as the workers' retries would send them.
    int sent = 0;
    for (int64_t id = 1; id <= kResults; ++id) {
      if (acked.count(id)) continue;
      worker.Publish(*t, "IDRIG/rig-k/RESULT", Result(id));
      if (++sent % 10 == 0) t->Handle(0);
    }
    if (!killed) {
      // The burst is sent faster than the catalogue writes it: kill it once 60 results are
      // acknowledged, i.e. in the middle of the writes (whether 60 arrive during the burst
      // or just after it depends on the machine's speed, not on the catalogue).
      Until(
          *t, [&] { return acked.size() >= 60; }, 10.0);
      catalog.Kill(SIGKILL);
      killed = true;
      killed_at = std::chrono::steady_clock::now();
      t->Handle(0);
      acked_before_kill = acked;
      ASSERT_GE(acked_before_kill.size(), 60u) << "the catalogue acknowledged too few results before the kill";
      ASSERT_LT(acked_before_kill.size(), static_cast<size_t>(kResults)) << "the kill came after the last write";
      // Before any restart: every acknowledged result is already in the file.
      Catalog after_kill(db);
      for (int64_t a : acked_before_kill)
        ASSERT_TRUE(after_kill.ModelForRequest(a).has_value()) << "acked result " << a << " lost";
      EXPECT_EQ(after_kill.IntegrityCheck(), "ok");
    }
    Until(
        *t, [] { return false; }, 0.2);
    if (killed && !restarted &&
        std::chrono::steady_clock::now() - killed_at > std::chrono::milliseconds(300)) {
      Start(&catalog, "idrig-catalog", {"--config", dir + "/catalog.json"}, dir + "/catalog.log");
      restarted = true;
    }
  }
  ASSERT_TRUE(killed);
  ASSERT_EQ(static_cast<int64_t>(acked.size()), kResults) << "not every result was acknowledged";
  catalog.Kill(SIGTERM);
  Catalog c(db);
  EXPECT_EQ(c.CountModels(), kResults);  // each request once (request_id is UNIQUE as well)
  for (int64_t id = 1; id <= kResults; ++id) ASSERT_TRUE(c.ModelForRequest(id).has_value()) << id;
  EXPECT_EQ(c.IntegrityCheck(), "ok");
  std::printf("acknowledged before kill -9: %zu of %lld\n", acked_before_kill.size(),
              static_cast<long long>(kResults));
}

TEST(Processes, WorkerKilledMidJobAnotherWorkerCompletesIt) {
  if (!NetnsReady()) GTEST_SKIP() << "needs root for a private network namespace";
  const std::string dir = Dir("worker_kill");
  const Keys keys(dir);
  const std::string key = keys.command;
  nlohmann::json catalog_config = keys.Roles();
  catalog_config.update({{"db_path", dir + "/catalog.db"}, {"lease_s", 1.0}, {"offer_period_s", 0.3}});
  WriteFile(dir + "/catalog.json", catalog_config.dump());
  WriteFile(dir + "/rig.json", nlohmann::json({{"rig_id", "rig-k"},
                                               {"noise_std", 0.001},
                                               {"key_file", key},
                                               {"model",
                                                {{"format", "idrig.model/1"},
                                                 {"kind", "tf"},
                                                 {"domain", "continuous"},
                                                 {"Ts", 0.0},
                                                 {"num", {1.0}},
                                                 {"den", {1.0, 1.2, 1.0}}}}})
                                   .dump());
  WriteFile(dir + "/excite.json",
            nlohmann::json({{"rig_id", "rig-k"}, {"key_file", key}, {"operator_key_file", keys.operator_key}})
                .dump());
  nlohmann::json worker_config = keys.Roles();
  worker_config["renew_s"] = 0.25;
  WriteFile(dir + "/worker.json", worker_config.dump());
  EnvelopeSigner operator_signer(kOperatorRole, keys.Operator(), "cli:test");
  KeyRing ring;
  ring.keys[kServiceRole] = keys.Service();
  EnvelopeVerifier verifier(ring, "", 300, "test");
  Child catalog, logger, rig, excite, worker1, worker2;
  Start(&catalog, "idrig-catalog", {"--config", dir + "/catalog.json"}, dir + "/catalog.log");
  Start(&logger, "idrig-logger", {"--db", dir + "/experiments.db"}, dir + "/logger.log");
  Start(&rig, "idrig-rig-sim", {"--config", dir + "/rig.json"}, dir + "/rig.log");
  Start(&excite, "idrig-excite", {"--config", dir + "/excite.json"}, dir + "/excite.log");
  Start(&worker1, "idrig-worker",
        {"--config", dir + "/worker.json", "--id", "w1", "--debug-delay", "4"}, dir + "/w1.log");

  auto t = MakeLcmTransport(kUrl);
  std::set<std::string> services;
  experiment_status_t rig_status{};
  std::optional<result_ack_t> ack;
  t->Subscribe("IDRIG/STATUS/.*", [&](const std::string&, const uint8_t* d, size_t n) {
    service_status_t s;
    if (Decode(d, n, &s, nullptr)) services.insert(s.service);
  });
  t->Subscribe("IDRIG/rig-k/EXP_STATUS", [&](const std::string&, const uint8_t* d, size_t n) {
    experiment_status_t s;
    if (Decode(d, n, &s, nullptr) && s.source == "rig" && s.experiment_id == 5) rig_status = s;
  });
  t->Subscribe("IDRIG/rig-k/ACK", [&](const std::string& c, const uint8_t* d, size_t n) {
    result_ack_t a;
    if (verifier.Open(c, d, n, {kServiceRole}, &a, nullptr, nullptr) && a.request_id == 4242) ack = a;
  });
  ASSERT_TRUE(Until(
      *t, [&] { return services.size() == 5; }, 10.0))
      << "services did not start";

  experiment_request_t request{};
  request.utime = NowMicros();
  request.request_id = 1;
  request.rig_id = "rig-k";
  request.experiment_id = 5;
  request.action = experiment_request_t::ACTION_START;
  request.signal_spec = "prbs:bits=7,amp=1";
  request.sample_rate_hz = 10;
  request.duration_s = 25.4;
  request.speed = 50;
  operator_signer.Publish(*t, "IDRIG/rig-k/EXP_REQ", request);
  ASSERT_TRUE(Until(
      *t, [&] { return rig_status.state == experiment_status_t::STATE_DONE; }, 10.0));

  identify_request_t job{};
  job.utime = NowMicros();
  job.request_id = 4242;
  job.rig_id = "rig-k";
  job.experiment_id = 5;
  job.method = "arx-oe";
  job.options_json = "{\"order\":2}";
  operator_signer.Publish(*t, "IDRIG/rig-k/IDENT_REQ", job);
  // Wait until w1 holds the lease (it then computes, plus a 4 s delay), then kill it.
  Catalog reader(dir + "/catalog.db");
  ASSERT_TRUE(Until(
      *t,
      [&] {
        auto j = reader.Job(4242);
        return j && j->state == "leased" && j->worker_id == "w1";
      },
      10.0))
      << "w1 never held the job";
  Until(
      *t, [] { return false; }, 0.5);
  ASSERT_FALSE(ack.has_value()) << "w1 finished before it could be killed";
  worker1.Kill(SIGKILL);
  Start(&worker2, "idrig-worker", {"--config", dir + "/worker.json", "--id", "w2"},
        dir + "/w2.log");
  ASSERT_TRUE(Until(
      *t, [&] { return ack.has_value(); }, 15.0))
      << "no worker completed the job";
  EXPECT_GT(ack->model_id, 0);
  EXPECT_EQ(ack->worker_id, "w2");
  Until(
      *t, [] { return false; }, 0.5);
  EXPECT_EQ(reader.CountModels(), 1);
  const auto model = reader.ModelForRequest(4242);
  ASSERT_TRUE(model.has_value());
  EXPECT_EQ(model->worker_id, "w2");
  EXPECT_EQ(model->n_samples, 254);
  EXPECT_EQ(reader.Job(4242)->attempts, 2);  // w1's lease, then w2's
  EXPECT_EQ(reader.Job(4242)->state, "done");
}

}  // namespace
}  // namespace idrig
