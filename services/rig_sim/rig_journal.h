#pragma once
// The rig's memory across restarts, in its state directory: for each experiment the encoded
// measurement blocks it published (exp-<id>.blocks, appended one length-prefixed block at a
// time, so a kill -9 loses at most the block being written) and, once it ended, exp-<id>.end
// holding the final message. An experiment with blocks but no .end was interrupted: the
// restarted rig says so (STATE_INTERRUPTED) instead of adopting it and inventing samples, and can
// still re-send the blocks it did publish. dir "" disables the journal.
#include <cstdint>
#include <string>
#include <vector>

namespace idrig {

class RigJournal {
 public:
  struct Experiment {
    int64_t experiment_id = 0;
    std::vector<std::vector<uint8_t>> blocks;  // encoded measurement_block_t, seq order
    bool ended = false;
  };
  explicit RigJournal(std::string dir);
  ~RigJournal();
  RigJournal(const RigJournal&) = delete;
  RigJournal& operator=(const RigJournal&) = delete;
  bool enabled() const { return !dir_.empty(); }
  void Begin(int64_t experiment_id);
  void Append(int64_t experiment_id, const std::vector<uint8_t>& block);
  void End(int64_t experiment_id, const std::string& message);
  // Every experiment in the directory, oldest first (a torn last block is dropped).
  std::vector<Experiment> Load() const;
  // Deletes the files of all but the newest `keep` experiments.
  void Prune(int keep) const;

 private:
  std::string Path(int64_t experiment_id, const char* suffix) const;
  std::string dir_;
  int fd_ = -1;
  int64_t open_id_ = 0;
};

}  // namespace idrig
