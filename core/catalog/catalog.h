#pragma once
// The SQLite catalogue: rigs, experiments, identification jobs (leases), models with their
// lineage (experiment, data hash, method, options, software version, time), per-model metrics
// (fit, poles, natural frequencies, damping, DC gain) and diagnosis reports.
// WAL journal, synchronous=FULL (a result is durable before it is acknowledged), schema
// migrations by PRAGMA user_version, prepared statements only. Schema: docs/services.md.
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/catalog/sqlite.h"

namespace idrig {

struct ExperimentRecord {
  std::string rig_id;
  int64_t experiment_id = 0;
  std::string signal_spec;
  double sample_rate_hz = 0.0;
  int64_t samples_total = 0;
  int64_t blocks_total = 0;
  std::string state;  // running, done, stopped, failed, interrupted
  int64_t start_utime = 0, end_utime = 0;
  std::string message;          // the rig's final word (interrupted: the samples missing)
  int64_t samples_planned = 0;  // from the excitation service
};

struct JobRecord {
  int64_t request_id = 0;
  std::string rig_id;
  int64_t experiment_id = 0;
  std::string method, options_json = "{}", requested_by;
  std::string state = "pending";  // pending, leased, done, failed
  std::string worker_id;
  int64_t lease_expires_utime = 0;
  int attempts = 0;
  int64_t created_utime = 0, finished_utime = 0;
  std::string message;
};

struct ModelRecord {
  int64_t model_id = 0;
  int64_t request_id = 0;
  std::string rig_id;
  int64_t experiment_id = 0;
  std::string method, options_json, data_hash, software_version, worker_id;
  int64_t n_samples = 0;
  double sample_time_s = 0.0;
  int64_t created_utime = 0;
  double compute_s = 0.0;
  double fit_percent = std::nan("");
  std::string status;
  std::string model_json, report_json;
  std::string signal_spec;  // from the experiment (read side only)
};

// A stored gap-diagnosis report (idrig.gap/1 JSON) with its lineage.
struct DiagnosisRecord {
  int64_t report_id = 0, request_id = 0, model_id = 0, experiment_id = 0, created_utime = 0;
  std::string rig_id, report_json;
};

struct Metric {
  std::string name;
  double value = 0.0;
  std::string unit;
};

// Metrics of a method report: fit_percent (the method's own), record_fit_percent (the worker's
// simulation fit on the whole record, the same measure for every method), dc_gain, order, and for each pole k (continuous
// models; discrete poles are mapped by s = ln(z)/Ts) pole_k_re, pole_k_im [rad/s],
// wn_k [rad/s], zeta_k (sorted by wn). Never throws: a model it cannot read gives fewer metrics.
std::vector<Metric> ModelMetrics(const nlohmann::json& report);

enum class ClaimOutcome { kGranted, kDenied, kDone, kUnknown };

class Catalog {
 public:
  // Opens or creates the catalogue at `path` and migrates it. Throws std::runtime_error.
  explicit Catalog(const std::string& path, bool read_only = false);
  static const std::vector<std::string>& Migrations();
  int SchemaVersion() { return db_.UserVersion(); }

  void TouchRig(const std::string& rig_id, int64_t utime);
  void UpsertExperiment(const ExperimentRecord& experiment);
  std::vector<ExperimentRecord> Experiments(const std::string& rig_id = "");

  // Jobs. AddJob returns false when the request id is already known (idempotent).
  bool AddJob(const JobRecord& job);
  std::optional<JobRecord> Job(int64_t request_id);
  std::vector<JobRecord> Jobs(const std::string& state = "");
  // Grants the lease when the job is pending, its lease expired, or the worker holds it
  // (renewal). *job receives the job's state after the call.
  ClaimOutcome Claim(int64_t request_id, const std::string& worker_id, int64_t now_utime,
                     int64_t lease_us, JobRecord* job);
  // Pending jobs and jobs whose lease has expired (to offer again).
  std::vector<JobRecord> JobsToOffer(int64_t now_utime);
  // Marks a job failed (the method reported an error); idempotent.
  void FailJob(int64_t request_id, const std::string& worker_id, const std::string& message,
               int64_t utime);

  // Stores a model once per request_id, with metrics, and marks its job done, in one
  // transaction. Returns (model_id, inserted): inserted = false for a duplicate.
  std::pair<int64_t, bool> StoreModel(const ModelRecord& model, const std::vector<Metric>& metrics);
  std::vector<ModelRecord> Models(const std::string& rig_id = "", const std::string& method = "",
                                  int limit = 1000);
  std::optional<ModelRecord> Model(int64_t model_id);
  std::optional<ModelRecord> ModelForRequest(int64_t request_id);
  std::vector<Metric> Metrics(int64_t model_id);
  // (model, value of metric `name`) over time for a rig, oldest first.
  std::vector<std::pair<ModelRecord, double>> History(const std::string& rig_id,
                                                      const std::string& metric,
                                                      const std::string& method = "");
  // Stores a diagnosis report once per request_id; returns (report_id, inserted).
  std::pair<int64_t, bool> StoreDiagnosis(int64_t request_id, const std::string& rig_id,
                                          int64_t model_id, int64_t experiment_id,
                                          const std::string& report_json, int64_t utime);
  std::optional<DiagnosisRecord> Diagnosis(int64_t report_id);
  // Newest first; every rig when rig_id is empty.
  std::vector<DiagnosisRecord> Diagnoses(const std::string& rig_id = "", int limit = 1000);
  int64_t CountModels();
  // "ok" when PRAGMA integrity_check passes, else its first message.
  std::string IntegrityCheck();

 private:
  SqliteDatabase db_;
};

}  // namespace idrig
