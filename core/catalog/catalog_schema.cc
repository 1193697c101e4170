// The catalogue's schema: the migrations (PRAGMA user_version) and opening a catalogue
// (WAL, synchronous=FULL, foreign keys). The queries are in catalog.cc; docs/services.md.
#include <stdexcept>

#include "core/catalog/catalog.h"

namespace idrig {

const std::vector<std::string>& Catalog::Migrations() {
  static const std::vector<std::string> migrations = {
      // 1: the catalogue.
      R"sql(
CREATE TABLE rigs(
  rig_id TEXT PRIMARY KEY,
  first_seen_utime INTEGER NOT NULL,
  last_seen_utime INTEGER NOT NULL);
CREATE TABLE experiments(
  rig_id TEXT NOT NULL REFERENCES rigs(rig_id),
  experiment_id INTEGER NOT NULL,
  signal_spec TEXT NOT NULL DEFAULT '',
  sample_rate_hz REAL NOT NULL DEFAULT 0,
  samples_total INTEGER NOT NULL DEFAULT 0,
  blocks_total INTEGER NOT NULL DEFAULT 0,
  state TEXT NOT NULL DEFAULT 'running',
  start_utime INTEGER NOT NULL DEFAULT 0,
  end_utime INTEGER NOT NULL DEFAULT 0,
  PRIMARY KEY(rig_id, experiment_id));
CREATE TABLE jobs(
  request_id INTEGER PRIMARY KEY,
  rig_id TEXT NOT NULL,
  experiment_id INTEGER NOT NULL,
  method TEXT NOT NULL,
  options_json TEXT NOT NULL DEFAULT '{}',
  requested_by TEXT NOT NULL DEFAULT '',
  state TEXT NOT NULL DEFAULT 'pending',
  worker_id TEXT NOT NULL DEFAULT '',
  lease_expires_utime INTEGER NOT NULL DEFAULT 0,
  attempts INTEGER NOT NULL DEFAULT 0,
  created_utime INTEGER NOT NULL,
  finished_utime INTEGER NOT NULL DEFAULT 0,
  message TEXT NOT NULL DEFAULT '');
CREATE TABLE models(
  model_id INTEGER PRIMARY KEY,
  request_id INTEGER NOT NULL UNIQUE,
  rig_id TEXT NOT NULL,
  experiment_id INTEGER NOT NULL,
  method TEXT NOT NULL,
  options_json TEXT NOT NULL,
  data_hash TEXT NOT NULL,
  n_samples INTEGER NOT NULL,
  sample_time_s REAL NOT NULL,
  software_version TEXT NOT NULL,
  worker_id TEXT NOT NULL,
  created_utime INTEGER NOT NULL,
  compute_s REAL NOT NULL DEFAULT 0,
  fit_percent REAL,
  status TEXT NOT NULL DEFAULT '',
  model_json TEXT NOT NULL,
  report_json TEXT NOT NULL);
CREATE INDEX models_by_rig_time ON models(rig_id, created_utime);
CREATE TABLE metrics(
  model_id INTEGER NOT NULL REFERENCES models(model_id),
  name TEXT NOT NULL,
  value REAL NOT NULL,
  unit TEXT NOT NULL DEFAULT '',
  PRIMARY KEY(model_id, name));
CREATE TABLE diagnosis_reports(
  report_id INTEGER PRIMARY KEY,
  request_id INTEGER NOT NULL UNIQUE,
  rig_id TEXT NOT NULL,
  model_id INTEGER REFERENCES models(model_id),
  experiment_id INTEGER NOT NULL DEFAULT 0,
  created_utime INTEGER NOT NULL,
  report_json TEXT NOT NULL);
)sql",
      // 2: offering jobs scans by state.
      "CREATE INDEX jobs_by_state ON jobs(state, lease_expires_utime);",
      // 3: why an experiment ended as it did (an interrupted one names its missing samples),
      // and how many samples were planned (excite's samples_total).
      "ALTER TABLE experiments ADD COLUMN message TEXT NOT NULL DEFAULT '';"
      "ALTER TABLE experiments ADD COLUMN samples_planned INTEGER NOT NULL DEFAULT 0;",
  };
  return migrations;
}

Catalog::Catalog(const std::string& path, bool read_only) : db_(path, read_only) {
  if (read_only) {
    if (db_.UserVersion() < 1)
      throw std::runtime_error("'" + path + "' is not an idrig catalogue (no schema)");
    return;
  }
  db_.Exec("PRAGMA journal_mode=WAL");
  db_.Exec("PRAGMA synchronous=FULL");
  db_.Exec("PRAGMA foreign_keys=ON");
  db_.Migrate(Migrations());
}

}  // namespace idrig
