#pragma once
// The logger's experiment store (a separate SQLite file from the catalogue, same rules: WAL,
// migrations, prepared statements only). Raw LCM encodings are stored as BLOBs per block, so a
// replay re-publishes exactly what the rig sent; the columns beside them index the blocks.
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "core/catalog/sqlite.h"

namespace idrig {

struct StoredBlock {
  int64_t seq = 0, first_sample = 0, n_samples = 0, utime = 0, recv_utime = 0;
  std::vector<uint8_t> data;  // LCM encoding of the measurement_block_t / actuator_command_t
};

struct StoredExperiment {
  std::string rig_id;
  int64_t experiment_id = 0;
  std::string signal_spec;
  double sample_rate_hz = 0.0;
  bool ended = false;
  int64_t blocks_total = 0, samples_total = 0;
  int64_t blocks_stored = 0, commands_stored = 0;
  int64_t updated_utime = 0;
};

class ExperimentStore {
 public:
  // read_only: opens an existing store without writing to it (the dashboard, experiment export).
  explicit ExperimentStore(const std::string& path, bool read_only = false);
  static const std::vector<std::string>& Migrations();

  void Begin();  // batch writes in one transaction (as rosbag2 does)
  void Commit();
  // INSERT OR IGNORE: a duplicate (rig, experiment, seq) is kept once. Returns true if new.
  bool AddBlock(const std::string& rig_id, int64_t experiment_id, const StoredBlock& block);
  bool AddCommand(const std::string& rig_id, int64_t experiment_id, const StoredBlock& command);
  // Records what the rig reported (end, totals) or the excitation (spec, fs).
  void UpdateExperiment(const StoredExperiment& experiment);

  std::vector<StoredExperiment> Experiments();
  bool FindExperiment(const std::string& rig_id, int64_t experiment_id, StoredExperiment* out);
  std::vector<StoredBlock> Blocks(const std::string& rig_id, int64_t experiment_id,
                                  const std::set<int64_t>& skip = {});
  std::set<int64_t> BlockSeqs(const std::string& rig_id, int64_t experiment_id);
  // Block seqs in [0, blocks_total) not stored (blocks_total from the rig's final status, or
  // max seq + 1 while the experiment runs), the first max_listed of them: both totals come from
  // unsigned messages, and a status claiming 2^62 blocks made the logger list them all
  // (tests/fuzz/fuzz_worker_logger: out of memory).
  std::vector<int64_t> MissingBlocks(const std::string& rig_id, int64_t experiment_id,
                                     size_t max_listed = 4000);
  // How many there are (all of them, counted without listing).
  int64_t MissingCount(const std::string& rig_id, int64_t experiment_id);
  // Sample ranges [first, last] in [0, samples_total) that no stored actuator command covers
  // (commands the logger did not hear: it names them instead of calling the record complete).
  std::vector<std::pair<int64_t, int64_t>> SamplesWithoutCommand(const std::string& rig_id,
                                                                 int64_t experiment_id,
                                                                 int64_t samples_total);

 private:
  SqliteDatabase db_;
  SqliteStatement insert_block_, insert_command_;
};

}  // namespace idrig
