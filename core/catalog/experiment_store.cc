#include "core/catalog/experiment_store.h"

#include <iterator>
#include <stdexcept>

namespace idrig {

const std::vector<std::string>& ExperimentStore::Migrations() {
  static const std::vector<std::string> migrations = {R"sql(
CREATE TABLE experiments(
  rig_id TEXT NOT NULL,
  experiment_id INTEGER NOT NULL,
  signal_spec TEXT NOT NULL DEFAULT '',
  sample_rate_hz REAL NOT NULL DEFAULT 0,
  ended INTEGER NOT NULL DEFAULT 0,
  blocks_total INTEGER NOT NULL DEFAULT 0,
  samples_total INTEGER NOT NULL DEFAULT 0,
  updated_utime INTEGER NOT NULL DEFAULT 0,
  PRIMARY KEY(rig_id, experiment_id));
CREATE TABLE blocks(
  rig_id TEXT NOT NULL,
  experiment_id INTEGER NOT NULL,
  seq INTEGER NOT NULL,
  first_sample INTEGER NOT NULL,
  n_samples INTEGER NOT NULL,
  utime INTEGER NOT NULL,
  recv_utime INTEGER NOT NULL,
  data BLOB NOT NULL,
  PRIMARY KEY(rig_id, experiment_id, seq)) WITHOUT ROWID;
CREATE TABLE commands(
  rig_id TEXT NOT NULL,
  experiment_id INTEGER NOT NULL,
  seq INTEGER NOT NULL,
  first_sample INTEGER NOT NULL,
  n_samples INTEGER NOT NULL,
  utime INTEGER NOT NULL,
  recv_utime INTEGER NOT NULL,
  data BLOB NOT NULL,
  PRIMARY KEY(rig_id, experiment_id, seq)) WITHOUT ROWID;
)sql"};
  return migrations;
}

namespace {
SqliteDatabase& Prepared(SqliteDatabase& db) {
  db.Exec("PRAGMA journal_mode=WAL");
  db.Exec("PRAGMA synchronous=NORMAL");
  db.Migrate(ExperimentStore::Migrations());
  return db;
}
// A read-only store is used as it is (no pragma, no migration): it must have the schema.
SqliteDatabase& Checked(SqliteDatabase& db) {
  if (db.UserVersion() < 1)
    throw std::runtime_error("'" + db.path() + "' is not an idrig experiment store (no schema)");
  return db;
}
}  // namespace

ExperimentStore::ExperimentStore(const std::string& path, bool read_only)
    : db_(path, read_only),
      insert_block_(read_only ? Checked(db_) : Prepared(db_),
                    "INSERT OR IGNORE INTO blocks(rig_id, experiment_id, seq, first_sample, "
                    "n_samples, utime, recv_utime, data) VALUES(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)"),
      insert_command_(
          db_,
          "INSERT OR IGNORE INTO commands(rig_id, experiment_id, seq, first_sample, "
          "n_samples, utime, recv_utime, data) VALUES(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)") {}

void ExperimentStore::Begin() { db_.Exec("BEGIN"); }
void ExperimentStore::Commit() { db_.Exec("COMMIT"); }

namespace {
bool Insert(SqliteDatabase& db, SqliteStatement& s, const std::string& rig_id,
            int64_t experiment_id, const StoredBlock& b) {
  s.Bind(1, rig_id).Bind(2, experiment_id).Bind(3, b.seq).Bind(4, b.first_sample);
  s.Bind(5, b.n_samples).Bind(6, b.utime).Bind(7, b.recv_utime);
  s.BindBlob(8, b.data.data(), b.data.size());
  s.Run();
  return db.Changes() > 0;
}
}  // namespace

bool ExperimentStore::AddBlock(const std::string& rig_id, int64_t experiment_id,
                               const StoredBlock& block) {
  return Insert(db_, insert_block_, rig_id, experiment_id, block);
}

bool ExperimentStore::AddCommand(const std::string& rig_id, int64_t experiment_id,
                                 const StoredBlock& command) {
  return Insert(db_, insert_command_, rig_id, experiment_id, command);
}

void ExperimentStore::UpdateExperiment(const StoredExperiment& e) {
  SqliteStatement s(db_,
                    "INSERT INTO experiments(rig_id, experiment_id, signal_spec, sample_rate_hz, "
                    "ended, blocks_total, samples_total, updated_utime) "
                    "VALUES(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8) "
                    "ON CONFLICT(rig_id, experiment_id) DO UPDATE SET "
                    "signal_spec = CASE WHEN excluded.signal_spec <> '' THEN excluded.signal_spec "
                    "ELSE signal_spec END, "
                    "sample_rate_hz = CASE WHEN excluded.sample_rate_hz > 0 THEN "
                    "excluded.sample_rate_hz ELSE sample_rate_hz END, "
                    "ended = max(ended, excluded.ended), "
                    "blocks_total = max(blocks_total, excluded.blocks_total), "
                    "samples_total = max(samples_total, excluded.samples_total), "
                    "updated_utime = excluded.updated_utime");
  s.Bind(1, e.rig_id).Bind(2, e.experiment_id).Bind(3, e.signal_spec).Bind(4, e.sample_rate_hz);
  s.Bind(5, e.ended ? 1 : 0).Bind(6, e.blocks_total).Bind(7, e.samples_total);
  s.Bind(8, e.updated_utime).Run();
}

namespace {
const char* kExperimentSelect =
    "SELECT e.rig_id, e.experiment_id, e.signal_spec, e.sample_rate_hz, e.ended, "
    "e.blocks_total, e.samples_total, e.updated_utime, "
    "(SELECT count(*) FROM blocks b WHERE b.rig_id = e.rig_id AND b.experiment_id = "
    "e.experiment_id), "
    "(SELECT count(*) FROM commands c WHERE c.rig_id = e.rig_id AND c.experiment_id = "
    "e.experiment_id) "
    "FROM experiments e ";
StoredExperiment ReadExperiment(const SqliteStatement& s) {
  StoredExperiment e;
  SqliteRow(s) >> e.rig_id >> e.experiment_id >> e.signal_spec >> e.sample_rate_hz >> e.ended >>
      e.blocks_total >> e.samples_total >> e.updated_utime >> e.blocks_stored >> e.commands_stored;
  return e;
}
}  // namespace

std::vector<StoredExperiment> ExperimentStore::Experiments() {
  const std::string sql = std::string(kExperimentSelect) + "ORDER BY e.updated_utime";
  SqliteStatement s(db_, sql.c_str());
  std::vector<StoredExperiment> out;
  while (s.Step()) out.push_back(ReadExperiment(s));
  return out;
}

bool ExperimentStore::FindExperiment(const std::string& rig_id, int64_t experiment_id,
                                     StoredExperiment* out) {
  const std::string sql =
      std::string(kExperimentSelect) + "WHERE e.rig_id = ?1 AND e.experiment_id = ?2";
  SqliteStatement s(db_, sql.c_str());
  s.Bind(1, rig_id).Bind(2, experiment_id);
  if (!s.Step()) return false;
  *out = ReadExperiment(s);
  return true;
}

std::vector<StoredBlock> ExperimentStore::Blocks(const std::string& rig_id, int64_t experiment_id,
                                                 const std::set<int64_t>& skip) {
  SqliteStatement s(db_,
                    "SELECT seq, first_sample, n_samples, utime, recv_utime, data FROM blocks "
                    "WHERE rig_id = ?1 AND experiment_id = ?2 ORDER BY seq");
  s.Bind(1, rig_id).Bind(2, experiment_id);
  std::vector<StoredBlock> out;
  while (s.Step()) {
    if (skip.count(s.Int(0))) continue;
    StoredBlock b;
    SqliteRow(s) >> b.seq >> b.first_sample >> b.n_samples >> b.utime >> b.recv_utime >> b.data;
    out.push_back(std::move(b));
  }
  return out;
}

std::set<int64_t> ExperimentStore::BlockSeqs(const std::string& rig_id, int64_t experiment_id) {
  SqliteStatement s(db_, "SELECT seq FROM blocks WHERE rig_id = ?1 AND experiment_id = ?2");
  s.Bind(1, rig_id).Bind(2, experiment_id);
  std::set<int64_t> out;
  while (s.Step()) out.insert(s.Int(0));
  return out;
}

std::vector<std::pair<int64_t, int64_t>> ExperimentStore::SamplesWithoutCommand(
    const std::string& rig_id, int64_t experiment_id, int64_t samples_total) {
  SqliteStatement s(db_,
                    "SELECT first_sample, n_samples FROM commands WHERE rig_id = ?1 AND "
                    "experiment_id = ?2 AND n_samples > 0 ORDER BY first_sample");
  s.Bind(1, rig_id).Bind(2, experiment_id);
  std::vector<std::pair<int64_t, int64_t>> gaps;
  int64_t covered = 0;  // samples 0 .. covered-1 have a command
  while (s.Step()) {
    const int64_t first = s.Int(0), n = s.Int(1);
    if (first > covered) gaps.push_back({covered, std::min(first, samples_total) - 1});
    covered = std::max(covered, first + n);
  }
  if (covered < samples_total) gaps.push_back({covered, samples_total - 1});
  return gaps;
}

namespace {
int64_t BlocksExpected(ExperimentStore& store, const std::string& rig_id, int64_t experiment_id,
                       const std::set<int64_t>& have) {
  StoredExperiment e;
  if (store.FindExperiment(rig_id, experiment_id, &e) && e.ended) return e.blocks_total;
  return have.empty() || *have.rbegin() < 0 ? 0 : *have.rbegin() + 1;
}
}  // namespace

std::vector<int64_t> ExperimentStore::MissingBlocks(const std::string& rig_id,
                                                    int64_t experiment_id, size_t max_listed) {
  const std::set<int64_t> have = BlockSeqs(rig_id, experiment_id);
  const int64_t total = BlocksExpected(*this, rig_id, experiment_id, have);
  std::vector<int64_t> missing;
  // At most have.size() + max_listed steps, whatever the total claims.
  for (int64_t k = 0; k < total && missing.size() < max_listed; ++k)
    if (!have.count(k)) missing.push_back(k);
  return missing;
}

int64_t ExperimentStore::MissingCount(const std::string& rig_id, int64_t experiment_id) {
  const std::set<int64_t> have = BlockSeqs(rig_id, experiment_id);
  const int64_t total = BlocksExpected(*this, rig_id, experiment_id, have);
  if (total <= 0) return 0;
  const auto stored = std::distance(have.lower_bound(0), have.lower_bound(total));
  return total - static_cast<int64_t>(stored);
}

}  // namespace idrig
