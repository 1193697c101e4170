#include "core/catalog/catalog.h"

#include <algorithm>
#include <complex>
#include <stdexcept>

#include "core/io/model_json.h"
#include "core/numeric/model/lti_model.h"

namespace idrig {

void Catalog::TouchRig(const std::string& rig_id, int64_t utime) {
  SqliteStatement s(
      db_,
      "INSERT INTO rigs(rig_id, first_seen_utime, last_seen_utime) VALUES(?1, ?2, ?2) "
      "ON CONFLICT(rig_id) DO UPDATE SET last_seen_utime = "
      "max(last_seen_utime, excluded.last_seen_utime)");
  s.Bind(1, rig_id).Bind(2, utime).Run();
}

void Catalog::UpsertExperiment(const ExperimentRecord& e) {
  TouchRig(e.rig_id, e.start_utime > 0 ? e.start_utime : e.end_utime);
  SqliteStatement s(
      db_,
      "INSERT INTO experiments(rig_id, experiment_id, signal_spec, sample_rate_hz, "
      "samples_total, blocks_total, state, start_utime, end_utime, message, samples_planned) "
      "VALUES(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11) "
      "ON CONFLICT(rig_id, experiment_id) DO UPDATE SET "
      "signal_spec = CASE WHEN excluded.signal_spec <> '' THEN excluded.signal_spec ELSE "
      "signal_spec END, "
      "sample_rate_hz = CASE WHEN excluded.sample_rate_hz > 0 THEN excluded.sample_rate_hz ELSE "
      "sample_rate_hz END, "
      "samples_total = max(samples_total, excluded.samples_total), "
      "blocks_total = max(blocks_total, excluded.blocks_total), "
      "state = excluded.state, "
      "start_utime = CASE WHEN start_utime = 0 THEN excluded.start_utime ELSE start_utime END, "
      "end_utime = max(end_utime, excluded.end_utime), "
      "message = CASE WHEN excluded.message <> '' THEN excluded.message ELSE message END, "
      "samples_planned = max(samples_planned, excluded.samples_planned)");
  s.Bind(1, e.rig_id).Bind(2, e.experiment_id).Bind(3, e.signal_spec).Bind(4, e.sample_rate_hz);
  s.Bind(5, e.samples_total).Bind(6, e.blocks_total).Bind(7, e.state).Bind(8, e.start_utime);
  s.Bind(9, e.end_utime).Bind(10, e.message).Bind(11, e.samples_planned).Run();
}

std::vector<ExperimentRecord> Catalog::Experiments(const std::string& rig_id) {
  SqliteStatement s(db_,
                    "SELECT rig_id, experiment_id, signal_spec, sample_rate_hz, samples_total, "
                    "blocks_total, state, start_utime, end_utime, message, samples_planned "
                    "FROM experiments "
                    "WHERE ?1 = '' OR rig_id = ?1 ORDER BY start_utime, experiment_id");
  s.Bind(1, rig_id);
  std::vector<ExperimentRecord> out;
  while (s.Step()) {
    ExperimentRecord e;
    SqliteRow(s) >> e.rig_id >> e.experiment_id >> e.signal_spec >> e.sample_rate_hz >>
        e.samples_total >> e.blocks_total >> e.state >> e.start_utime >> e.end_utime >>
        e.message >> e.samples_planned;
    out.push_back(e);
  }
  return out;
}

namespace {
const char* kJobColumns =
    "request_id, rig_id, experiment_id, method, options_json, requested_by, state, worker_id, "
    "lease_expires_utime, attempts, created_utime, finished_utime, message";
JobRecord ReadJob(const SqliteStatement& s) {
  JobRecord j;
  SqliteRow(s) >> j.request_id >> j.rig_id >> j.experiment_id >> j.method >> j.options_json >>
      j.requested_by >> j.state >> j.worker_id >> j.lease_expires_utime >> j.attempts >>
      j.created_utime >> j.finished_utime >> j.message;
  return j;
}
}  // namespace

bool Catalog::AddJob(const JobRecord& j) {
  SqliteStatement s(db_,
                    "INSERT OR IGNORE INTO jobs(request_id, rig_id, experiment_id, method, "
                    "options_json, requested_by, state, created_utime) "
                    "VALUES(?1, ?2, ?3, ?4, ?5, ?6, 'pending', ?7)");
  s.Bind(1, j.request_id).Bind(2, j.rig_id).Bind(3, j.experiment_id).Bind(4, j.method);
  s.Bind(5, j.options_json).Bind(6, j.requested_by).Bind(7, j.created_utime).Run();
  return db_.Changes() > 0;
}

std::optional<JobRecord> Catalog::Job(int64_t request_id) {
  const std::string sql = std::string("SELECT ") + kJobColumns + " FROM jobs WHERE request_id = ?1";
  SqliteStatement s(db_, sql.c_str());
  s.Bind(1, request_id);
  if (!s.Step()) return std::nullopt;
  return ReadJob(s);
}

std::vector<JobRecord> Catalog::Jobs(const std::string& state) {
  const std::string sql = std::string("SELECT ") + kJobColumns +
                          " FROM jobs WHERE ?1 = '' OR state = ?1 ORDER BY created_utime";
  SqliteStatement s(db_, sql.c_str());
  s.Bind(1, state);
  std::vector<JobRecord> out;
  while (s.Step()) out.push_back(ReadJob(s));
  return out;
}

ClaimOutcome Catalog::Claim(int64_t request_id, const std::string& worker_id, int64_t now,
                            int64_t lease_us, JobRecord* job) {
  SqliteTransaction tx(db_);
  auto current = Job(request_id);
  if (!current) return ClaimOutcome::kUnknown;
  if (current->state == "done" || current->state == "failed") {
    if (job) *job = *current;
    return ClaimOutcome::kDone;
  }
  const bool free = current->state == "pending" || current->lease_expires_utime < now;
  const bool renewal = current->state == "leased" && current->worker_id == worker_id &&
                       current->lease_expires_utime >= now;
  if (!free && !renewal) {
    if (job) *job = *current;
    return ClaimOutcome::kDenied;
  }
  SqliteStatement s(db_,
                    "UPDATE jobs SET state = 'leased', worker_id = ?2, lease_expires_utime = ?3, "
                    "attempts = attempts + ?4 WHERE request_id = ?1");
  s.Bind(1, request_id).Bind(2, worker_id).Bind(3, now + lease_us).Bind(4, renewal ? 0 : 1).Run();
  tx.Commit();
  if (job) *job = *Job(request_id);
  return ClaimOutcome::kGranted;
}

std::vector<JobRecord> Catalog::JobsToOffer(int64_t now) {
  const std::string sql = std::string("SELECT ") + kJobColumns +
                          " FROM jobs WHERE state = 'pending' OR (state = 'leased' AND "
                          "lease_expires_utime < ?1) ORDER BY created_utime";
  SqliteStatement s(db_, sql.c_str());
  s.Bind(1, now);
  std::vector<JobRecord> out;
  while (s.Step()) out.push_back(ReadJob(s));
  return out;
}

void Catalog::FailJob(int64_t request_id, const std::string& worker_id, const std::string& message,
                      int64_t utime) {
  SqliteStatement s(db_,
                    "UPDATE jobs SET state = 'failed', worker_id = ?2, message = ?3, "
                    "finished_utime = ?4 WHERE request_id = ?1 AND state <> 'done' AND "
                    "state <> 'failed'");
  s.Bind(1, request_id).Bind(2, worker_id).Bind(3, message).Bind(4, utime).Run();
}

std::pair<int64_t, bool> Catalog::StoreModel(const ModelRecord& m,
                                             const std::vector<Metric>& metrics) {
  SqliteTransaction tx(db_);
  {
    SqliteStatement find(db_, "SELECT model_id FROM models WHERE request_id = ?1");
    find.Bind(1, m.request_id);
    if (find.Step()) return {find.Int(0), false};  // rolled back: nothing written
  }
  TouchRig(m.rig_id, m.created_utime);
  SqliteStatement insert(
      db_,
      "INSERT INTO models(request_id, rig_id, experiment_id, method, options_json, data_hash, "
      "n_samples, sample_time_s, software_version, worker_id, created_utime, compute_s, "
      "fit_percent, status, model_json, report_json) "
      "VALUES(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16)");
  insert.Bind(1, m.request_id).Bind(2, m.rig_id).Bind(3, m.experiment_id).Bind(4, m.method);
  insert.Bind(5, m.options_json).Bind(6, m.data_hash).Bind(7, m.n_samples);
  insert.Bind(8, m.sample_time_s).Bind(9, m.software_version).Bind(10, m.worker_id);
  insert.Bind(11, m.created_utime).Bind(12, m.compute_s);
  if (std::isfinite(m.fit_percent))
    insert.Bind(13, m.fit_percent);
  else
    insert.BindNull(13);
  insert.Bind(14, m.status).Bind(15, m.model_json).Bind(16, m.report_json).Run();
  const int64_t model_id = db_.LastInsertRowId();
  SqliteStatement metric(db_,
                         "INSERT OR REPLACE INTO metrics(model_id, name, value, unit) "
                         "VALUES(?1, ?2, ?3, ?4)");
  for (const auto& x : metrics) {
    if (!std::isfinite(x.value)) continue;
    metric.Bind(1, model_id).Bind(2, x.name).Bind(3, x.value).Bind(4, x.unit).Run();
  }
  SqliteStatement job(db_,
                      "UPDATE jobs SET state = 'done', worker_id = ?2, finished_utime = ?3 "
                      "WHERE request_id = ?1");
  job.Bind(1, m.request_id).Bind(2, m.worker_id).Bind(3, m.created_utime).Run();
  tx.Commit();
  return {model_id, true};
}

namespace {
const char* kModelSelect =
    "SELECT m.model_id, m.request_id, m.rig_id, m.experiment_id, m.method, m.options_json, "
    "m.data_hash, m.software_version, m.worker_id, m.n_samples, m.sample_time_s, "
    "m.created_utime, m.compute_s, m.fit_percent, m.status, m.model_json, m.report_json, "
    "coalesce(e.signal_spec, '') FROM models m LEFT JOIN experiments e "
    "ON e.rig_id = m.rig_id AND e.experiment_id = m.experiment_id ";
ModelRecord ReadModel(const SqliteStatement& s) {
  ModelRecord m;
  SqliteRow(s) >> m.model_id >> m.request_id >> m.rig_id >> m.experiment_id >> m.method >>
      m.options_json >> m.data_hash >> m.software_version >> m.worker_id >> m.n_samples >>
      m.sample_time_s >> m.created_utime >> m.compute_s >> m.fit_percent >> m.status >>
      m.model_json >> m.report_json >> m.signal_spec;  // fit_percent: NULL reads as NaN
  return m;
}
}  // namespace

std::vector<ModelRecord> Catalog::Models(const std::string& rig_id, const std::string& method,
                                         int limit) {
  const std::string sql = std::string(kModelSelect) +
                          "WHERE (?1 = '' OR m.rig_id = ?1) AND (?2 = '' OR m.method = ?2) "
                          "ORDER BY m.created_utime, m.model_id LIMIT ?3";
  SqliteStatement s(db_, sql.c_str());
  s.Bind(1, rig_id).Bind(2, method).Bind(3, limit);
  std::vector<ModelRecord> out;
  while (s.Step()) out.push_back(ReadModel(s));
  return out;
}

std::optional<ModelRecord> Catalog::Model(int64_t model_id) {
  const std::string sql = std::string(kModelSelect) + "WHERE m.model_id = ?1";
  SqliteStatement s(db_, sql.c_str());
  s.Bind(1, model_id);
  if (!s.Step()) return std::nullopt;
  return ReadModel(s);
}

std::optional<ModelRecord> Catalog::ModelForRequest(int64_t request_id) {
  const std::string sql = std::string(kModelSelect) + "WHERE m.request_id = ?1";
  SqliteStatement s(db_, sql.c_str());
  s.Bind(1, request_id);
  if (!s.Step()) return std::nullopt;
  return ReadModel(s);
}

std::vector<Metric> Catalog::Metrics(int64_t model_id) {
  SqliteStatement s(db_, "SELECT name, value, unit FROM metrics WHERE model_id = ?1 ORDER BY name");
  s.Bind(1, model_id);
  std::vector<Metric> out;
  while (s.Step()) out.push_back({s.Text(0), s.Double(1), s.Text(2)});
  return out;
}

std::vector<std::pair<ModelRecord, double>> Catalog::History(const std::string& rig_id,
                                                             const std::string& metric,
                                                             const std::string& method) {
  const std::string sql = std::string(kModelSelect) +
                          "JOIN metrics x ON x.model_id = m.model_id AND x.name = ?2 "
                          "WHERE m.rig_id = ?1 AND (?3 = '' OR m.method = ?3) "
                          "ORDER BY m.created_utime, m.model_id";
  // The metric value is read with a second prepared statement per row (kept simple).
  SqliteStatement s(db_, sql.c_str());
  s.Bind(1, rig_id).Bind(2, metric).Bind(3, method);
  std::vector<std::pair<ModelRecord, double>> out;
  SqliteStatement value(db_, "SELECT value FROM metrics WHERE model_id = ?1 AND name = ?2");
  while (s.Step()) {
    ModelRecord m = ReadModel(s);
    value.Bind(1, m.model_id).Bind(2, metric);
    double v = std::nan("");
    if (value.Step()) v = value.Double(0);
    value.Reset();
    out.emplace_back(std::move(m), v);
  }
  return out;
}

std::pair<int64_t, bool> Catalog::StoreDiagnosis(int64_t request_id, const std::string& rig_id,
                                                 int64_t model_id, int64_t experiment_id,
                                                 const std::string& report_json, int64_t utime) {
  SqliteTransaction tx(db_);
  SqliteStatement find(db_, "SELECT report_id FROM diagnosis_reports WHERE request_id = ?1");
  find.Bind(1, request_id);
  if (find.Step()) return {find.Int(0), false};
  SqliteStatement s(db_,
                    "INSERT INTO diagnosis_reports(request_id, rig_id, model_id, experiment_id, "
                    "created_utime, report_json) VALUES(?1, ?2, ?3, ?4, ?5, ?6)");
  s.Bind(1, request_id).Bind(2, rig_id);
  if (model_id > 0)
    s.Bind(3, model_id);
  else
    s.BindNull(3);
  s.Bind(4, experiment_id).Bind(5, utime).Bind(6, report_json).Run();
  const int64_t id = db_.LastInsertRowId();
  tx.Commit();
  return {id, true};
}

namespace {
constexpr const char* kDiagnosisSelect =
    "SELECT report_id, request_id, rig_id, coalesce(model_id, 0), experiment_id, created_utime, "
    "report_json FROM diagnosis_reports ";
DiagnosisRecord ReadDiagnosis(const SqliteStatement& s) {
  DiagnosisRecord d;
  SqliteRow(s) >> d.report_id >> d.request_id >> d.rig_id >> d.model_id >> d.experiment_id >>
      d.created_utime >> d.report_json;
  return d;
}
}  // namespace

std::optional<DiagnosisRecord> Catalog::Diagnosis(int64_t report_id) {
  const std::string sql = std::string(kDiagnosisSelect) + "WHERE report_id = ?1";
  SqliteStatement s(db_, sql.c_str());
  s.Bind(1, report_id);
  if (!s.Step()) return std::nullopt;
  return ReadDiagnosis(s);
}

std::vector<DiagnosisRecord> Catalog::Diagnoses(const std::string& rig_id, int limit) {
  const std::string sql = std::string(kDiagnosisSelect) +
                          "WHERE (?1 = '' OR rig_id = ?1) ORDER BY report_id DESC LIMIT ?2";
  SqliteStatement s(db_, sql.c_str());
  s.Bind(1, rig_id).Bind(2, static_cast<int64_t>(limit));
  std::vector<DiagnosisRecord> out;
  while (s.Step()) out.push_back(ReadDiagnosis(s));
  return out;
}

int64_t Catalog::CountModels() {
  SqliteStatement s(db_, "SELECT count(*) FROM models");
  s.Step();
  return s.Int(0);
}

std::string Catalog::IntegrityCheck() {
  SqliteStatement s(db_, "PRAGMA integrity_check");
  return s.Step() ? s.Text(0) : "no answer";
}

std::vector<Metric> ModelMetrics(const nlohmann::json& report) {
  std::vector<Metric> out;
  try {
    if (report.contains("fit_percent") && report["fit_percent"].is_number())
      out.push_back({"fit_percent", report["fit_percent"].get<double>(), "%"});
    if (report.contains("record_fit_percent") && report["record_fit_percent"].is_number())
      out.push_back({"record_fit_percent", report["record_fit_percent"].get<double>(), "%"});
    if (!report.contains("model")) return out;
    const LtiModel model = ModelFromJson(report["model"]);
    const StateSpace ss = ToStateSpace(model);
    out.push_back({"order", static_cast<double>(ss.Order()), ""});
    const Eigen::MatrixXd gain = DcGain(ss);
    if (gain.size() > 0) out.push_back({"dc_gain", gain(0, 0), "output/input"});
    Eigen::VectorXcd poles = Poles(ss);
    std::vector<std::complex<double>> s_poles;
    for (int i = 0; i < poles.size(); ++i) {
      std::complex<double> p = poles(i);
      if (ss.IsDiscrete()) p = std::log(p) / ss.sample_time;  // s = ln(z)/Ts
      s_poles.push_back(p);
    }
    std::sort(s_poles.begin(), s_poles.end(), [](auto a, auto b) {
      if (std::abs(a) != std::abs(b)) return std::abs(a) < std::abs(b);
      return a.imag() < b.imag();
    });
    for (size_t k = 0; k < s_poles.size(); ++k) {
      const std::string n = std::to_string(k + 1);
      const double wn = std::abs(s_poles[k]);
      out.push_back({"pole_" + n + "_re", s_poles[k].real(), "rad/s"});
      out.push_back({"pole_" + n + "_im", s_poles[k].imag(), "rad/s"});
      out.push_back({"wn_" + n, wn, "rad/s"});
      out.push_back({"zeta_" + n, wn > 0 ? -s_poles[k].real() / wn : 1.0, ""});
    }
  } catch (...) {
    // A model we cannot read gives no pole metrics; the model itself is still stored.
  }
  return out;
}

}  // namespace idrig
