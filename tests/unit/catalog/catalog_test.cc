// The SQLite catalogue on a temporary file: migrations, idempotent model storage, job leases,
// history of a metric, lineage; and the logger's experiment store with gap detection.
#include "core/catalog/catalog.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>

#include "core/catalog/experiment_store.h"

namespace idrig {
namespace {

std::string TempPath(const std::string& name) {
  const std::string path = ::testing::TempDir() + "/" + name + "_" + std::to_string(getpid());
  for (const char* suffix : {"", "-wal", "-shm"}) std::remove((path + suffix).c_str());
  return path;
}

ModelRecord Model(int64_t request_id, double pole) {
  ModelRecord m;
  m.request_id = request_id;
  m.rig_id = "rig-a";
  m.experiment_id = 7;
  m.method = "arx";
  m.options_json = "{}";
  m.data_hash = "abc";
  m.n_samples = 100;
  m.sample_time_s = 0.1;
  m.software_version = "test";
  m.worker_id = "w1";
  m.created_utime = 1000 + request_id;
  m.fit_percent = 95.0;
  m.status = "converged";
  // W(s) = 1/(s - pole): one real pole, DC gain -1/pole.
  nlohmann::json report = {{"fit_percent", 95.0},
                           {"model",
                            {{"format", "idrig.model/1"},
                             {"kind", "tf"},
                             {"domain", "continuous"},
                             {"Ts", 0.0},
                             {"num", {1.0}},
                             {"den", {1.0, -pole}}}}};
  m.model_json = report["model"].dump();
  m.report_json = report.dump();
  return m;
}

TEST(Catalog, MigratesOnceAndKeepsData) {
  const std::string path = TempPath("catalog_migrate");
  {
    Catalog c(path);
    EXPECT_EQ(c.SchemaVersion(), static_cast<int>(Catalog::Migrations().size()));
    c.StoreModel(Model(1, -2.0), {});
  }
  Catalog again(path);
  EXPECT_EQ(again.SchemaVersion(), static_cast<int>(Catalog::Migrations().size()));
  EXPECT_EQ(again.CountModels(), 1);
  EXPECT_EQ(again.IntegrityCheck(), "ok");
}

TEST(Catalog, StoresAModelOncePerRequest) {
  Catalog c(TempPath("catalog_idempotent"));
  JobRecord job;
  job.request_id = 11;
  job.rig_id = "rig-a";
  job.experiment_id = 7;
  job.method = "arx";
  job.created_utime = 5;
  EXPECT_TRUE(c.AddJob(job));
  EXPECT_FALSE(c.AddJob(job));
  const ModelRecord m = Model(11, -2.0);
  const auto first = c.StoreModel(m, ModelMetrics(nlohmann::json::parse(m.report_json)));
  const auto second = c.StoreModel(m, {});
  EXPECT_TRUE(first.second);
  EXPECT_FALSE(second.second);
  EXPECT_EQ(first.first, second.first);
  EXPECT_EQ(c.CountModels(), 1);
  EXPECT_EQ(c.Job(11)->state, "done");
  // Metrics from the model: pole -2 -> wn 2 rad/s, zeta 1, DC gain 1/2.
  double wn = 0, gain = 0;
  for (const auto& x : c.Metrics(first.first)) {
    if (x.name == "wn_1") wn = x.value;
    if (x.name == "dc_gain") gain = x.value;
  }
  EXPECT_NEAR(wn, 2.0, 1e-12);
  EXPECT_NEAR(gain, 0.5, 1e-12);
}

TEST(Catalog, LeasesGoToOneWorkerUntilTheyExpire) {
  Catalog c(TempPath("catalog_leases"));
  JobRecord job;
  job.request_id = 3;
  job.rig_id = "rig-a";
  job.method = "arx";
  job.created_utime = 1;
  c.AddJob(job);
  JobRecord state;
  EXPECT_EQ(c.Claim(3, "w1", 1000, 500, &state), ClaimOutcome::kGranted);
  EXPECT_EQ(state.attempts, 1);
  EXPECT_EQ(c.Claim(3, "w2", 1200, 500, &state), ClaimOutcome::kDenied);
  EXPECT_EQ(state.worker_id, "w1");
  EXPECT_EQ(c.Claim(3, "w1", 1400, 500, &state), ClaimOutcome::kGranted);  // renewal
  EXPECT_EQ(state.attempts, 1);
  EXPECT_TRUE(c.JobsToOffer(1500).empty());
  // w1 stops renewing: after 1900 the job is offered again and w2 gets it.
  EXPECT_EQ(c.JobsToOffer(2000).size(), 1u);
  EXPECT_EQ(c.Claim(3, "w2", 2000, 500, &state), ClaimOutcome::kGranted);
  EXPECT_EQ(state.attempts, 2);
  EXPECT_EQ(c.Claim(99, "w2", 2000, 500, &state), ClaimOutcome::kUnknown);
  ModelRecord m = Model(3, -1.0);
  m.worker_id = "w2";
  c.StoreModel(m, {});
  EXPECT_EQ(c.Claim(3, "w1", 2100, 500, &state), ClaimOutcome::kDone);
}

TEST(Catalog, HistoryOfAMetricWithLineage) {
  Catalog c(TempPath("catalog_history"));
  ExperimentRecord e;
  e.rig_id = "rig-a";
  e.experiment_id = 7;
  e.signal_spec = "step:amp=1";
  e.sample_rate_hz = 10;
  e.state = "done";
  e.start_utime = 1;
  c.UpsertExperiment(e);
  for (int k = 1; k <= 3; ++k) {
    const ModelRecord m = Model(k, -1.0 * k);
    c.StoreModel(m, ModelMetrics(nlohmann::json::parse(m.report_json)));
  }
  const auto history = c.History("rig-a", "wn_1");
  ASSERT_EQ(history.size(), 3u);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(history[k].second, k + 1.0, 1e-12);
  EXPECT_EQ(history[0].first.signal_spec, "step:amp=1");
  EXPECT_EQ(history[0].first.data_hash, "abc");
  EXPECT_TRUE(c.History("rig-b", "wn_1").empty());
}

TEST(Catalog, DiagnosisReportsAreIdempotent) {
  Catalog c(TempPath("catalog_diag"));
  const auto a = c.StoreDiagnosis(5, "rig-a", 0, 7, "{}", 10);
  const auto b = c.StoreDiagnosis(5, "rig-a", 0, 7, "{}", 11);
  EXPECT_TRUE(a.second);
  EXPECT_FALSE(b.second);
  EXPECT_EQ(a.first, b.first);
  // Read back with the lineage; the second store did not replace the first.
  c.StoreDiagnosis(6, "rig-b", 0, 8, "{\"x\":2}", 12);
  const auto stored = c.Diagnosis(a.first);
  ASSERT_TRUE(stored.has_value());
  EXPECT_EQ(stored->request_id, 5);
  EXPECT_EQ(stored->experiment_id, 7);
  EXPECT_EQ(stored->created_utime, 10);
  EXPECT_EQ(stored->report_json, "{}");
  EXPECT_EQ(c.Diagnoses().size(), 2u);
  ASSERT_EQ(c.Diagnoses("rig-b").size(), 1u);
  EXPECT_EQ(c.Diagnoses("rig-b")[0].report_json, "{\"x\":2}");
  EXPECT_FALSE(c.Diagnosis(999).has_value());
}

TEST(Catalog, NotACatalogueIsAnError) {
  const std::string path = TempPath("catalog_empty");
  {
    SqliteDatabase db(path);
    db.Exec("CREATE TABLE x(a)");
  }
  EXPECT_THROW(Catalog(path, true), std::runtime_error);
  EXPECT_THROW(Catalog("/nonexistent/dir/catalog.db"), std::runtime_error);
}

TEST(ExperimentStore, FindsGapsBySequenceNumber) {
  const std::string store_path = TempPath("experiments");
  ExperimentStore store(store_path);
  store.Begin();
  for (int64_t seq : {0, 1, 3, 4, 4, 7}) {
    StoredBlock b;
    b.seq = seq;
    b.first_sample = 10 * seq;
    b.n_samples = 10;
    b.data = {1, 2, 3};
    store.AddBlock("rig-a", 1, b);
  }
  store.Commit();
  EXPECT_EQ(store.BlockSeqs("rig-a", 1).size(), 5u);  // duplicate 4 stored once
  EXPECT_EQ(store.MissingBlocks("rig-a", 1), (std::vector<int64_t>{2, 5, 6}));
  StoredExperiment e;
  e.rig_id = "rig-a";
  e.experiment_id = 1;
  e.ended = true;
  e.blocks_total = 10;
  store.UpdateExperiment(e);
  EXPECT_EQ(store.MissingBlocks("rig-a", 1), (std::vector<int64_t>{2, 5, 6, 8, 9}));
  EXPECT_EQ(store.MissingCount("rig-a", 1), 5);
  EXPECT_EQ(store.MissingBlocks("rig-a", 1, 2), (std::vector<int64_t>{2, 5}));
  EXPECT_EQ(store.Blocks("rig-a", 1, {0, 1}).size(), 3u);

  // Read-only (the dashboard): the same answers, and writes are refused by SQLite.
  ExperimentStore reader(store_path, true);
  EXPECT_EQ(reader.MissingBlocks("rig-a", 1), (std::vector<int64_t>{2, 5, 6, 8, 9}));
  StoredBlock b;
  b.seq = 2;
  b.data = {1};
  EXPECT_THROW(reader.AddBlock("rig-a", 1, b), std::runtime_error);
  EXPECT_THROW(ExperimentStore(TempPath("no_such_store"), true), std::runtime_error);
}

// An (unsigned) final status claiming 2^62 blocks: counted, and only the first few listed (the
// logger listed them all: out of memory, tests/fuzz/fuzz_worker_logger oom-f7675171).
TEST(ExperimentStore, AHugeBlockTotalIsCountedNotListed) {
  ExperimentStore store(":memory:");
  for (int64_t seq : {0, 1, 3}) {
    StoredBlock b;
    b.seq = seq;
    b.n_samples = 10;
    b.data = {1};
    store.AddBlock("rig-a", 1, b);
  }
  StoredExperiment e;
  e.rig_id = "rig-a";
  e.experiment_id = 1;
  e.ended = true;
  e.blocks_total = int64_t{1} << 62;
  store.UpdateExperiment(e);
  EXPECT_EQ(store.MissingCount("rig-a", 1), (int64_t{1} << 62) - 3);
  EXPECT_EQ(store.MissingBlocks("rig-a", 1, 4), (std::vector<int64_t>{2, 4, 5, 6}));
  EXPECT_EQ(store.MissingBlocks("rig-a", 1).size(), 4000u);
  // A block seq far ahead while the experiment runs: the same.
  StoredBlock far;
  far.seq = int64_t{1} << 61;
  far.data = {1};
  store.AddBlock("rig-a", 2, far);
  EXPECT_EQ(store.MissingCount("rig-a", 2), int64_t{1} << 61);
  EXPECT_EQ(store.MissingBlocks("rig-a", 2, 3), (std::vector<int64_t>{0, 1, 2}));
}

}  // namespace
}  // namespace idrig
