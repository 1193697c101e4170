#pragma once
// idrig-logger: records actuator commands and measurement blocks of every rig, per experiment,
// into the SQLite experiment store (core/catalog/experiment_store.h); knows exactly which
// blocks it lost (gaps in seq, and blocks missing before the rig's final blocks_total); replays
// a stored experiment on request (replay_request_t -> REPLAY blocks + replay_done_t).
// As lcm-logger does, the LCM thread only copies messages into a bounded queue; a writer
// thread stores them in batched transactions. A full queue drops (and counts) the message.
#include <atomic>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "core/catalog/experiment_store.h"
#include "core/transport/status.h"
#include "core/transport/transport.h"

namespace idrig {

// The index fields of an encoded measurement_block_t, read without decoding the samples.
struct MeasurementHeader {
  std::string rig_id;
  int64_t utime = 0, experiment_id = 0, seq = 0, first_sample = 0;
  int32_t n_samples = 0;
};
// false for another type or a truncated message.
bool PeekMeasurementHeader(const uint8_t* data, size_t size, MeasurementHeader* header);

struct LoggerConfig {
  std::string db_path = "idrig-experiments.db";
  size_t queue_capacity = 200000;   // messages waiting for the writer
  int lcm_queue_capacity = 100000;  // LCM per-subscription queue
  int replay_pause_every = 200;     // blocks; pause 2 ms to let receivers drain
  double recover_period_s = 0.5;    // ask the rig again for lost blocks this often
  double recover_window_s = 60.0;   // ... for experiments ended less than this ago
  std::string lcmlog_path;          // also write every recorded message to this .lcmlog ("" = off)
  // false: no writer thread; Poll() and Flush() store what is queued on the caller's thread,
  // and Poll() then runs the loss recovery when due (tests and the fuzz target, whose runs must
  // repeat). Not read from the config file.
  bool writer_thread = true;
  static LoggerConfig FromJson(const nlohmann::json& config);
};

class LoggerService {
 public:
  LoggerService(Transport& transport, LoggerConfig config);
  ~LoggerService();
  void Poll(int timeout_ms);
  // Waits until the writer has stored everything queued so far (tests, benchmarks); without a
  // writer thread, stores it here.
  void Flush();
  int64_t stored_blocks() const { return stored_blocks_; }
  nlohmann::json Details();

 private:
  enum class Kind { kMeasurement, kCommand, kStatus, kReplayRequest };
  struct Item {
    Kind kind;
    int64_t recv_utime;
    std::string channel;
    std::vector<uint8_t> bytes;
  };
  struct Writer;  // the writer's store and .lcmlog (logger_service.cc)
  void Enqueue(Kind kind, const std::string& channel, const uint8_t* data, size_t size);
  std::unique_ptr<Writer> OpenWriter();
  void WriteBatch(Writer& writer, const std::deque<Item>& batch);
  void MaybeRecover(Writer& writer);
  void WriteQueued();  // without a writer thread: stores everything queued, on this thread
  void WriterLoop();
  void Store(ExperimentStore& store, const Item& item);
  void Replay(ExperimentStore& store, const Item& item);
  void UpdateSummary(ExperimentStore& store);
  void RecoverLosses(ExperimentStore& store);

  Transport& transport_;
  LoggerConfig config_;
  StatusReporter reporter_;
  std::mutex mutex_;
  std::condition_variable wake_, drained_;
  std::deque<Item> queue_;
  bool stop_ = false;
  size_t in_flight_ = 0;
  std::atomic<int64_t> stored_blocks_{0}, stored_commands_{0}, duplicates_{0}, replays_{0};
  std::atomic<int64_t> wrong_rig_{0};  // ignored: the message's rig is not its channel's
  std::atomic<size_t> peak_queue_{0};
  std::atomic<int64_t> recovery_requests_{0};
  std::mutex summary_mutex_;
  nlohmann::json summary_ = nlohmann::json::array();
  std::unique_ptr<Writer> inline_writer_;  // writer_thread false
  std::thread writer_;
};

}  // namespace idrig
